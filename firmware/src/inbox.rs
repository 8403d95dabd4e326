//! The hand-off between the two contexts of a node, in both directions:
//! finished items from the CAN receive side to the control tick (already
//! decoded, reassembled and, for segments and configurations, validated),
//! and the [`TickSnapshot`] the tick publishes back. A leaf below both sides, so
//! neither depends on the other. The tick only files items, so a frame costs
//! it a short, bounded step.

use triquint_shared::protocol::{
    Command, CommandCode, DriveConfig, FaultCode, Heartbeat, PARAM_COUNT, Reject,
};
use triquint_shared::quintic::JointMotion;

use crate::scaling::{Retarget, TimeScaling, UNIT_Q16};
use crate::segment::Seg;
use crate::sync::SyncEstimator;

/// Items the tick takes per tick at most (`Drive::take_from`): the
/// bus delivers at most about one frame per 100 µs tick, so the queue never
/// builds up, and the tick's worst case stays bounded whatever arrives.
pub const TAKE_PER_TICK: usize = 2;

/// Slots of the queue between the receive context and the tick ([`Inbox`]).
pub const INBOX_SLOTS: usize = 8;

/// The lock-free single-producer (receive side), single-consumer (tick)
/// queue of a board; it holds `INBOX_SLOTS − 1` items, of which
/// [`RESERVED_SLOTS`] only for urgent items (see [`offer`]).
pub type Inbox = heapless::spsc::Queue<Item, INBOX_SLOTS>;

/// Slots of the inbox that only urgent items ([`Item::is_urgent`]) may
/// fill: a flood of segments cannot keep a Stop, an Emergency, a Home or a
/// ClearFault out. Segments dropped for want of room are resent by the
/// host's flow control; those three have no resend.
pub const RESERVED_SLOTS: usize = 3;

/// What the receive side needs to know of the node, published by the tick
/// (`Drive::snapshot`); a board shares it in a critical section.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TickSnapshot {
    /// CRC of the running configuration (0: none).
    pub config_crc: u32,
    /// Queue flushes so far: a flush also drops a partial segment.
    pub flushes: u32,
    /// No motion pending (Idle or Fault): the time sync may take a new host time base.
    pub may_rebase: bool,
    /// The time-scaling and the override a resume returns to: the receive
    /// side sizes a hold, resume, override or stop in the middle of a
    /// transition ahead of the tick ([`Retarget`]).
    pub scaling: TimeScaling,
    pub override_q16: u32,
    /// The stop ramps the tick runs transitions with, controlled and quick
    /// (ns; `Drive::ramps_ns`), while configured.
    pub ramps_ns: Option<(i64, i64)>,
}

impl TickSnapshot {
    /// A node just started: nothing configured, at σ = 1.
    pub const INITIAL: TickSnapshot = TickSnapshot {
        config_crc: 0,
        flushes: 0,
        may_rebase: true,
        scaling: TimeScaling::nominal(0, 0),
        override_q16: UNIT_Q16,
        ramps_ns: None,
    };
}

impl Default for TickSnapshot {
    fn default() -> Self {
        Self::INITIAL
    }
}

/// The producer end of the inbox, as [`offer`] needs it.
#[allow(
    clippy::result_large_err,
    reason = "the item goes back to the caller, as heapless's enqueue does (no allocation)"
)]
pub trait Sink {
    /// Items queued now.
    fn queued(&self) -> usize;
    /// Items the queue holds at most.
    fn slots(&self) -> usize;
    /// Queues `item`; gives it back when the queue is full.
    fn put(&mut self, item: Item) -> Result<(), Item>;
}

impl Sink for heapless::spsc::Producer<'_, Item> {
    fn queued(&self) -> usize {
        self.len()
    }
    fn slots(&self) -> usize {
        self.capacity()
    }
    fn put(&mut self, item: Item) -> Result<(), Item> {
        self.enqueue(item)
    }
}

impl<const N: usize> Sink for heapless::spsc::Queue<Item, N> {
    fn queued(&self) -> usize {
        self.len()
    }
    fn slots(&self) -> usize {
        self.capacity()
    }
    fn put(&mut self, item: Item) -> Result<(), Item> {
        self.enqueue(item)
    }
}

/// Queues an item for the tick, keeping [`RESERVED_SLOTS`] free for urgent
/// items: an ordinary item is refused (given back) when only the reserved
/// slots are left, an urgent one only when the queue is completely full
/// (then the caller waits for the tick and offers it again; a board's
/// receive task does, so urgent items are never dropped).
#[allow(clippy::result_large_err, reason = "as Sink::put")]
// Never inlined: the boards' ELF check (scripts/elf_check.py --calls) finds
// the receive task's hand-off through this symbol.
#[inline(never)]
pub fn offer(sink: &mut impl Sink, item: Item) -> Result<(), Item> {
    if !item.is_urgent() && sink.queued() + RESERVED_SLOTS >= sink.slots() {
        return Err(item);
    }
    sink.put(item)
}

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
    /// A compact continuation: the body CRC of the predecessor it was
    /// rebuilt on, which the node must hold as its last accepted segment.
    pub pred_crc: Option<u32>,
}

/// A configuration ready to run, its values checked. The tick builds the
/// robot model and derives the periods as it commits: carried here, they
/// would make every inbox slot larger.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Prepared {
    pub cfg: DriveConfig,
    /// The receive side's verdict for the ceiling lock.
    pub lock: LockCheck,
}

/// What the ceiling lock needs of a prepared commit (`ceiling_lock`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LockCheck {
    /// Replayed by the board from its own store, not sent by a host:
    /// not held to the ceiling lock.
    pub kept: bool,
    /// The first locked parameter it widens, judged against the
    /// configuration of CRC `against` (0: none).
    pub widens: Option<u8>,
    pub against: u32,
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
    /// FeedHold, Resume, Override, Stop or QuickStop in the middle of a
    /// transition: the new transition, sized by the receive side.
    Scaling(Retarget),
    /// FeedHold, Resume, Override, Stop or QuickStop otherwise: the host
    /// time (ns) it applies at (`SyncEstimator::apply_ns` at its receipt),
    /// its 64-bit arithmetic done here rather than in the tick.
    At(i64),
}

impl CommandData {
    /// The prepared time-scaling change, if any.
    pub fn retarget(&self) -> Option<&Retarget> {
        match self {
            CommandData::Scaling(r) => Some(r),
            _ => None,
        }
    }

    /// The host time (ns) a feed command applies at, as the receive side
    /// dated it; `None` if it did not.
    pub fn applies_at(&self) -> Option<i64> {
        match self {
            CommandData::Scaling(r) => Some(r.t_ns),
            CommandData::At(t) => Some(*t),
            _ => None,
        }
    }
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
        /// The sender (0: the host).
        node: u8,
        /// Host time (ns) the stop it causes begins at: the sender's
        /// instant where the receive side could date it, else the receipt.
        t_ns: i64,
        /// The ramp its sender runs (100 µs units, 0 = the full ramp).
        ramp_100us: u16,
        /// The stop it causes when Running in a transition, sized ahead.
        ready: Option<Retarget>,
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

impl Item {
    /// Stop, QuickStop, ClearFault, Home, FeedHold, Resume, Override and
    /// Emergency: what has no resend by the host's flow control and must
    /// reach the tick even behind a flood of segments.
    pub fn is_urgent(&self) -> bool {
        match self {
            Item::Emergency { .. } => true,
            Item::Command { command, .. } => matches!(
                command.command(),
                Ok(CommandCode::Stop
                    | CommandCode::QuickStop
                    | CommandCode::ClearFault
                    | CommandCode::Home
                    | CommandCode::FeedHold
                    | CommandCode::Resume
                    | CommandCode::Override)
            ),
            _ => false,
        }
    }
}
