//! The bounds every drive applies to what it receives, declared once: the
//! firmware checks segments and commands with these constants, and the
//! "Acceptance bounds" table of `docs/protocol.md` is generated from
//! [`BOUNDS`], so the spec cannot promise one number while the drives use another.

pub use super::segment::MAX_DURATION_US;
use super::wire::spec_text;

/// Shortest segment accepted (µs).
pub const MIN_DURATION_US: u32 = 1;
/// The margin a drive grants over the configured velocity, acceleration and
/// jerk limits, as a fraction of them (segment check), and the largest jump
/// of q', q'', q''' between segments, also as a fraction of the limits. Not
/// the planner's own verification tolerance: this one absorbs the drive's
/// f32 evaluation of an exactly verified plan.
pub const RELATIVE_LIMIT_MARGIN: f32 = 0.01;
/// Largest jump a drive accepts between a segment's start position and the
/// previous segment's end (m), on every axis: f32 rounding of positions, not
/// a gap in the plan.
pub const MAX_POSITION_JUMP_M: f32 = 10e-6;
/// Positions (finite, soft limits) are checked at `LIMIT_CHECK_INTERVALS + 1`
/// evenly spaced points of a segment (a safety net behind the host's exact
/// verification, not a replacement for it); velocity, acceleration and jerk
/// by the segment's exact maxima.
pub const LIMIT_CHECK_INTERVALS: i64 = 64;
/// A command repeated (same code, token, argument) within this time is a
/// duplicate frame, answered again and not executed again (µs): CAN resends
/// a frame whose ACK slot a receiver missed.
pub const REPEAT_WINDOW_US: u64 = 100_000;
/// Sync timeout of a node without a configuration (µs): what its
/// HeartbeatExt `flags` (synced) is judged by.
pub const UNCONFIGURED_SYNC_TIMEOUT_US: u64 = 500_000;
/// Heartbeat period of a node without a configuration (µs).
pub const UNCONFIGURED_HEARTBEAT_US: u64 = 100_000;
/// Shortest heartbeat period, whatever is configured (µs).
pub const MIN_HEARTBEAT_US: u64 = 1_000;
/// A running node stops with `PeerLost` when a peer is still Loaded or
/// Armed this long after the start, or Idle this long before the end of
/// the plan (µs): covers the start skew (one tick) and the end skew.
pub const PEER_SKEW_MARGIN_US: u64 = 20_000;
/// A node that stops for a fault vouches for its ramp (Emergency
/// `ramp_100us`) over the plan time its stop covers and this much more
/// (µs): a peer that takes the Emergency within this of the fault checks
/// a window inside the sender's, so an honest ramp is never refused.
pub const PEER_RAMP_MARGIN_US: i64 = 10_000;
/// A peer dates the stop an Emergency causes to its sender's instant when
/// that is within this of the receipt (µs): a frame's way on a busy bus
/// and a tick. Further back, the ramp would begin part-way with a step in
/// acceleration; the receipt is used instead.
pub const EMERGENCY_DATE_MAX_US: i64 = 2_000;
/// How long the maintenance window `UnlockCeilings` opens stays open at
/// most (µs): long enough for a configuration's writes and the commit's
/// resends, short enough that a forgotten unlock does not stay open.
pub const MAINTENANCE_WINDOW_US: u64 = 10_000_000;

/// One row of the generated table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bound {
    pub name: &'static str,
    pub value: f64,
    pub unit: &'static str,
    pub doc: &'static str,
}

/// Every bound above, for `docs/protocol.md`.
pub const BOUNDS: &[Bound] = &[
    Bound {
        name: "segment duration",
        value: MIN_DURATION_US as f64,
        unit: "µs (min)",
        doc: spec_text!("Shorter: `Invalid`."),
    },
    Bound {
        name: "segment duration",
        value: MAX_DURATION_US as f64,
        unit: "µs (max)",
        doc: spec_text!("Longer: `Invalid`."),
    },
    Bound {
        name: "limit tolerance",
        value: RELATIVE_LIMIT_MARGIN as f64 * 100.0,
        unit: "%",
        doc: spec_text!(
            "The exact maxima of every axis's velocity, acceleration and jerk over a segment may exceed the configured limits by this much (`Invalid` beyond), and the ceilings (`Above…Ceiling`, `OverrideAboveCeiling`, `StopAboveCeiling` beyond); also the largest jump of q', q'', q''' between segments, as a fraction of the limits (`Discontinuous` beyond)."
        ),
    },
    Bound {
        name: "check points",
        value: (LIMIT_CHECK_INTERVALS + 1) as f64,
        unit: "per segment",
        doc: spec_text!(
            "Evenly spaced points (both ends included) at which every axis's position is checked finite (`Invalid`) and the node's own axis within its soft limits (`OutsideSoftLimits`)."
        ),
    },
    Bound {
        name: "position continuity",
        value: MAX_POSITION_JUMP_M as f64 * 1e6,
        unit: "µm",
        doc: spec_text!(
            "Largest jump between a segment's start and the previous end, every axis (`Discontinuous` beyond)."
        ),
    },
    Bound {
        name: "command repeat window",
        value: REPEAT_WINDOW_US as f64 / 1000.0,
        unit: "ms",
        doc: spec_text!(
            "The same command, token and argument again within this time is answered again, not executed again."
        ),
    },
    Bound {
        name: "unconfigured sync timeout",
        value: UNCONFIGURED_SYNC_TIMEOUT_US as f64 / 1000.0,
        unit: "ms",
        doc: spec_text!(
            "`flags` bit synced of a node without a configuration (configured: `sync_timeout`)."
        ),
    },
    Bound {
        name: "unconfigured heartbeat period",
        value: UNCONFIGURED_HEARTBEAT_US as f64 / 1000.0,
        unit: "ms",
        doc: spec_text!(
            "Heartbeat period of a node without a configuration (configured: `heartbeat_period`)."
        ),
    },
    Bound {
        name: "shortest heartbeat period",
        value: MIN_HEARTBEAT_US as f64 / 1000.0,
        unit: "ms",
        doc: spec_text!("A shorter configured `heartbeat_period` is raised to this."),
    },
    Bound {
        name: "peer skew margin",
        value: PEER_SKEW_MARGIN_US as f64 / 1000.0,
        unit: "ms",
        doc: spec_text!(
            "A peer still Loaded/Armed this long after the start, or Idle this long before the plan's end, stops a running node (`PeerLost`)."
        ),
    },
    Bound {
        name: "maintenance window",
        value: MAINTENANCE_WINDOW_US as f64 / 1000.0,
        unit: "ms",
        doc: spec_text!(
            "`UnlockCeilings` lets the next ConfigCommit raise ceilings or widen the travel for at most this long (`CeilingsLocked` after)."
        ),
    },
];
