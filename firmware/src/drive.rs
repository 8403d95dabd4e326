//! The control side of a drive node: state, segment queue and the control
//! tick, fed with finished items by the receive side (through the hand-off
//! types of the `inbox` module). Here: the drive's state, filing items,
//! stopping, and the tick that runs the parts in order; the parts are in
//! `drive/`: `segments` (filing a segment), `queue_ramps` (the queued
//! segments' largest own ramps, by block), `commands`, `supervision`
//! (what else stops the drive), `reference` (start trigger and reference),
//! `telemetry` (periodic frames); the control law is the `law` module.

mod commands;
mod homing;
mod queue_ramps;
mod reference;
mod segments;
mod supervision;
mod telemetry;

use heapless::Deque;
use nalgebra::Vector3;
use triquint_shared::Model;
use triquint_shared::protocol::contract::{PEER_RAMP_MARGIN_US, UNCONFIGURED_SYNC_TIMEOUT_US};
use triquint_shared::protocol::{
    Command, CommandAck, DriveConfig, Emergency, FaultCode, Frame, PARAM_COUNT, Reject, State,
};
use triquint_shared::quintic::JointMotion;

use crate::ceiling_lock::Window;
use crate::derived_config::DerivedConfig;
use crate::enable_check::{EnableCheck, Expected};
use crate::f32_cast::to_f32;
use crate::hal::{Encoder, LimitSwitch, MotorOutput, NoSwitch};
use crate::homing::Homing;
use crate::inbox::{Item, Source, TAKE_PER_TICK, TickSnapshot};
use crate::law::{self, Gains, LawState};
use crate::reaction::{self, Reaction};
use crate::scaling::{Phase, Retarget, TimeScaling, UNIT_Q16};
use crate::segment::{Seg, UnitRamps};
use crate::sync::SyncEstimator;
use queue_ramps::queued;
use triquint_shared::protocol::segment_maxima::PIECES;

/// The feedforward is evaluated this many control periods ahead on the
/// path: the torque computed now acts from the next tick on, held for one.
pub const FF_LOOKAHEAD_TICKS: f32 = 1.5;
const FF_LOOKAHEAD_NS_PER_S: f32 = FF_LOOKAHEAD_TICKS * 1e9;
/// Encoder scale of a node without a configuration (m per count): only
/// for the position it reports before it has one.
pub const UNCONFIGURED_M_PER_COUNT: f32 = 1e-9;

/// Segment queue capacity of a node (segments): declared in shared, where
/// the planner and `check` hold plans to it (`protocol::streaming`).
pub use triquint_shared::protocol::streaming::QUEUE_CAPACITY;
/// Frames waiting for the CAN controller.
pub const OUTBOX: usize = 16;

/// A frame waiting in the outbox: every message a node sends fits a
/// classic frame's 8 bytes, so the outbox does not keep 64 for each.
#[derive(Clone, Copy, Debug)]
struct Outgoing {
    id: u16,
    len: u8,
    fd: bool,
    data: [u8; 8],
}

impl Outgoing {
    /// `None` for a payload over 8 bytes (no message of a node has one).
    fn of(f: &Frame) -> Option<Self> {
        let mut data = [0; 8];
        data.get_mut(..f.len as usize)?.copy_from_slice(f.payload());
        Some(Self {
            id: f.id,
            len: f.len,
            fd: f.fd,
            data,
        })
    }

    fn frame(&self) -> Frame {
        Frame::with_payload(self.id, &self.data[..(self.len as usize).min(8)], self.fd)
    }
}

/// No segment dropped since the last flush: it ends before any plan time.
const NONE_DROPPED: Dropped = (
    i64::MIN,
    0,
    UnitRamps {
        pieces: [0; PIECES],
        largest: [0; 2],
    },
);

/// A piece of a segment of 1 µs lasts this many ns: 1 000 ns a µs divides
/// by the pieces.
const PIECE_NS_PER_US: i64 = 1000 / PIECES as i64;
const _: () = assert!(1000 % PIECES == 0);

/// The largest own controlled ramp for a stop from σ ≤ 1 (100 µs units)
/// of the pieces of a segment from plan time `a` (ns) of `us` µs that
/// overlap [`lo`, `hi`), which the segment overlaps (0 if no piece does).
#[inline(always)]
fn pieces_over(a: i64, us: u32, ramps: &UnitRamps, lo: i64, hi: i64) -> u16 {
    let piece = us as i64 * PIECE_NS_PER_US;
    let mut m = 0;
    let mut p0 = a;
    for &r in &ramps.pieces {
        let p1 = p0 + piece;
        // A plain comparison: `max` is a call out of the tick's memory.
        if r > m && p1 > lo && p0 < hi {
            m = r;
        }
        p0 = p1;
    }
    m
}

/// What a node keeps of the segment it last dropped: its start (plan ns),
/// duration (µs) and its pieces' own ramps for stops from σ ≤ 1.
type Dropped = (i64, u32, UnitRamps);

/// Why the node is slowing down.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StopReason {
    /// Stop command: Idle at rest.
    Commanded,
    /// Feed hold: stay Running at rest until Resume.
    Hold,
    /// Fault: Fault at rest.
    Fault(FaultCode),
}

/// Counters and last values, for telemetry and tests.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stats {
    pub rejects: u16,
    pub reason_counts: [u8; Reject::TABLE.len()],
    pub last_reject: u8,
    pub torque: f32,
    pub following_error: f32,
    pub q: f32,
    pub v: f32,
    pub reference: JointMotion<f32>,
    /// Host time (ns) of the first Running tick.
    pub started_at_ns: Option<i64>,
    /// The last enable check's fitted gain over the model's (0: none yet).
    pub check_gain_ratio: f32,
    /// Its fitted load torque over the model's (0: none yet).
    pub check_load_ratio: f32,
    pub ticks: u64,
}

/// The control side of one drive node, with a segment queue of capacity `Q`.
#[derive(Clone)]
pub struct Drive<const Q: usize = QUEUE_CAPACITY> {
    node_id: u8,
    state: State,
    fault: FaultCode,
    active: Option<DerivedConfig>,
    /// The committed configuration and its robot model (valid with `active`).
    cfg: DriveConfig,
    /// The maintenance window in which a commit may widen the ceilings.
    maintenance: Window,
    model: Model<f32>,
    queue: Deque<Seg, Q>,
    /// Queue flushes so far (the receive side then drops a partial segment).
    flushes: u32,
    next_seq: u16,
    queued_end_ns: i64,
    /// The largest of the queued segments' own stop ramps, controlled and
    /// quick (µs): the drive's floor under the configured ones.
    queue_ramps_us: (u32, u32),
    /// The largest per block of queue slots (`drive/queue_ramps.rs`).
    block_ramps: [queue_ramps::BlockRamps; queue_ramps::MAX_BLOCKS],
    /// The last segment the queue dropped (the one before its front):
    /// its span and its pieces' own ramps for stops from σ ≤ 1. A dated
    /// stop applies up to `APPLY_LATE_MAX_US` late, by when
    /// a node may have dropped the segment it begins in (and its peers,
    /// whose ticks fall elsewhere, not): every node counts it all the
    /// same, and one that begins earlier still gets the full ramp.
    dropped: Dropped,
    /// End motion (q, q', q'', q''') of the last accepted segment.
    prev_end: Option<JointMotion<f32>>,
    /// Body CRC of the last accepted segment (valid with `prev_end`).
    prev_crc: u32,
    sync: SyncEstimator,
    scaling: TimeScaling,
    stop_reason: Option<StopReason>,
    /// Feed override σ (1/65 536; persists until changed, clamped to a new
    /// configuration's cap).
    override_q16: u32,
    /// A FeedHold before Start: the plan starts held.
    hold_latched: bool,
    start_ns: Option<i64>,
    current_seq: u16,
    plan_ns: i64,
    hold: Option<Vector3<f32>>,
    hold_own: f32,
    /// The position loop's state (integral, error derivative, feedforward).
    law: LawState,
    last_q: Option<f32>,
    vel: f32,
    enabled: bool,
    /// The fault reaction took the torque off: the power stage stays off
    /// (the brake applied) until ClearFault.
    torque_off: bool,
    /// The fault reaction holds by this static torque (N·m, before the
    /// motor's direction) with no position feedback.
    open_loop: Option<f32>,
    /// The load torque the last enable check measured (N·m).
    measured_load: Option<f32>,
    /// The enable check in progress since the power stage came on.
    check: Option<EnableCheck>,
    /// The enable check passed since the power stage came on.
    verified: bool,
    next_heartbeat_us: u64,
    next_telemetry_us: u64,
    last_local_us: u64,
    errors: (u8, u8),
    outbox: Deque<Outgoing, OUTBOX>,
    dropped_tx: u32,
    /// A ReadConfig's values and the index of the next one to send: sent
    /// over as many ticks as the outbox needs (`config_readout`).
    readout: Option<([f32; PARAM_COUNT], u8)>,
    /// The last command executed and its answer: a CAN frame can arrive twice
    /// (a transmitter that missed the ACK resends it), so a repeat of the
    /// same command, token and argument within the repeat window
    /// ([`triquint_shared::protocol::contract::REPEAT_WINDOW_US`]) is
    /// answered again, not executed again.
    last_command: Option<(Command, CommandAck, u64)>,
    /// Receive time (µs) of the command being handled.
    command_rx_us: u64,
    /// Local time (µs) of the last heartbeat of the drive of each axis.
    peer_seen_us: [Option<u64>; 3],
    /// The axis position is absolute (homed, or started homed).
    homed: bool,
    /// Encoder count of the axis zero (set by homing).
    home_offset: i64,
    /// The homing run, in state Homing.
    homing: Option<Homing>,
    /// The limit switch input at the last tick.
    switch_active: bool,
    pub stats: Stats,
}

impl<const Q: usize> Drive<Q> {
    /// A node with number `node_id` (1–15), Idle, unconfigured, motor off,
    /// homed (its encoder's zero is the axis zero: simulators, tests).
    pub fn new(node_id: u8) -> Self {
        Self::with_homed(node_id, true)
    }

    /// A node after power-on on a machine whose position is unknown until
    /// it is homed (a board with a limit switch, `triquint-sim --unhomed`).
    pub fn new_unhomed(node_id: u8) -> Self {
        Self::with_homed(node_id, false)
    }

    fn with_homed(node_id: u8, homed: bool) -> Self {
        Self {
            node_id,
            state: State::Idle,
            fault: FaultCode::None,
            active: None,
            cfg: DriveConfig::default(),
            maintenance: Window::default(),
            model: Model {
                rho_u: [Vector3::zeros(); 3],
                l: 0.0,
                l2: 0.0,
                platform_mass: 0.0,
                strut_mass: 0.0,
                slider_mass: 0.0,
                rotor_inertia: 0.0,
                ratio: 0.0,
                inv_ratio: 0.0,
                gravity: 0.0,
            },
            queue: Deque::new(),
            flushes: 0,
            next_seq: 0,
            queued_end_ns: 0,
            queue_ramps_us: (0, 0),
            block_ramps: [queue_ramps::BlockRamps::default(); queue_ramps::MAX_BLOCKS],
            dropped: NONE_DROPPED,
            prev_end: None,
            prev_crc: 0,
            sync: SyncEstimator::default(),
            scaling: TimeScaling::nominal(0, 0),
            stop_reason: None,
            override_q16: UNIT_Q16,
            hold_latched: false,
            start_ns: None,
            current_seq: 0,
            plan_ns: 0,
            hold: None,
            hold_own: 0.0,
            law: LawState::default(),
            last_q: None,
            vel: 0.0,
            enabled: false,
            torque_off: false,
            open_loop: None,
            measured_load: None,
            check: None,
            verified: false,
            next_heartbeat_us: 0,
            next_telemetry_us: 0,
            last_local_us: 0,
            errors: (0, 0),
            outbox: Deque::new(),
            dropped_tx: 0,
            readout: None,
            peer_seen_us: [None; 3],
            homed,
            home_offset: 0,
            homing: None,
            switch_active: false,
            last_command: None,
            command_rx_us: 0,
            stats: Stats::default(),
        }
    }

    pub fn state(&self) -> State {
        self.state
    }
    pub fn fault(&self) -> FaultCode {
        self.fault
    }
    pub fn node_id(&self) -> u8 {
        self.node_id
    }
    pub fn queue_depth(&self) -> usize {
        self.queue.len()
    }
    pub fn next_seq(&self) -> u16 {
        self.next_seq
    }
    pub fn config_crc(&self) -> u32 {
        self.active.as_ref().map(|a| a.crc).unwrap_or(0)
    }
    /// What the receive side needs to know, published every tick.
    pub fn snapshot(&self) -> TickSnapshot {
        TickSnapshot {
            config_crc: self.config_crc(),
            flushes: self.flushes,
            // Only a node with no motion pending may follow a new host time base.
            may_rebase: matches!(self.state, State::Idle | State::Fault),
            scaling: self.scaling,
            override_q16: self.override_q16,
            ramps_ns: self.active.map(|a| self.ramps_ns(&a)),
        }
    }

    /// The stop ramps every transition runs with, controlled and quick
    /// (ns): the configured ones, never shorter than the queued segments'
    /// own (docs/protocol.md, "Stop ramp").
    pub fn ramps_ns(&self, a: &DerivedConfig) -> (i64, i64) {
        let (s, q) = self.queue_ramps_us;
        (
            a.stop_ns.max(s as i64 * 1000),
            a.quick_stop_ns.max(q as i64 * 1000),
        )
    }

    /// The ramp for a stop from host time `t` that the host dated
    /// (`dated_100us` × 100 µs, docs/protocol.md "A ramp for the path
    /// ahead"), if it is shorter than `full_ns` (the ramp every transition
    /// runs with) and covers the own ramps of every queued piece the stop
    /// passes through (the dropped segment's included); else `full_ns`.
    /// Only from a constant σ: a transition begun in another one is sized
    /// against `full_ns`. `u16::MAX` is no ramp (`f32_cast::ramp_units`).
    // Cold, out of line: only the tick that takes a dated stop runs it.
    #[cold]
    #[inline(never)]
    fn dated_ramp_ns(&self, t: i64, dated_100us: u16, full_ns: i64, quick: bool) -> i64 {
        let dated = dated_100us as i64 * 100_000;
        // Held to the pieces' ramps for stops from σ ≤ 1 only.
        if dated == 0
            || dated_100us == u16::MAX
            || dated >= full_ns
            || self.scaling.in_transition()
            || self.scaling.target_q16() > UNIT_Q16
        {
            return full_ns;
        }
        let s = self.scaling.constant_plan_time_ns(t);
        // At σ ≤ 1 the stop covers at most T/2 of plan time.
        let end = s + (dated >> 1);
        // The segment before the front first, then the queue in plan
        // order, piece by piece up to the window's end; a stop that begins
        // before the dropped segment gets the full ramp.
        let (from, us, ramps) = &self.dropped;
        if *from > s {
            return full_ns;
        }
        // The dropped segment, then the queue in plan order, up to the
        // window's end. Piece bounds only for a segment whose largest own
        // ramp is too long (a quick stop is held to the whole segment's);
        // a piece that ended by s counts for nothing.
        let refuses = |a: i64, us: u32, r: &UnitRamps| {
            if quick {
                // The front may have ended by s: the tick takes a stop
                // before it advances the queue.
                r.largest[1] > dated_100us && a + us as i64 * 1000 > s
            } else {
                r.largest[0] > dated_100us && pieces_over(a, us, r, s, end) > dated_100us
            }
        };
        if *from + *us as i64 * 1000 > s && refuses(*from, *us, ramps) {
            return full_ns;
        }
        let halves = self.queue.as_slices();
        let mut i = 0;
        while let Some(q) = queued(halves, i) {
            if q.start_ns >= end {
                break;
            }
            // A block none of whose segments has a longer own ramp refuses
            // nothing: skipped whole.
            if let Some(n) = self.block_at_most(q.seq, quick as usize, dated_100us) {
                i += n;
                continue;
            }
            if refuses(q.start_ns, q.duration_us, &q.unit_ramps) {
                return full_ns;
            }
            i += 1;
        }
        dated
    }

    /// The ramp (ns) this node vouches for, for a controlled stop for its
    /// own fault from host time `t`, and in 100 µs units (rounded up) for
    /// its Emergency: the largest own ramp for a stop from σ ≤ 1 of the
    /// queued pieces overlapping [s − 1 µs, s + `PEER_RAMP_MARGIN_US` +
    /// T/2] for plan time s, the window every peer that takes its
    /// Emergency within the margin checks. The full ramp `full_ns` (and 0) from a transition or
    /// σ above 1, when the queue does not hold that window (nor the plan's
    /// end), or when not shorter (docs/protocol.md, "A ramp for a fault
    /// stop").
    // Cold, out of line: only the tick that takes a fault runs it.
    #[cold]
    #[inline(never)]
    fn path_ramp(&self, t: i64, full_ns: i64) -> (i64, u16) {
        const MARGIN_NS: i64 = PEER_RAMP_MARGIN_US * 1000;
        if self.scaling.in_transition() || self.scaling.target_q16() > UNIT_Q16 {
            return (full_ns, 0);
        }
        let s = self.scaling.constant_plan_time_ns(t);
        // A µs before s too: a peer dates its stop to s rounded to the µs.
        let lo = s - 1_000;
        // The segment before the front, if the stop begins in it.
        let (from, us, ramps) = &self.dropped;
        if *from > lo {
            return (full_ns, 0);
        }
        let mut units = 0u16;
        // The window's reach for a ramp of `units`.
        let reach_of = |units: u16| s + MARGIN_NS + units as i64 * 50_000;
        let mut reach = reach_of(0);
        // In plan order; the window grows as pieces raise the ramp (a piece
        // past it ends the scan: every later one begins later). Piece
        // bounds only for a segment whose largest own ramp is longer than
        // the ramp so far.
        let raise = |a: i64, us: u32, ramps: &UnitRamps, units: &mut u16, reach: &mut i64| {
            if ramps.largest[0] <= *units {
                return;
            }
            // A segment inside the window so far: every piece counts (the
            // window only grows), so its largest, with no piece bounds.
            if a >= lo && a + us as i64 * 1000 <= *reach {
                *units = ramps.largest[0];
                *reach = reach_of(*units);
                return;
            }
            let piece = us as i64 * PIECE_NS_PER_US;
            let mut p0 = a;
            for &r in &ramps.pieces {
                if p0 >= *reach {
                    break;
                }
                p0 += piece;
                if p0 > lo && r > *units {
                    *units = r;
                    *reach = reach_of(r);
                }
            }
        };
        if *from + *us as i64 * 1000 > lo {
            raise(*from, *us, ramps, &mut units, &mut reach);
        }
        let (head, tail) = self.queue.as_slices();
        'scan: for half in [head, tail] {
            for q in half {
                if q.start_ns >= reach {
                    break 'scan;
                }
                raise(
                    q.start_ns,
                    q.duration_us,
                    &q.unit_ramps,
                    &mut units,
                    &mut reach,
                );
            }
        }
        let held = self.queued_end_ns >= reach || self.queue.back().is_some_and(|b| b.last);
        let ramp = units as i64 * 100_000;
        if !held || units == 0 || units == u16::MAX || ramp >= full_ns {
            return (full_ns, 0);
        }
        (ramp, units)
    }

    /// The largest of the queued segments' own stop ramps, controlled and
    /// quick (ns).
    pub fn queue_ramps_ns(&self) -> (i64, i64) {
        let (s, q) = self.queue_ramps_us;
        (s as i64 * 1000, q as i64 * 1000)
    }

    /// Is the axis position absolute?
    pub fn is_homed(&self) -> bool {
        self.homed
    }
    /// Encoder count of the axis zero.
    pub fn home_offset(&self) -> i64 {
        self.home_offset
    }
    /// The homing run (state Homing).
    pub fn homing(&self) -> Option<&Homing> {
        self.homing.as_ref()
    }
    /// The fault reaction took the torque off (the power stage is off).
    pub fn is_torque_off(&self) -> bool {
        self.torque_off
    }
    /// The enable check passed since the power stage came on.
    pub fn is_verified(&self) -> bool {
        self.verified
    }
    /// Tests with an ideal encoder (no plant to answer the enable check):
    /// the check counts as passed.
    #[cfg(test)]
    pub(crate) fn assume_verified(&mut self) {
        if self.enabled {
            self.verified = true;
            self.check = None;
        }
    }
    /// The enable check is running.
    pub fn is_checking(&self) -> bool {
        self.check.is_some()
    }
    pub fn config(&self) -> Option<DriveConfig> {
        self.active.as_ref().map(|_| self.cfg)
    }
    pub fn is_synced(&self) -> bool {
        match &self.active {
            Some(a) => self.sync.is_synced(self.last_local_us, a.sync_timeout_us),
            None => self
                .sync
                .is_synced(self.last_local_us, UNCONFIGURED_SYNC_TIMEOUT_US),
        }
    }
    /// Host time (ns) estimated at local time `local_us`.
    pub fn host_ns(&self, local_us: u64) -> Option<i64> {
        self.sync.host_ns(local_us)
    }
    pub fn scaling_phase(&self) -> Phase {
        self.scaling.phase
    }
    /// The time-scaling now (tests, monitors).
    pub fn scaling(&self) -> TimeScaling {
        self.scaling
    }
    /// The feed override (per mille).
    pub fn override_permille(&self) -> u32 {
        (self.override_q16 * 1000 + UNIT_Q16 / 2) / UNIT_Q16
    }
    /// Held by feed hold (Running at or toward rest), or a hold latched before Start.
    pub fn is_held(&self) -> bool {
        self.hold_latched || self.stop_reason == Some(StopReason::Hold)
    }
    /// The segment the reference is taken from while Running or Stopping:
    /// (sequence number, CRC-32 of its body as received).
    pub fn executing(&self) -> Option<(u16, u32)> {
        match self.state {
            State::Running | State::Stopping => self.queue.front().map(|s| (s.seq, s.crc)),
            _ => None,
        }
    }
    /// Plan time of the last reference (ns).
    pub fn plan_ns(&self) -> i64 {
        self.plan_ns
    }
    /// Frames the controller refused and the outbox could not keep.
    pub fn dropped_tx(&self) -> u32 {
        self.dropped_tx
    }

    /// The CAN controller's (transmit, receive) error counters, for HeartbeatExt.
    pub fn set_error_counters(&mut self, e: (u8, u8)) {
        self.errors = e;
    }
    /// The error counters the next HeartbeatExt reports.
    pub fn error_counters(&self) -> (u8, u8) {
        self.errors
    }

    /// Next frame to transmit.
    pub fn peek_tx(&self) -> Option<Frame> {
        self.outbox.front().map(Outgoing::frame)
    }
    pub fn pop_tx(&mut self) -> Option<Frame> {
        self.outbox.pop_front().as_ref().map(Outgoing::frame)
    }

    fn send(&mut self, f: Frame) {
        if Outgoing::of(&f)
            .and_then(|o| self.outbox.push_back(o).ok())
            .is_none()
        {
            self.dropped_tx = self.dropped_tx.saturating_add(1);
        }
    }

    /// Ahead of everything waiting; with the outbox full (a bus that
    /// takes nothing: babble, bus-off), the newest waiting frame gives way,
    /// so an Emergency is never lost to routine traffic queued before it.
    fn send_priority(&mut self, f: Frame) {
        let Some(o) = Outgoing::of(&f) else {
            self.dropped_tx = self.dropped_tx.saturating_add(1);
            return;
        };
        if self.outbox.is_full() {
            self.outbox.pop_back();
            self.dropped_tx = self.dropped_tx.saturating_add(1);
        }
        let _ = self.outbox.push_front(o);
    }

    /// Takes up to [`TAKE_PER_TICK`] items from the queue from the receive
    /// side: what a board does at the start of every tick.
    pub fn take_from(&mut self, inbox: &mut impl Source) {
        for _ in 0..TAKE_PER_TICK {
            let Some(item) = inbox.front() else {
                break;
            };
            self.take(item);
            inbox.pop_front();
        }
    }

    /// Files one item from the receive side.
    pub fn take(&mut self, item: &Item) {
        match *item {
            Item::Sync(s) => self.sync = s,
            Item::Emergency {
                code,
                node,
                t_ns,
                ramp_100us,
                ref ready,
            } => {
                if node == 0 || self.is_peer(node) {
                    self.on_emergency(code, t_ns, ready.as_ref(), ramp_100us)
                }
            }
            Item::PeerHeartbeat {
                node,
                heartbeat,
                rx_us,
            } => self.on_peer_heartbeat(node, &heartbeat, rx_us),
            Item::Command {
                command,
                rx_us,
                ref data,
            } => self.on_command(&command, rx_us, data),
            Item::PartIgnored(r) => {
                self.count_reject(r);
            }
            Item::PartRejected { seq, reason } => {
                let n = self.count_reject(reason);
                self.ack(seq, reason, n);
            }
            Item::Segment(ref c) => match self.accept(c) {
                Ok(()) => self.ack(c.seg.seq, Reject::Accepted, 0),
                Err(r) => {
                    let n = self.count_reject(r);
                    self.ack(c.seg.seq, r, n);
                }
            },
        }
    }

    // Out of line: rare (a plan's end, a stop's), and the tick's own code
    // must fit the ESC1's CCM SRAM.
    #[inline(never)]
    fn flush(&mut self) {
        self.queue.clear();
        self.flushes = self.flushes.wrapping_add(1);
        self.next_seq = 0;
        self.queued_end_ns = 0;
        self.ramps_cleared();
        self.dropped = NONE_DROPPED;
        self.prev_end = None;
        self.start_ns = None;
        self.stop_reason = None;
    }

    /// Enters Fault at once (not moving): Emergency frame, hold where we are.
    // Cold, out of line: the tick's own code must fit the ESC1's CCM SRAM.
    #[cold]
    #[inline(never)]
    fn fault_now(&mut self, code: FaultCode) {
        if let Some(h) = self.homing.take() {
            // Hold where the homing reference is.
            self.hold_own = h.q;
        }
        self.state = State::Fault;
        self.fault = code;
        self.start_ns = None;
        self.emergency(code);
        self.react_at_rest(code);
    }

    /// What the axis knows of itself for the fault reaction table.
    fn reaction_axis(&self) -> reaction::Axis {
        reaction::Axis {
            brake: self.cfg.brake != 0.0,
            gravity_loaded: self.cfg.gravity != 0.0,
            verified: self.verified,
        }
    }

    /// In Fault at rest: the reaction table's reaction at rest (Hold is
    /// what Fault does anyway).
    // Cold, out of line: the tick's own code must fit the ESC1's CCM SRAM.
    #[cold]
    #[inline(never)]
    fn react_at_rest(&mut self, code: FaultCode) {
        match reaction::reaction(code, false, self.reaction_axis()) {
            Reaction::TorqueOff => {
                self.torque_off = true;
                self.check = None;
            }
            Reaction::HoldOpenLoop => {
                self.open_loop = Some(self.static_torque());
                self.check = None;
            }
            Reaction::Hold | Reaction::StopOnPath => {}
        }
    }

    /// The motor torque that holds the axis still against gravity: the
    /// load the enable check measured; without one, the model's weight of
    /// the axis's share (its slider, half its strut, a third of the
    /// platform).
    fn static_torque(&self) -> f32 {
        self.measured_load
            .unwrap_or_else(|| Expected::of(&self.model).load)
    }

    /// The Emergency frame of a fault whose stop carries no ramp of its
    /// own (not moving, homing, a fault during another stop), at the last
    /// reference's plan time.
    // Cold, out of line: the tick's own code must fit the ESC1's CCM SRAM.
    #[cold]
    #[inline(never)]
    fn emergency(&mut self, code: FaultCode) {
        self.emergency_at(code, 0, self.plan_ns);
    }

    /// [`Drive::emergency`] for a stop along the path that begins at plan
    /// time `plan_ns` (rounded to the µs) and runs the ramp `ramp_100us`
    /// (0: the full one).
    #[cold]
    #[inline(never)]
    fn emergency_at(&mut self, code: FaultCode, ramp_100us: u16, plan_ns: i64) {
        let plan_us = ((plan_ns.max(0) + 500) / 1000) as u32;
        let e = Emergency {
            code: code as u8,
            state: self.state as u8,
            ramp_100us,
            plan_time_us: plan_us,
        };
        let f = e.to_frame(self.node_id);
        self.send_priority(f);
    }

    /// Begins a stop along the path from host time `t` (ns; Running only)
    /// for a reason of this node's own: a fault's stop runs the ramp the
    /// node vouches for ([`Drive::path_ramp`]), which its Emergency carries.
    // Cold, out of line: the tick's own code must fit the ESC1's CCM SRAM.
    #[cold]
    #[inline(never)]
    fn begin_stop(&mut self, reason: StopReason, quick: bool, t: i64) {
        let Some(a) = self.active else {
            return;
        };
        if self.state == State::Running {
            let (stop, quick_ns) = self.ramps_ns(&a);
            let full = if quick { quick_ns } else { stop };
            // A quick stop (Kinematics) runs its full quick ramp: the peers
            // take its Emergency as a controlled stop.
            let (ramp, carried) = match reason {
                StopReason::Fault(_) if !quick => self.path_ramp(t, full),
                _ => (full, 0),
            };
            self.begin_stop_ramp(reason, t, None, (ramp, full), carried);
        }
    }

    /// Begins a stop along the path from host time `t` (ns), with the
    /// slow-down the receive side sized if it did, and the ramp a Stop,
    /// QuickStop, FeedHold or a peer's Emergency carries for its instant
    /// (`dated_100us`, 0 for none): see [`Drive::dated_ramp_ns`]. `None`:
    /// a controlled stop dated by the host that carries no ramp (another
    /// process's): the ramp this node vouches for at that instant
    /// ([`Drive::path_ramp`]), the same on every node that holds the
    /// segments it passes through.
    // Cold, out of line: the tick's own code must fit the ESC1's CCM SRAM.
    #[cold]
    #[inline(never)]
    fn begin_stop_dated(
        &mut self,
        reason: StopReason,
        quick: bool,
        t: i64,
        ready: Option<&Retarget>,
        dated_100us: Option<u16>,
    ) {
        let Some(a) = self.active else {
            return;
        };
        if self.state == State::Running {
            let (stop, quick_ns) = self.ramps_ns(&a);
            let full = if quick { quick_ns } else { stop };
            let (ramp, carried) = match dated_100us {
                None if !quick => self.path_ramp(t, full),
                d => {
                    let d = d.unwrap_or(0);
                    let ramp = self.dated_ramp_ns(t, d, full, quick);
                    (ramp, if ramp < full { d } else { 0 })
                }
            };
            self.begin_stop_ramp(reason, t, ready, (ramp, full), carried);
        }
    }

    /// Slows to rest from host time `t` over `ramp` (ns) where the full
    /// ramp is `full`, Running only: a shorter one is a ramp for the path
    /// (σ̈ bang-bang, [`TimeScaling::begin_path_stop`]). A fault's Emergency
    /// carries `carried_100us`, the ramp it runs when shorter than the full
    /// one, for the peers to run too.
    // Inline: each caller is cold and out of line already.
    #[inline(always)]
    fn begin_stop_ramp(
        &mut self,
        reason: StopReason,
        t: i64,
        ready: Option<&Retarget>,
        (ramp, full): (i64, i64),
        carried_100us: u16,
    ) {
        // Where a fault's stop begins on the path, for the peers to date theirs.
        let s = match reason {
            StopReason::Fault(_) => self.scaling.at(t).s_ns,
            _ => 0,
        };
        if ramp < full {
            self.scaling.begin_path_stop(t, ramp);
        } else {
            self.scaling.retarget_ready(t, 0, ramp, ready);
        }
        self.stop_reason = Some(reason);
        if reason != StopReason::Hold {
            self.state = State::Stopping;
        }
        if let StopReason::Fault(code) = reason {
            self.fault = code;
            self.emergency_at(code, carried_100us, s);
        }
    }

    /// One control tick at local time `now_us`, in its parts: measure,
    /// supervise time and peers, trigger the start, generate the reference,
    /// run the control law, supervise the motion, command the motor, and
    /// queue the periodic frames.
    pub fn tick<E: Encoder, M: MotorOutput>(&mut self, now_us: u64, enc: &mut E, motor: &mut M) {
        self.tick_with_switch(now_us, enc, motor, &mut NoSwitch);
    }

    /// [`Drive::tick`] with the axis's limit switch (needed to home).
    pub fn tick_with_switch<E: Encoder, M: MotorOutput, S: LimitSwitch>(
        &mut self,
        now_us: u64,
        enc: &mut E,
        motor: &mut M,
        switch: &mut S,
    ) {
        self.last_local_us = now_us;
        self.switch_active = switch.active();
        let edge = switch.take_edge();
        self.stats.ticks = self.stats.ticks.wrapping_add(1);
        let Some(a) = self.active else {
            motor.enable(false);
            motor.set_torque(0.0);
            self.enabled = false;
            self.last_q = Some(to_f32(enc.read_counts()) * UNCONFIGURED_M_PER_COUNT);
            self.periodic(now_us);
            return;
        };
        if (self.torque_off || !self.enabled) && self.power_stage(enc, motor, now_us) {
            return;
        }
        let q = self.measure(&a, enc);
        let host = self.sync.host_ns(now_us);
        if let Some(code) = self.time_fault(&a, host.is_some(), now_us) {
            self.on_time_fault(code, now_us, a.sync_timeout_us);
        }
        let host_ns = host.unwrap_or(0);
        self.trigger_start(host_ns);
        let (reference, ff_ref) = self.reference(&a, host_ns);

        // Feedforward and PID on our own axis (`min` lets the compiler drop
        // the bounds checks: no panic path in the tick).
        let i = a.axis.min(2);
        let mut r_own = reference.q[i];
        // Homing, or slowing to rest from it after an Emergency (Stopping).
        if self.homing.is_some() {
            r_own = self.homing_step(&a, q, edge, now_us);
        }
        let mut ff = 0.0;
        if self.cfg.feedforward != 0.0 && self.hold.is_some() && self.homing.is_none() {
            match law::feedforward(&self.model, &self.cfg, &ff_ref, i) {
                Some(t) => ff = t,
                None => {
                    if matches!(self.state, State::Running) {
                        let t = self.sync.host_ns(now_us).unwrap_or(0);
                        self.begin_stop(StopReason::Fault(FaultCode::Kinematics), true, t);
                    }
                }
            }
        }
        let mut out = law::step(&mut self.law, &Gains::new(&self.cfg, &a), r_own, q, ff);
        if let Some(code) = self.motion_fault(out.error, q, r_own) {
            self.on_motion_fault(code, now_us);
        }
        // The enable check and the Fault state: rare, out of line.
        if self.check.is_some() || self.state == State::Fault {
            out.torque = self.check_and_fault(out.torque, out.error, q, a.dt, now_us);
        }
        motor.set_torque(out.torque * self.cfg.direction);

        self.stats.torque = out.torque;
        self.stats.following_error = out.error;
        self.stats.q = q;
        self.stats.v = self.vel;
        self.stats.reference = reference;
        self.periodic(now_us);
    }

    /// The power stage off (torque off by the fault reaction: the tick is
    /// done, true) or coming on (the brake releases: the loop starts afresh
    /// and the enable check begins).
    #[cold]
    #[inline(never)]
    fn power_stage<E: Encoder, M: MotorOutput>(
        &mut self,
        enc: &mut E,
        motor: &mut M,
        now_us: u64,
    ) -> bool {
        if self.torque_off {
            self.power_off(enc, motor, now_us);
            return true;
        }
        motor.enable(true);
        self.enabled = true;
        self.law.integral = 0.0;
        self.last_q = None;
        self.verified = false;
        self.measured_load = None;
        self.check = self.active.map(|a| EnableCheck::new(a.dt));
        false
    }

    /// A tick with the torque off by the fault reaction: power stage off,
    /// the position still measured and reported.
    fn power_off<E: Encoder, M: MotorOutput>(&mut self, enc: &mut E, motor: &mut M, now_us: u64) {
        motor.enable(false);
        motor.set_torque(0.0);
        self.enabled = false;
        let Some(a) = self.active else {
            return;
        };
        let q = self.measure(&a, enc);
        self.stats.torque = 0.0;
        self.stats.q = q;
        self.stats.v = self.vel;
        self.periodic(now_us);
    }

    /// Reads the encoder: our position (m), and the filtered velocity.
    fn measure<E: Encoder>(&mut self, a: &DerivedConfig, enc: &mut E) -> f32 {
        let q = to_f32(enc.read_counts().wrapping_sub(self.home_offset)) * a.inv_cpm;
        let raw_v = match self.last_q {
            Some(l) => (q - l) / a.dt,
            None => 0.0,
        };
        if self.last_q.is_none() {
            self.hold_own = q;
        }
        self.last_q = Some(q);
        self.vel += a.vel_alpha * (raw_v - self.vel);
        q
    }

    /// Buffered plan time ahead of the current plan time (ns), for tests and monitors.
    pub fn buffered_end_ns(&self) -> i64 {
        self.queued_end_ns
    }
}

#[cfg(test)]
mod outbox_tests {
    extern crate std;
    use super::*;

    /// Every message a node sends fits the outbox's 8 bytes a frame.
    #[test]
    fn a_nodes_messages_fit_the_outbox() {
        use triquint_shared::protocol::all_messages;
        let sent: std::vec::Vec<_> = all_messages()
            .into_iter()
            .filter(|m| m.sender == "node")
            .collect();
        assert!(sent.len() >= 7, "{}", sent.len());
        for m in sent {
            assert!(m.len <= 8 && !m.fd, "{} is {} bytes", m.name, m.len);
        }
        let long = Frame::with_payload(0x181, &[0; 12], true);
        let mut d: Drive = Drive::new(1);
        d.send(long);
        assert_eq!((d.outbox.len(), d.dropped_tx()), (0, 1));
    }

    /// A bus that takes nothing fills the outbox with routine frames; an
    /// Emergency still goes to its front, and the newest routine frame is
    /// the one counted dropped.
    #[test]
    fn an_emergency_finds_room_in_a_full_outbox() {
        let mut d: Drive = Drive::new(1);
        let routine = |k: u8| Frame::with_payload(0x701, &[k], false);
        for k in 0..OUTBOX as u8 + 2 {
            d.send(routine(k));
        }
        assert_eq!((d.outbox.len(), d.dropped_tx()), (OUTBOX, 2));
        d.emergency_at(FaultCode::FollowingError, 0, 0);
        assert_eq!(d.dropped_tx(), 3);
        let first = d.pop_tx().expect("a frame");
        assert_eq!(first.id, 0x010 + 1, "the Emergency first");
        let rest: std::vec::Vec<u8> = core::iter::from_fn(|| d.pop_tx())
            .map(|f| f.data[0])
            .collect();
        let kept: std::vec::Vec<u8> = (0..OUTBOX as u8 - 1).collect();
        assert_eq!(rest, kept, "the oldest routine frames kept, in order");
    }
}
