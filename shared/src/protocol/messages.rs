//! THE declaration of the triquint CAN protocol: every code table and every
//! fixed-layout message, once. The codec, `docs/triquint.dbc`, the tables of
//! `docs/protocol.md` and `testdata/protocol/golden.txt` are generated from it.
//! Multiplexed messages (segment parts, configuration) are declared in
//! [`super::segment`] and [`super::config`].

use super::Frame;
use super::wire::{Addr, code_enum, messages};

code_enum! {
    /// Drive state (CiA 402 in spirit, reduced to what a motion queue needs).
    State {
        /// Servo holds position; no segments queued. Accepts config and segments.
        Idle = 0,
        /// At least one segment queued; waiting for Arm.
        Loaded = 1,
        /// Checks passed (config, time sync, position at plan start); waiting for Start.
        Armed = 2,
        /// Executing the queue on the shared time base (feed hold is a sub-mode).
        Running = 3,
        /// Slowing along the buffered path by a jerk-limited time-scaling.
        Stopping = 4,
        /// Stopped with a fault code; holds position; only ClearFault leaves it.
        Fault = 5,
        /// Moving toward the limit switch, latching its edge and backing off
        /// (after Home); Idle and homed when done, Fault if it fails.
        Homing = 6,
    }
}

code_enum! {
    /// Fault codes (Emergency, Heartbeat) and refusal reasons (CommandAck); 0 = none.
    FaultCode {
        /// No fault / command accepted.
        None = 0,
        /// Buffered motion time fell below the stop's plan-time length (from the stop ramp length T_s) plus margin.
        Underrun = 1,
        /// No time sync within the configured timeout while armed or running.
        LostSync = 2,
        /// |position reference − encoder| exceeded the configured bound.
        FollowingError = 3,
        /// Another node sent an Emergency frame or a heartbeat with a fault.
        PeerEmergency = 4,
        /// The host sent an Emergency frame (emergency stop).
        HostEmergency = 5,
        /// Arm refused: this axis is further than the arm tolerance from the plan start.
        ArmTooFar = 6,
        /// Arm or Start refused: no valid time sync yet.
        NotSynced = 7,
        /// Arm refused or segment rejected: no active configuration.
        NoConfig = 8,
        /// ConfigCommit refused: CRC differs or a parameter is missing or invalid.
        ConfigMismatch = 9,
        /// Start time already passed when the Start command arrived.
        StartInPast = 10,
        /// Arm refused: the queue does not begin with the plan's first segment.
        EmptyQueue = 11,
        /// Command not allowed in the current state.
        WrongState = 12,
        /// The feedforward could not be computed (pose outside the workspace).
        Kinematics = 13,
        /// Unknown command code or argument.
        BadCommand = 14,
        /// Commanded quick stop (not an error; reported for the record).
        QuickStop = 15,
        /// A peer node fell silent (no heartbeat within the sync timeout) or lost its configuration (reset) while running.
        PeerLost = 16,
        /// The measured position left this axis's soft limits while running: jerk-limited stop along the path.
        SoftLimit = 17,
        /// Arm or segment refused: the axis is not homed (its position is unknown). The node stays Idle; run Home first.
        NotHomed = 18,
        /// Homing did not finish within `homing_timeout`.
        HomingTimeout = 19,
        /// Home refused: the limit switch is already active (axis on or beyond its switch; move it off by hand).
        HomeSwitchActive = 20,
        /// Homing travelled `homing_max_travel` without a switch edge (dead switch or wrong direction).
        HomeSwitchNeverTriggered = 21,
        /// Override refused: above the configuration's `override_cap` (the acknowledgement's value is the cap in per mille), or 0.
        OverrideAboveCap = 22,
        /// The enable check: after the power stage came on, the axis accelerated against its torque (motor or encoder direction reversed): torque off.
        WrongDirection = 23,
        /// The enable check: the axis's acceleration per torque was outside ¼–4× the model's (encoder scale, lead or inertia wrong).
        WrongScale = 24,
        /// ConfigCommit refused: the configuration would raise a ceiling (`ceiling_*`, indices 55–58) or widen the travel (`soft_limit_min`, `soft_limit_max`) beyond the active configuration's outside a maintenance window (`UnlockCeilings`); the acknowledgement's value is the index of the first such parameter.
        CeilingsLocked = 25,
    }
}

code_enum! {
    /// Result of a segment (SegmentAck.result).
    Reject {
        /// Complete, CRC valid, in sequence, queued.
        Accepted = 0,
        /// CRC-32 over the reassembled segment does not match.
        BadCrc = 1,
        /// Segment sequence number already accepted (or part received twice).
        Duplicate = 2,
        /// Part index or sequence number out of order; the partial segment is dropped.
        OutOfOrder = 3,
        /// The queue is full (host ignored flow control).
        QueueFull = 4,
        /// Contents invalid: zero duration, coefficients out of range, bad flags.
        Invalid = 5,
        /// Segments are not accepted in this state (Stopping, Fault, no config).
        WrongState = 6,
        /// A new segment began before the previous one was complete.
        Incomplete = 7,
        /// The segment does not start where the previous one ends.
        Discontinuous = 8,
        /// The segment leaves this axis's soft limits.
        OutsideSoftLimits = 9,
        /// The axis is not homed: segments are refused until it is.
        NotHomed = 10,
        /// A compact segment whose predecessor this node does not hold as the host built on it (lost, refused or resent): the host sends it in full.
        NoPredecessor = 11,
        /// The segment's exact largest joint velocity is above the configured `ceiling_velocity` (with the relative margin).
        AboveVelocityCeiling = 12,
        /// The segment's exact largest joint acceleration is above `ceiling_acceleration`.
        AboveAccelerationCeiling = 13,
        /// The segment's exact largest joint jerk is above `ceiling_jerk`.
        AboveJerkCeiling = 14,
        /// At the configured `override_cap` the segment's scaled maxima (σv, σ²a, σ³j) would exceed a ceiling.
        OverrideAboveCeiling = 15,
        /// A stop or hold ramp (`stop_time`, `quick_stop_time`) on this segment would exceed the stop budget the jerk ceiling allows (docs/protocol.md, "Ceilings").
        StopAboveCeiling = 16,
    }
}

code_enum! {
    /// Command codes (Command.command).
    CommandCode {
        /// Loaded → Armed after checks; refusal → Fault with the reason.
        Arm = 1,
        /// Armed → Running at host time `arg` (µs, wrapping u32).
        Start = 2,
        /// Stop along the path with the configured stop ramp length T_s, then Idle (queue flushed); from host time `arg` (µs, 0 = on receipt).
        Stop = 3,
        /// Stop along the path with the quick-stop ramp length, then Idle (queue flushed); from host time `arg`.
        QuickStop = 4,
        /// Fault → Idle; the queue is flushed and sequence numbers restart at 0.
        ClearFault = 5,
        /// Running: slow to rest on the path from host time `arg` (µs, 0 = on receipt) and wait; before Start: latched, the plan starts held.
        FeedHold = 6,
        /// Running and held (or holding): back to the override's speed from host time `arg`; before Start: clears a latched hold.
        Resume = 7,
        /// Activate the written parameters if their CRC-32 equals `arg`.
        ConfigCommit = 8,
        /// Idle or Loaded: flush the queue, sequence numbers restart at 0.
        Reset = 9,
        /// Answer with a ConfigValue frame for every parameter.
        ReadConfig = 10,
        /// Idle with a configuration: home this axis (state Homing, then Idle and homed).
        Home = 11,
        /// Feed override: σ = `arg2`/1000 from host time `arg` (persists; a hold keeps it for the resume); refused above `override_cap`, the acknowledgement's value is the cap (per mille).
        Override = 12,
        /// Idle with a configuration: open the maintenance window in which the next ConfigCommit may raise ceilings or widen the travel; `arg` must be the CRC-32 of the active configuration (else `ConfigMismatch`). The window closes at that commit, at any other command but ReadConfig and ConfigCommit, and the maintenance window (Acceptance bounds) after it opened; the acknowledgement's value is the window (ms).
        UnlockCeilings = 13,
    }
}

/// Protocol version carried in every heartbeat: a host refuses nodes of
/// another version. What each version changed: the top of `docs/protocol.md`.
pub const PROTOCOL_VERSION: u8 = 11;

/// Bits of HeartbeatExt `flags`.
pub mod flags {
    /// The node has a valid time sync.
    pub const SYNCED: u8 = 1 << 0;
    /// The axis is homed: its position is absolute.
    pub const HOMED: u8 = 1 << 1;
    /// Running and held at rest by feed hold.
    pub const HELD: u8 = 1 << 2;
    /// A feed-rate override other than 100 % is set.
    pub const OVERRIDE: u8 = 1 << 3;
    /// The limit switch input is active now.
    pub const SWITCH: u8 = 1 << 4;
    /// The node has an active configuration.
    pub const CONFIGURED: u8 = 1 << 5;
    /// Every flag with its name, for the spec and decoders.
    pub const TABLE: &[(u8, &str, &str)] = &[
        (SYNCED, "synced", "valid time sync"),
        (HOMED, "homed", "axis homed: position absolute"),
        (HELD, "held", "Running, held at rest by feed hold"),
        (OVERRIDE, "override", "feed-rate override other than 100 %"),
        (SWITCH, "switch", "limit switch input active"),
        (CONFIGURED, "configured", "an active configuration"),
    ];
}

messages! {
    /// Sent at once when a node faults (or by the host, node 0, as an emergency stop).
    Emergency = Addr::FromNodeOrHost(0x010), len 8, from "node/host", every "on event" {
        /// Fault code.
        code: u8 @ 0 ["", 1.0, FaultCode],
        /// State after the fault.
        state: u8 @ 1 ["", 1.0, State],
        /// The ramp of the node's stop along the path (100 µs units), for
        /// peers to run the same one: the largest own ramp for a stop from
        /// σ ≤ 1 of the segments' pieces it passes through; 0 = the full
        /// ramp.
        ramp_100us: u16 @ 2 ["s", 0.0001],
        /// Plan time at the fault.
        plan_time_us: u32 @ 4 ["us", 1.0],
    }
    /// Broadcast time base. `prev_tx_us` is the host time at which the previous
    /// sync (seq − 1) was transmitted, so receivers cancel queueing delay.
    TimeSync = Addr::Broadcast(0x020), len 5, from "host", every "100 ms" {
        /// Sync sequence number (wrapping).
        seq: u8 @ 0 ["", 1.0],
        /// Host time when sync `seq − 1` left the host (µs, wrapping).
        prev_tx_us: u32 @ 1 ["us", 1.0],
    }
    /// Command to node n (or all nodes on node 0); answered by CommandAck.
    Command = Addr::ToNode(0x030), len 8, from "host", every "on event" {
        /// Command code.
        command: u8 @ 0 ["", 1.0, CommandCode],
        /// Echoed in the CommandAck.
        token: u8 @ 1 ["", 1.0],
        /// Start: host time (µs); FeedHold, Resume, Stop, QuickStop, Override: host time (µs) all nodes apply it at, 0 = on receipt; ConfigCommit: CRC-32; UnlockCeilings: CRC-32 of the active configuration; otherwise 0.
        arg: u32 @ 2 ["", 1.0],
        /// Override: σ in per mille (1000 = 100 %); Stop, QuickStop, FeedHold: the stop ramp for the path ahead of its instant in 100 µs, run if shorter than the full ramp and covering the own ramps of the queued segments' pieces the stop passes through; 0 = none carried: dated (`arg` ≠ 0), a Stop or FeedHold runs the ramp the drive sizes for its instant, on receipt the full ramp; otherwise 0.
        arg2: u16 @ 6 ["", 1.0],
    }
    /// Acknowledgement of every segment, accepted or rejected.
    SegmentAck = Addr::FromNode(0x180), len 8, from "node", every "per segment" {
        /// Segment sequence number (or the partial segment's).
        seq: u16 @ 0 ["", 1.0],
        /// Accepted or the reason for rejection.
        result: u8 @ 2 ["", 1.0, Reject],
        /// Segments queued after this one.
        depth: u8 @ 3 ["", 1.0],
        /// Next sequence number the node will accept.
        next_seq: u16 @ 4 ["", 1.0],
        /// Queue capacity (segments).
        capacity: u8 @ 6 ["", 1.0],
        /// How many segments were rejected for this reason so far (saturating).
        reason_count: u8 @ 7 ["", 1.0],
    }
    /// Answer to every Command.
    CommandAck = Addr::FromNode(0x1A0), len 8, from "node", every "per command" {
        /// Command code answered.
        command: u8 @ 0 ["", 1.0, CommandCode],
        /// Token of the command.
        token: u8 @ 1 ["", 1.0],
        /// 0 = done, otherwise why not.
        result: u8 @ 2 ["", 1.0, FaultCode],
        /// State after the command.
        state: u8 @ 3 ["", 1.0, State],
        /// ConfigCommit: CRC-32 the node computed (refused with CeilingsLocked: the index of the first parameter that widens); Override: the cap (per mille); Arm: the feed override the plan starts at (per mille); UnlockCeilings: the window (ms); otherwise 0.
        value: u32 @ 4 ["", 1.0],
    }
    /// Periodic status of node n.
    Heartbeat = Addr::FromNode(0x700), len 8, from "node", every "100 ms" {
        /// State.
        state: u8 @ 0 ["", 1.0, State],
        /// Active fault (0 = none).
        fault: u8 @ 1 ["", 1.0, FaultCode],
        /// Segments queued (including the executing one).
        queue_depth: u8 @ 2 ["", 1.0],
        /// Protocol version.
        protocol_version: u8 @ 3 ["", 1.0],
        /// CRC-32 of the active configuration (0 = none).
        config_crc: u32 @ 4 ["", 1.0],
    }
    /// Second heartbeat frame: sequence, rejection and bus counters.
    HeartbeatExt = Addr::FromNode(0x740), len 8, from "node", every "100 ms" {
        /// Next sequence number the node will accept (= last accepted + 1).
        next_seq: u16 @ 0 ["", 1.0],
        /// Segments and parts rejected since the last Reset (saturating).
        rejects: u16 @ 2 ["", 1.0],
        /// CAN transmit error counter (TEC).
        tx_errors: u8 @ 4 ["", 1.0],
        /// CAN receive error counter (REC).
        rx_errors: u8 @ 5 ["", 1.0],
        /// Reason of the last rejection.
        last_reject: u8 @ 6 ["", 1.0, Reject],
        /// Bits: 0 synced, 1 homed, 2 held, 3 override active, 4 limit switch active, 5 configured.
        flags: u8 @ 7 ["", 1.0],
    }
    /// Telemetry: measured position and velocity of node n's axis.
    Telemetry = Addr::FromNode(0x780), len 8, from "node", every "configurable" {
        /// Joint position from the encoder.
        position: f32 @ 0 ["m", 1.0],
        /// Joint velocity (filtered difference).
        velocity: f32 @ 4 ["m/s", 1.0],
    }
    /// Telemetry: torque command and following error of node n's axis.
    TelemetryExt = Addr::FromNode(0x790), len 8, from "node", every "configurable" {
        /// Motor torque command.
        torque: f32 @ 0 ["N.m", 1.0],
        /// Position reference − measured position.
        following_error: f32 @ 4 ["m", 1.0],
    }
}

impl Emergency {
    /// The host's emergency stop (from node 0, state Fault): what every
    /// drive faults or stops on.
    pub fn host_stop() -> Frame {
        Self {
            code: FaultCode::HostEmergency as u8,
            state: State::Fault as u8,
            ramp_100us: 0,
            plan_time_us: 0,
        }
        .to_frame(0)
    }
}

impl HeartbeatExt {
    /// Is flag `bit` (one of [`flags`]) set?
    pub const fn has(&self, bit: u8) -> bool {
        self.flags & bit != 0
    }
}
