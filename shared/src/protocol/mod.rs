//! The triquint CAN protocol: identifiers, messages, codec, segment transport.
//!
//! Everything is declared once: fixed-layout messages and code tables in
//! [`messages`], the segment body in [`segment`], configuration parameters in
//! [`config`]. The DBC file, the tables of `docs/protocol.md` and the golden
//! vectors are generated from these declarations by [`generate`] (tests fail when
//! the committed files are stale; `TRIQUINT_BLESS=1 cargo test -p
//! triquint-shared protocol` rewrites them).
//!
//! Bus: 1 Mbit/s classic CAN 2.0A (11-bit identifiers), or CAN-FD with
//! 1 Mbit/s arbitration and 5 Mbit/s data phase. Node ids 1–15; which axis
//! a node drives is its configuration (`axis`), by default node k drives
//! axis k; node 0 is the host or "all nodes".

pub mod compact;
pub mod config;
pub mod contract;
pub mod crc;
#[cfg(any(feature = "alloc", test))]
pub mod describe;
#[cfg(any(feature = "alloc", test))]
pub mod generate;
pub mod messages;
pub mod segment;
pub mod segment_maxima;
pub mod segment_rx;
pub mod stop_ramp;
pub mod streaming;
pub mod wire;

pub use compact::Compact;
pub use config::{DriveConfig, DriveSettings, PARAM_COUNT, PARAMS};
pub use crc::crc32;
pub use messages::*;
pub use segment::{PartEvent, Reassembler, WireSegment};
pub use segment_rx::{SegmentEvent, SegmentRx};
pub use wire::{Addr, MAX_NODE_ID, MessageDef};

/// Largest payload (CAN-FD).
pub const MAX_PAYLOAD: usize = 64;
/// The default node ids of the drives of axes 1–3 (any distinct ids
/// 1–15 may be configured).
pub const NODES: [u8; 3] = [1, 2, 3];
/// Consecutive outlying TimeSync samples after which an Idle (or faulted)
/// node takes a new host time base (docs/protocol.md, "Time base").
pub const SYNC_REBASE_AFTER: u32 = 3;
/// The syncs of a session after which every node's sync status is of its
/// time base: the first pairs with none, [`SYNC_REBASE_AFTER`] outliers
/// rebase, one more synchronises, and one more covers a heartbeat composed
/// before that one arrived.
pub const SYNCS_TO_FOLLOW: u32 = SYNC_REBASE_AFTER + 3;

/// One CAN frame with an 11-bit identifier.
#[derive(Clone, Copy, PartialEq, Eq)]
pub struct Frame {
    pub id: u16,
    pub len: u8,
    /// CAN-FD frame (with bit-rate switch).
    pub fd: bool,
    pub data: [u8; MAX_PAYLOAD],
}

impl core::fmt::Debug for Frame {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        write!(f, "{:03X}#", self.id)?;
        if self.fd {
            write!(f, "#")?;
        }
        for b in self.payload() {
            write!(f, "{b:02X}")?;
        }
        Ok(())
    }
}

impl Frame {
    pub fn new(id: u16, len: usize, fd: bool) -> Self {
        Self {
            id: id & 0x7FF,
            len: len.min(MAX_PAYLOAD) as u8,
            fd,
            data: [0; MAX_PAYLOAD],
        }
    }
    /// A frame with `payload` copied in (truncated to 64 bytes).
    pub fn with_payload(id: u16, payload: &[u8], fd: bool) -> Self {
        let mut f = Self::new(id, payload.len(), fd);
        let n = f.len as usize;
        f.data[..n].copy_from_slice(&payload[..n]);
        f
    }
    pub fn payload(&self) -> &[u8] {
        &self.data[..(self.len as usize).min(MAX_PAYLOAD)]
    }
}

/// Encodes a fixed-layout message for node `node` (0 = host/broadcast).
macro_rules! impl_to_frame {
    ($($t:ident),*) => {$(
        impl $t {
            pub fn to_frame(&self, node: u8) -> Frame {
                Frame::with_payload(Self::DEF.addr.id(node), &self.encode(), false)
            }
        }
    )*};
}
impl_to_frame!(
    Emergency,
    TimeSync,
    Command,
    SegmentAck,
    CommandAck,
    Heartbeat,
    HeartbeatExt,
    Telemetry,
    TelemetryExt
);

/// A decoded frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Msg {
    Emergency(Emergency),
    TimeSync(TimeSync),
    Command(Command),
    ConfigWrite { index: u8, value: f32 },
    SegmentPart,
    SegmentPartFd,
    SegmentCompact,
    SegmentCompactFd,
    SegmentAck(SegmentAck),
    CommandAck(CommandAck),
    ConfigValue { index: u8, value: f32 },
    Heartbeat(Heartbeat),
    HeartbeatExt(HeartbeatExt),
    Telemetry(Telemetry),
    TelemetryExt(TelemetryExt),
}

/// Why a frame could not be decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum DecodeError {
    #[error("identifier 0x{0:03X} is not part of the protocol")]
    UnknownId(u16),
    #[error("{name}: payload of {got} bytes, expected {want}")]
    Length {
        name: &'static str,
        got: usize,
        want: usize,
    },
}

/// Every message of the protocol, one variant each, in identifier order.
/// [`decode`] and [`all_messages`] are exhaustive matches over it, so a
/// message added here without its decoder does not compile; a fixed-layout
/// message declared in [`messages`] but missing here fails the test
/// `every_declared_message_has_a_kind`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MsgKind {
    Emergency,
    TimeSync,
    Command,
    ConfigWrite,
    SegmentPart,
    SegmentCompact,
    SegmentPartFd,
    SegmentCompactFd,
    SegmentAck,
    CommandAck,
    ConfigValue,
    Heartbeat,
    HeartbeatExt,
    Telemetry,
    TelemetryExt,
}

impl MsgKind {
    /// Every kind, in identifier order.
    pub const ALL: [MsgKind; 15] = [
        MsgKind::Emergency,
        MsgKind::TimeSync,
        MsgKind::Command,
        MsgKind::ConfigWrite,
        MsgKind::SegmentPart,
        MsgKind::SegmentCompact,
        MsgKind::SegmentPartFd,
        MsgKind::SegmentCompactFd,
        MsgKind::SegmentAck,
        MsgKind::CommandAck,
        MsgKind::ConfigValue,
        MsgKind::Heartbeat,
        MsgKind::HeartbeatExt,
        MsgKind::Telemetry,
        MsgKind::TelemetryExt,
    ];

    /// The declaration of this message.
    pub const fn def(self) -> &'static MessageDef {
        match self {
            MsgKind::Emergency => &Emergency::DEF,
            MsgKind::TimeSync => &TimeSync::DEF,
            MsgKind::Command => &Command::DEF,
            MsgKind::ConfigWrite => &config::CONFIG_WRITE,
            MsgKind::SegmentPart => &segment::SEGMENT_PART,
            MsgKind::SegmentPartFd => &segment::SEGMENT_PART_FD,
            MsgKind::SegmentCompact => &compact::SEGMENT_COMPACT,
            MsgKind::SegmentCompactFd => &compact::SEGMENT_COMPACT_FD,
            MsgKind::SegmentAck => &SegmentAck::DEF,
            MsgKind::CommandAck => &CommandAck::DEF,
            MsgKind::ConfigValue => &config::CONFIG_VALUE,
            MsgKind::Heartbeat => &Heartbeat::DEF,
            MsgKind::HeartbeatExt => &HeartbeatExt::DEF,
            MsgKind::Telemetry => &Telemetry::DEF,
            MsgKind::TelemetryExt => &TelemetryExt::DEF,
        }
    }

    /// Decodes a payload of this kind (at least `def().len` bytes).
    fn decode(self, p: &[u8]) -> Msg {
        let param = || config::decode_param(p).unwrap_or((0, 0.0));
        match self {
            MsgKind::Emergency => Msg::Emergency(Emergency::decode(p)),
            MsgKind::TimeSync => Msg::TimeSync(TimeSync::decode(p)),
            MsgKind::Command => Msg::Command(Command::decode(p)),
            MsgKind::ConfigWrite => {
                let (index, value) = param();
                Msg::ConfigWrite { index, value }
            }
            MsgKind::SegmentPart => Msg::SegmentPart,
            MsgKind::SegmentPartFd => Msg::SegmentPartFd,
            MsgKind::SegmentCompact => Msg::SegmentCompact,
            MsgKind::SegmentCompactFd => Msg::SegmentCompactFd,
            MsgKind::SegmentAck => Msg::SegmentAck(SegmentAck::decode(p)),
            MsgKind::CommandAck => Msg::CommandAck(CommandAck::decode(p)),
            MsgKind::ConfigValue => {
                let (index, value) = param();
                Msg::ConfigValue { index, value }
            }
            MsgKind::Heartbeat => Msg::Heartbeat(Heartbeat::decode(p)),
            MsgKind::HeartbeatExt => Msg::HeartbeatExt(HeartbeatExt::decode(p)),
            MsgKind::Telemetry => Msg::Telemetry(Telemetry::decode(p)),
            MsgKind::TelemetryExt => Msg::TelemetryExt(TelemetryExt::decode(p)),
        }
    }
}

impl Msg {
    /// Which message this is.
    pub const fn kind(&self) -> MsgKind {
        match self {
            Msg::Emergency(_) => MsgKind::Emergency,
            Msg::TimeSync(_) => MsgKind::TimeSync,
            Msg::Command(_) => MsgKind::Command,
            Msg::ConfigWrite { .. } => MsgKind::ConfigWrite,
            Msg::SegmentPart => MsgKind::SegmentPart,
            Msg::SegmentPartFd => MsgKind::SegmentPartFd,
            Msg::SegmentCompact => MsgKind::SegmentCompact,
            Msg::SegmentCompactFd => MsgKind::SegmentCompactFd,
            Msg::SegmentAck(_) => MsgKind::SegmentAck,
            Msg::CommandAck(_) => MsgKind::CommandAck,
            Msg::ConfigValue { .. } => MsgKind::ConfigValue,
            Msg::Heartbeat(_) => MsgKind::Heartbeat,
            Msg::HeartbeatExt(_) => MsgKind::HeartbeatExt,
            Msg::Telemetry(_) => MsgKind::Telemetry,
            Msg::TelemetryExt(_) => MsgKind::TelemetryExt,
        }
    }
}

/// Every message declaration, in identifier order (fixed and multiplexed).
pub fn all_messages() -> [&'static MessageDef; 15] {
    MsgKind::ALL.map(MsgKind::def)
}

/// Decodes a frame into the message and the node number in its identifier
/// (0 = host or broadcast). Segment parts are returned undecoded: feed their
/// payload to a [`SegmentRx`].
pub fn decode(frame: &Frame) -> Result<(Msg, u8), DecodeError> {
    for (kind, &(addr, len, name)) in MsgKind::ALL.into_iter().zip(ROUTES.iter()) {
        if let Some(node) = addr.matches(frame.id) {
            let p = frame.payload();
            if p.len() < len {
                return Err(DecodeError::Length {
                    name,
                    got: p.len(),
                    want: len,
                });
            }
            return Ok((kind.decode(p), node));
        }
    }
    Err(DecodeError::UnknownId(frame.id))
}

/// What [`decode`] reads of each declaration, in `MsgKind::ALL`'s order:
/// taken at compile time, so that a drive's image carries these and not
/// the declarations' documentation (the spec's text, field tables).
const ROUTES: [(Addr, usize, &str); MsgKind::ALL.len()] = {
    let mut routes = [(Addr::Broadcast(0), 0, ""); MsgKind::ALL.len()];
    let mut i = 0;
    while i < routes.len() {
        let def = MsgKind::ALL[i].def();
        routes[i] = (def.addr, def.len, def.name);
        i += 1;
    }
    routes
};

/// ConfigWrite frame to node `node`.
pub fn config_write_frame(node: u8, index: u8, value: f32) -> Frame {
    Frame::with_payload(
        config::CONFIG_WRITE.addr.id(node),
        &config::encode_param(index, value),
        false,
    )
}

/// ConfigValue frame from node `node`.
pub fn config_value_frame(node: u8, index: u8, value: f32) -> Frame {
    Frame::with_payload(
        config::CONFIG_VALUE.addr.id(node),
        &config::encode_param(index, value),
        false,
    )
}

/// Bits on the wire of a frame, for bus-load accounting: a classic base
/// frame has 47 overhead bits + 8 per data byte, of which 34 + 8n are subject
/// to bit stuffing (worst case one stuff bit per 4, typical estimate one per
/// 5 (used here), plus 3 interframe bits. For CAN-FD the arbitration phase (about 30 bits
/// including stuffing) runs at the nominal rate and the data phase (control,
/// data, 17/21-bit CRC, fixed stuff bits) at the data rate.
/// Returns the duration in nanoseconds.
pub fn frame_time_ns(frame: &Frame, nominal_bps: u64, data_bps: u64) -> u64 {
    let n = frame.len as u64;
    if !frame.fd {
        let stuffable = 34 + 8 * n;
        let bits = 47 + 8 * n + stuffable / 5 + 3;
        bits * 1_000_000_000 / nominal_bps
    } else {
        let dlc_bytes = fd_dlc_len(frame.len as usize) as u64;
        // Arbitration phase: SOF, 11-bit id, RRS, IDE, FDF, res, BRS (+ stuffing),
        // then CRC delimiter, ACK, EOF, IFS at the nominal rate.
        let nominal_bits = 1 + 11 + 5 + 3 + 2 + 7 + 3;
        let crc_bits = if dlc_bytes > 16 { 21 } else { 17 };
        let data_bits = 1 + 4 + 8 * dlc_bytes + 4 + crc_bits + (crc_bits / 4 + 1);
        let data_bits = data_bits + (8 * dlc_bytes).div_ceil(5);
        nominal_bits * 1_000_000_000 / nominal_bps + data_bits * 1_000_000_000 / data_bps
    }
}

/// Smallest valid CAN-FD payload length ≥ `n`.
pub const fn fd_dlc_len(n: usize) -> usize {
    match n {
        0..=8 => n,
        9..=12 => 12,
        13..=16 => 16,
        17..=20 => 20,
        21..=24 => 24,
        25..=32 => 32,
        33..=48 => 48,
        _ => 64,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn identifiers_are_unique_and_ordered_by_priority() {
        let mut ids: heapless::Vec<(u16, &str), 256> = heapless::Vec::new();
        for def in all_messages() {
            for &n in def.addr.nodes() {
                ids.push((def.addr.id(n), def.name)).unwrap();
            }
        }
        for (i, a) in ids.iter().enumerate() {
            assert!(a.0 < 0x800, "{} 0x{:X}", a.1, a.0);
            for b in &ids[i + 1..] {
                assert_ne!(a.0, b.0, "{} and {} share 0x{:X}", a.1, b.1, a.0);
            }
        }
        // Priority classes in the order the spec requires.
        let class = [
            Emergency::DEF.addr.id(3),
            TimeSync::DEF.addr.id(0),
            Command::DEF.addr.id(3),
            config::CONFIG_WRITE.addr.id(3),
            segment::SEGMENT_PART_FD.addr.id(0),
            SegmentAck::DEF.addr.id(3),
            CommandAck::DEF.addr.id(3),
            Heartbeat::DEF.addr.id(3),
            Telemetry::DEF.addr.id(1),
        ];
        let lowest = [
            Emergency::DEF.addr.id(0),
            TimeSync::DEF.addr.id(0),
            Command::DEF.addr.id(0),
            config::CONFIG_WRITE.addr.id(0),
            segment::SEGMENT_PART.addr.id(0),
            SegmentAck::DEF.addr.id(1),
            CommandAck::DEF.addr.id(1),
            Heartbeat::DEF.addr.id(1),
            Telemetry::DEF.addr.id(1),
        ];
        for i in 1..class.len() {
            assert!(
                class[i - 1] < lowest[i],
                "class {i} not after class {}",
                i - 1
            );
        }
    }

    #[test]
    fn fields_fit_and_do_not_overlap() {
        for def in all_messages() {
            let mut used = [false; MAX_PAYLOAD];
            for f in def.fields {
                assert!(
                    f.offset + f.ty.len() <= def.len,
                    "{}.{} beyond the payload",
                    def.name,
                    f.name
                );
                for u in &mut used[f.offset..f.offset + f.ty.len()] {
                    assert!(!*u, "{}.{} overlaps", def.name, f.name);
                    *u = true;
                }
            }
            assert!(def.len <= if def.fd { 64 } else { 8 }, "{}", def.name);
        }
    }

    #[test]
    fn decode_checks_length_and_id() {
        let hb = Heartbeat {
            state: 3,
            fault: 0,
            queue_depth: 5,
            protocol_version: PROTOCOL_VERSION,
            config_crc: 0xDEAD_BEEF,
        };
        let f = hb.to_frame(2);
        assert_eq!(f.id, 0x702);
        assert_eq!(decode(&f), Ok((Msg::Heartbeat(hb), 2)));
        let short = Frame::with_payload(0x702, &[1, 2], false);
        assert!(matches!(decode(&short), Err(DecodeError::Length { .. })));
        let unknown = Frame::with_payload(0x7FF, &[], false);
        assert_eq!(decode(&unknown), Err(DecodeError::UnknownId(0x7FF)));
    }

    #[test]
    fn every_declared_message_has_a_kind() {
        let all = all_messages();
        for def in SIMPLE_MESSAGES {
            assert!(
                all.iter().any(|d| d.name == def.name),
                "{} is declared but has no MsgKind (no decoder)",
                def.name
            );
        }
        for (i, kind) in MsgKind::ALL.iter().enumerate() {
            assert!(!MsgKind::ALL[..i].contains(kind), "{kind:?} listed twice");
        }
    }

    #[test]
    fn every_kind_decodes_to_itself() {
        for kind in MsgKind::ALL {
            let def = kind.def();
            let node = def.addr.nodes()[def.addr.nodes().len() - 1];
            let f = Frame::new(def.addr.id(node), def.len, def.fd);
            let (msg, n) = decode(&f).unwrap();
            assert_eq!((msg.kind(), n), (kind, node), "{}", def.name);
        }
    }

    #[test]
    fn code_fields_decode_to_their_enums() {
        let hb = Heartbeat {
            state: State::Running as u8,
            fault: 99,
            ..Default::default()
        };
        let Ok((Msg::Heartbeat(got), _)) = decode(&hb.to_frame(1)) else {
            panic!("not a heartbeat");
        };
        assert_eq!(got.state(), Ok(State::Running));
        assert_eq!(got.fault(), Err(99));
        let ack = SegmentAck {
            result: Reject::Discontinuous as u8,
            ..Default::default()
        };
        assert_eq!(ack.result(), Ok(Reject::Discontinuous));
        let c = Command {
            command: CommandCode::ClearFault as u8,
            ..Default::default()
        };
        assert_eq!(c.command(), Ok(CommandCode::ClearFault));
    }

    #[test]
    fn frame_times_match_the_prior_art() {
        // Classic 8-byte frame at 1 Mbit/s: about 110-130 µs.
        let f = Frame::new(0x100, 8, false);
        let t = frame_time_ns(&f, 1_000_000, 1_000_000);
        assert!((110_000..=135_000).contains(&t), "{t}");
        // 64-byte CAN-FD at 1/5 Mbit/s: about 150 µs.
        let f = Frame::new(0x110, 64, true);
        let t = frame_time_ns(&f, 1_000_000, 5_000_000);
        assert!((120_000..=170_000).contains(&t), "{t}");
    }
}
