//! What the CAN receive context hands to the control tick: finished items,
//! already decoded, reassembled and (segments, configurations) validated by
//! the [`crate::receiver::Receiver`]. The tick only files them
//! ([`crate::Drive::take`]), so a frame costs the tick a short, bounded step.

use triquint_shared::Model;
use triquint_shared::protocol::{Command, DriveConfig, FaultCode, Heartbeat, PARAM_COUNT, Reject};
use triquint_shared::quintic::JointMotion;

use crate::drive::Active;
use crate::segment::Seg;
use crate::sync::SyncEstimator;

/// Items the tick takes per tick at most ([`crate::Drive::take_from`]): the
/// bus delivers at most about one frame per 100 µs tick, so the queue never
/// builds up, and the tick's worst case stays bounded whatever arrives.
pub const TAKE_PER_TICK: usize = 2;

/// Slots of the queue between the receive context and the tick ([`Inbox`]).
pub const INBOX_SLOTS: usize = 8;

/// The lock-free single-producer (receive side), single-consumer (tick)
/// queue of a board; it holds `INBOX_SLOTS − 1` items.
pub type Inbox = heapless::spsc::Queue<Item, INBOX_SLOTS>;

/// Where the tick takes items from. Items are large (a prepared
/// configuration, a checked segment): the tick reads them in place and only
/// then frees the slot, so no copy of a whole item is made.
pub trait Source {
    fn front(&self) -> Option<&Item>;
    fn pop_front(&mut self);
}

/// The consumer end of the queue (a board: the tick owns it).
impl Source for heapless::spsc::Consumer<'_, Item> {
    fn front(&self) -> Option<&Item> {
        self.peek()
    }
    fn pop_front(&mut self) {
        let _ = self.dequeue();
    }
}

/// The whole queue (receive side and tick in one context: tests, the QEMU image).
impl<const N: usize> Source for heapless::spsc::Queue<Item, N> {
    fn front(&self) -> Option<&Item> {
        self.peek()
    }
    fn pop_front(&mut self) {
        let _ = self.dequeue();
    }
}

/// A segment, reassembled with a valid CRC and checked against a configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CheckedSegment {
    /// The segment with its plan start still 0: the node places it in time.
    pub seg: Seg,
    /// Motion at its start and end (for the C3 check against its neighbour).
    pub begin: JointMotion<f32>,
    pub end: JointMotion<f32>,
    /// Velocity, acceleration, jerk and soft limits: `Reject::Invalid` if broken.
    pub verdict: Result<(), Reject>,
    /// CRC of the configuration it was checked against (0: none).
    pub config_crc: u32,
}

/// A configuration ready to run: values checked, robot model built, periods derived.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prepared {
    pub cfg: DriveConfig,
    pub model: Model<f32>,
    pub active: Active,
}

/// What a command brings beyond its frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CommandData {
    None,
    /// ReadConfig: the written values to answer with.
    Values([f32; PARAM_COUNT]),
    /// ConfigCommit: the CRC of the written values and the prepared
    /// configuration, or why it cannot run.
    Commit {
        crc: u32,
        config: Result<Prepared, FaultCode>,
    },
}

/// One finished item for the tick. Local receive times in µs.
#[derive(Clone, Copy, Debug, PartialEq)]
#[allow(
    clippy::large_enum_variant,
    reason = "fixed-size queue slots, no allocation"
)]
pub enum Item {
    /// The time-sync estimate after a TimeSync frame (the receive side
    /// keeps the estimator and does its 64-bit arithmetic).
    Sync(SyncEstimator),
    Emergency {
        code: FaultCode,
        rx_us: u64,
    },
    PeerHeartbeat {
        node: u8,
        heartbeat: Heartbeat,
        rx_us: u64,
    },
    Command {
        command: Command,
        rx_us: u64,
        data: CommandData,
    },
    /// A duplicate or malformed part: counted, not answered.
    PartIgnored(Reject),
    /// A (partial) segment dropped: answered with a SegmentAck.
    PartRejected {
        seq: u16,
        reason: Reject,
    },
    Segment(CheckedSegment),
}
