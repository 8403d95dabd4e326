//! The control side of a drive node: state machine, segment queue and
//! control tick, fed with finished items by the receive side (through the
//! hand-off types of the `inbox` module).

use heapless::Deque;
use nalgebra::Vector3;
use triquint_shared::Model;
use triquint_shared::protocol::{
    Command, CommandAck, CommandCode, DriveConfig, Emergency, FaultCode, Frame, Heartbeat,
    HeartbeatExt, PROTOCOL_VERSION, Reject, SegmentAck, State, Telemetry, TelemetryExt,
    config_value_frame,
};
use triquint_shared::quintic::JointMotion;

use triquint_shared::protocol::contract::{
    CONTINUITY_TOL, LIMIT_TOL, MAX_DURATION_US, MIN_HEARTBEAT_US, PEER_SKEW_MARGIN_US,
    REPEAT_WINDOW_US, UNCONFIGURED_HEARTBEAT_US, UNCONFIGURED_SYNC_TIMEOUT_US,
};

use crate::active::Active;
use crate::hal::{Encoder, MotorOutput};
use crate::inbox::{CheckedSegment, CommandData, Item, Prepared, Source, Status, TAKE_PER_TICK};
use crate::law::{self, Gains, LawState};
use crate::ns::{to_f32, to_i64};
use crate::scaling::{Phase, TimeScaling};
use crate::segment::{Seg, scale};
use crate::sync::SyncEstimator;

/// The feedforward is evaluated this many control periods ahead on the
/// path: the torque computed now acts from the next tick on, held for one.
pub const FF_LOOKAHEAD_TICKS: f32 = 1.5;
const FF_LOOKAHEAD_NS_PER_S: f32 = FF_LOOKAHEAD_TICKS * 1e9;
/// Encoder scale of a node without a configuration (m per count): only
/// for the position it reports before it has one.
pub const UNCONFIGURED_M_PER_COUNT: f32 = 1e-9;

/// Segment queue capacity of a node (segments).
pub const QUEUE_CAPACITY: usize = 8;
/// Frames waiting for the CAN controller.
pub const OUTBOX: usize = 64;

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
    pub ticks: u64,
}

/// The control side of one drive node, with a segment queue of capacity `Q`.
pub struct Drive<const Q: usize = QUEUE_CAPACITY> {
    node_id: u8,
    state: State,
    fault: FaultCode,
    active: Option<Active>,
    /// The committed configuration and its robot model (valid with `active`).
    cfg: DriveConfig,
    model: Model<f32>,
    queue: Deque<Seg, Q>,
    /// Queue flushes so far (the receive side then drops a partial segment).
    flushes: u32,
    next_seq: u16,
    queued_end_ns: i64,
    /// End motion (q, q', q'', q''') of the last accepted segment.
    prev_end: Option<JointMotion<f32>>,
    sync: SyncEstimator,
    scaling: TimeScaling,
    stop_reason: Option<StopReason>,
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
    next_heartbeat_us: u64,
    next_telemetry_us: u64,
    last_local_us: u64,
    errors: (u8, u8),
    outbox: Deque<Frame, OUTBOX>,
    dropped_tx: u32,
    /// The last command executed and its answer: a CAN frame can arrive twice
    /// (a transmitter that missed the ACK resends it), so a repeat of the
    /// same command, token and argument within [`REPEAT_WINDOW_US`] is
    /// answered again, not executed again.
    last_command: Option<(Command, CommandAck, u64)>,
    /// Receive time (µs) of the command being handled.
    command_rx_us: u64,
    /// Local time (µs) of the last heartbeat of each node (index node − 1).
    peer_seen_us: [Option<u64>; 3],
    pub stats: Stats,
}

/// The new segment starts where the previous one ended, in position (within
/// [`CONTINUITY_TOL`]) and in velocity, acceleration and jerk (within
/// [`LIMIT_TOL`] of the limits): C3 continuity.
fn c3_continuous(prev: &JointMotion<f32>, next: &JointMotion<f32>, cfg: &DriveConfig) -> bool {
    (prev.q - next.q).amax() <= CONTINUITY_TOL
        && (prev.qd - next.qd).amax() <= LIMIT_TOL * cfg.max_velocity
        && (prev.qdd - next.qdd).amax() <= LIMIT_TOL * cfg.max_acceleration
        && (prev.qddd - next.qddd).amax() <= LIMIT_TOL * cfg.max_jerk
}

fn seq_diff(a: u16, b: u16) -> i16 {
    a.wrapping_sub(b) as i16
}

impl<const Q: usize> Drive<Q> {
    /// A node with number `node_id` (1–3), Idle, unconfigured, motor off.
    pub fn new(node_id: u8) -> Self {
        Self {
            node_id,
            state: State::Idle,
            fault: FaultCode::None,
            active: None,
            cfg: DriveConfig::default(),
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
            prev_end: None,
            sync: SyncEstimator::default(),
            scaling: TimeScaling::nominal(0, 0),
            stop_reason: None,
            start_ns: None,
            current_seq: 0,
            plan_ns: 0,
            hold: None,
            hold_own: 0.0,
            law: LawState::default(),
            last_q: None,
            vel: 0.0,
            enabled: false,
            next_heartbeat_us: 0,
            next_telemetry_us: 0,
            last_local_us: 0,
            errors: (0, 0),
            outbox: Deque::new(),
            dropped_tx: 0,
            peer_seen_us: [None; 3],
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
    pub fn status(&self) -> Status {
        Status {
            config_crc: self.config_crc(),
            flushes: self.flushes,
            // Only a node with no motion pending may follow a new host time base.
            may_rebase: matches!(self.state, State::Idle | State::Fault),
        }
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
        self.outbox.front().copied()
    }
    pub fn pop_tx(&mut self) -> Option<Frame> {
        self.outbox.pop_front()
    }

    fn send(&mut self, f: Frame) {
        if self.outbox.push_back(f).is_err() {
            self.dropped_tx = self.dropped_tx.saturating_add(1);
        }
    }

    fn send_priority(&mut self, f: Frame) {
        if self.outbox.push_front(f).is_err() {
            self.dropped_tx = self.dropped_tx.saturating_add(1);
        }
    }

    // ---------------------------------------------------------------- frames

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
            Item::Emergency { code, rx_us } => self.on_emergency(code, rx_us),
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

    fn count_reject(&mut self, r: Reject) -> u8 {
        self.stats.rejects = self.stats.rejects.saturating_add(1);
        self.stats.last_reject = r as u8;
        let slot = self.stats.reason_counts.get_mut(r as usize);
        match slot {
            Some(c) => {
                *c = c.saturating_add(1);
                *c
            }
            None => 0,
        }
    }

    fn ack(&mut self, seq: u16, result: Reject, reason_count: u8) {
        let a = SegmentAck {
            seq,
            result: result as u8,
            depth: self.queue.len() as u8,
            next_seq: self.next_seq,
            capacity: Q as u8,
            reason_count,
        };
        let f = a.to_frame(self.node_id);
        self.send(f);
    }

    /// Files a checked segment: the cheap, state-dependent checks (state,
    /// sequence, queue room, C3 continuity with the previous segment) and
    /// its place in plan time. The receive side did the expensive ones.
    fn accept(&mut self, c: &CheckedSegment) -> Result<(), Reject> {
        if !matches!(
            self.state,
            State::Idle | State::Loaded | State::Armed | State::Running
        ) || self.active.is_none()
        {
            return Err(Reject::WrongState);
        }
        let seg = &c.seg;
        let d = seq_diff(seg.seq, self.next_seq);
        if d < 0 {
            return Err(Reject::Duplicate);
        }
        if d > 0 {
            return Err(Reject::OutOfOrder);
        }
        let max_ns = MAX_DURATION_US as i64 * 1000;
        if seg.duration_ns == 0 || seg.duration_ns > max_ns || seg.first != (seg.seq == 0) {
            return Err(Reject::Invalid);
        }
        if self.queue.is_full() {
            return Err(Reject::QueueFull);
        }
        // Checked against another configuration (a commit in between).
        if c.config_crc != self.config_crc() {
            return Err(Reject::WrongState);
        }
        c.verdict?;
        if let Some(prev) = self.prev_end
            && !seg.first
            && !c3_continuous(&prev, &c.begin, &self.cfg)
        {
            return Err(Reject::Discontinuous);
        }
        let start_ns = if seg.first { 0 } else { self.queued_end_ns };
        if self.queue.push_back(*seg).is_err() {
            return Err(Reject::QueueFull);
        }
        if let Some(s) = self.queue.back_mut() {
            s.start_ns = start_ns;
            self.queued_end_ns = s.end_ns();
        }
        self.prev_end = Some(c.end);
        self.next_seq = self.next_seq.wrapping_add(1);
        if self.state == State::Idle {
            self.state = State::Loaded;
        }
        Ok(())
    }

    fn flush(&mut self) {
        self.queue.clear();
        self.flushes = self.flushes.wrapping_add(1);
        self.next_seq = 0;
        self.queued_end_ns = 0;
        self.prev_end = None;
        self.start_ns = None;
        self.stop_reason = None;
    }

    fn command_ack(&mut self, c: &Command, result: FaultCode, value: u32) {
        let a = CommandAck {
            command: c.command,
            token: c.token,
            result: result as u8,
            state: self.state as u8,
            value,
        };
        self.last_command = Some((*c, a, self.command_rx_us));
        let f = a.to_frame(self.node_id);
        self.send(f);
    }

    /// Enters Fault at once (not moving): Emergency frame, hold where we are.
    fn fault_now(&mut self, code: FaultCode) {
        self.state = State::Fault;
        self.fault = code;
        self.start_ns = None;
        self.emergency(code);
    }

    fn emergency(&mut self, code: FaultCode) {
        let plan_us = (self.plan_ns.max(0) / 1000) as u32;
        let e = Emergency {
            code: code as u8,
            state: self.state as u8,
            segment: self.current_seq,
            plan_time_us: plan_us,
        };
        let f = e.to_frame(self.node_id);
        self.send_priority(f);
    }

    /// Begins a stop along the path (Running only); otherwise handles the
    /// reason directly.
    fn begin_stop(&mut self, reason: StopReason, quick: bool, local_us: u64) {
        let Some(a) = self.active else {
            return;
        };
        if self.state == State::Running {
            let ramp = if quick { a.quick_stop_ns } else { a.stop_ns };
            let t = self.sync.host_ns(local_us).unwrap_or(0);
            self.scaling.begin_decel(t, ramp);
            self.stop_reason = Some(reason);
            if reason != StopReason::Hold {
                self.state = State::Stopping;
            }
            if let StopReason::Fault(code) = reason {
                self.fault = code;
                self.emergency(code);
            }
        }
    }

    fn on_emergency(&mut self, code: FaultCode, local_us: u64) {
        match self.state {
            State::Running => self.begin_stop(StopReason::Fault(code), false, local_us),
            State::Stopping if !matches!(self.stop_reason, Some(StopReason::Fault(_))) => {
                self.stop_reason = Some(StopReason::Fault(code));
                self.fault = code;
            }
            State::Loaded | State::Armed => self.fault_now(code),
            State::Idle if code == FaultCode::HostEmergency => self.fault_now(code),
            _ => {}
        }
    }

    /// Peer supervision: a peer that reports a fault (its Emergency may have
    /// been lost) or has lost its configuration (it was reset) stops us too.
    fn on_peer_heartbeat(&mut self, node: u8, h: &Heartbeat, rx_us: u64) {
        let Some(slot) = (node as usize)
            .checked_sub(1)
            .and_then(|i| self.peer_seen_us.get_mut(i))
        else {
            return;
        };
        *slot = Some(rx_us);
        if self.state != State::Running {
            return;
        }
        let peer = h.state().ok();
        if !matches!(h.fault(), Ok(FaultCode::None | FaultCode::QuickStop)) {
            self.on_emergency(FaultCode::PeerEmergency, rx_us);
        } else if h.config_crc == 0 || self.peer_left_behind(peer, rx_us) {
            self.on_emergency(FaultCode::PeerLost, rx_us);
        }
    }

    /// A peer still Loaded or Armed (it missed the Start) well after we
    /// started, or Idle before our plan's last segment: it is not moving
    /// with us. The margins cover the start skew (one tick) and the end skew.
    fn peer_left_behind(&self, peer: Option<State>, local_us: u64) -> bool {
        const MARGIN_NS: i64 = PEER_SKEW_MARGIN_US as i64 * 1000;
        let (Some(t), Some(t0)) = (self.sync.host_ns(local_us), self.stats.started_at_ns) else {
            return false;
        };
        match peer {
            Some(State::Loaded | State::Armed) => t - t0 > MARGIN_NS,
            Some(State::Idle) => self
                .queue
                .back()
                .is_some_and(|b| !b.last || self.plan_ns + MARGIN_NS < b.end_ns()),
            _ => false,
        }
    }

    /// A peer (seen at least once) whose heartbeat has been missing for the
    /// sync timeout.
    fn peer_silent(&self, a: &Active, now_us: u64) -> bool {
        self.peer_seen_us
            .iter()
            .enumerate()
            .filter(|(i, _)| *i + 1 != self.node_id as usize)
            .any(|(_, t)| t.is_some_and(|t| now_us.saturating_sub(t) > a.sync_timeout_us))
    }

    // Not inlined into the tick: commands are rare, and the tick's own code
    // must fit the 10 KB of CCM SRAM on the ESC1 board.
    #[inline(never)]
    fn on_command(&mut self, c: &Command, local_us: u64, data: &CommandData) {
        self.command_rx_us = local_us;
        if let Some((last, ack, at)) = self.last_command
            && last == *c
            && local_us.saturating_sub(at) < REPEAT_WINDOW_US
        {
            let f = ack.to_frame(self.node_id);
            self.send(f);
            return;
        }
        let Ok(code) = c.command() else {
            self.command_ack(c, FaultCode::BadCommand, 0);
            return;
        };
        let r = match code {
            CommandCode::Arm => self.arm(local_us),
            CommandCode::Start => self.start(c.arg, local_us),
            CommandCode::Stop | CommandCode::QuickStop => {
                let quick = code == CommandCode::QuickStop;
                match self.state {
                    State::Running => {
                        self.begin_stop(StopReason::Commanded, quick, local_us);
                        FaultCode::None
                    }
                    State::Armed => {
                        self.state = State::Loaded;
                        self.start_ns = None;
                        FaultCode::None
                    }
                    _ => FaultCode::None,
                }
            }
            CommandCode::ClearFault => {
                if self.state == State::Fault {
                    self.flush();
                    self.state = State::Idle;
                    self.fault = FaultCode::None;
                    self.law.integral = 0.0;
                    FaultCode::None
                } else {
                    FaultCode::WrongState
                }
            }
            CommandCode::FeedHold => {
                if self.state == State::Running && self.scaling.phase != Phase::Rest {
                    self.begin_stop(StopReason::Hold, false, local_us);
                    FaultCode::None
                } else {
                    FaultCode::WrongState
                }
            }
            CommandCode::Resume => match (self.state, self.active) {
                (State::Running, Some(a)) if self.stop_reason == Some(StopReason::Hold) => {
                    let t = self.sync.host_ns(local_us).unwrap_or(0);
                    self.scaling.at(t);
                    self.scaling.begin_accel(t, a.stop_ns);
                    self.stop_reason = None;
                    FaultCode::None
                }
                _ => FaultCode::WrongState,
            },
            CommandCode::ConfigCommit => {
                let (r, crc) = match data {
                    CommandData::Commit { crc, config } => (self.commit(config), *crc),
                    _ => (FaultCode::ConfigMismatch, 0),
                };
                self.command_ack(c, r, crc);
                return;
            }
            CommandCode::Reset => match self.state {
                State::Idle | State::Loaded | State::Armed => {
                    self.flush();
                    self.state = State::Idle;
                    FaultCode::None
                }
                _ => FaultCode::WrongState,
            },
            CommandCode::ReadConfig => {
                if let CommandData::Values(values) = data {
                    for (i, v) in values.iter().enumerate() {
                        let f = config_value_frame(self.node_id, i as u8, *v);
                        self.send(f);
                    }
                }
                FaultCode::None
            }
        };
        self.command_ack(c, r, 0);
    }

    /// Runs a configuration the receive side prepared (Idle only).
    fn commit(&mut self, config: &Result<Prepared, FaultCode>) -> FaultCode {
        if self.state != State::Idle {
            return FaultCode::WrongState;
        }
        let p = match config {
            Ok(p) => p,
            Err(code) => return *code,
        };
        self.cfg = p.cfg;
        self.model = p.model;
        self.active = Some(p.active);
        FaultCode::None
    }

    fn arm(&mut self, local_us: u64) -> FaultCode {
        if self.state != State::Loaded {
            return FaultCode::WrongState;
        }
        let Some(a) = self.active else {
            self.fault_now(FaultCode::NoConfig);
            return FaultCode::NoConfig;
        };
        if !self.sync.is_synced(local_us, a.sync_timeout_us) {
            self.fault_now(FaultCode::NotSynced);
            return FaultCode::NotSynced;
        }
        let Some(front) = self.queue.front().copied() else {
            self.fault_now(FaultCode::EmptyQueue);
            return FaultCode::EmptyQueue;
        };
        if !front.first {
            self.fault_now(FaultCode::EmptyQueue);
            return FaultCode::EmptyQueue;
        }
        let start = front.start_q();
        let own = start[a.axis.min(2)];
        match self.last_q {
            Some(q) if (q - own).abs() <= self.cfg.arm_tolerance => {}
            _ => {
                self.fault_now(FaultCode::ArmTooFar);
                return FaultCode::ArmTooFar;
            }
        }
        self.hold = Some(start);
        self.hold_own = own;
        self.state = State::Armed;
        FaultCode::None
    }

    fn start(&mut self, arg: u32, local_us: u64) -> FaultCode {
        if self.state != State::Armed {
            return FaultCode::WrongState;
        }
        let Some(now) = self.sync.host_us(local_us) else {
            self.fault_now(FaultCode::NotSynced);
            return FaultCode::NotSynced;
        };
        let d = arg.wrapping_sub(now as u32) as i32 as i64;
        if d < 0 {
            self.fault_now(FaultCode::StartInPast);
            return FaultCode::StartInPast;
        }
        self.start_ns = Some((now + d) * 1000);
        FaultCode::None
    }

    // ---------------------------------------------------------------- control

    /// One control tick at local time `now_us`, in its parts: measure,
    /// supervise time and peers, trigger the start, generate the reference,
    /// run the control law, supervise the motion, command the motor, and
    /// queue the periodic frames.
    pub fn tick<E: Encoder, M: MotorOutput>(&mut self, now_us: u64, enc: &mut E, motor: &mut M) {
        self.last_local_us = now_us;
        self.stats.ticks = self.stats.ticks.wrapping_add(1);
        let Some(a) = self.active else {
            motor.enable(false);
            motor.set_torque(0.0);
            self.enabled = false;
            self.last_q = Some(to_f32(enc.read_counts()) * UNCONFIGURED_M_PER_COUNT);
            self.periodic(now_us);
            return;
        };
        if !self.enabled {
            motor.enable(true);
            self.enabled = true;
            self.law.integral = 0.0;
            self.last_q = None;
        }
        let q = self.measure(&a, enc);
        let host = self.sync.host_ns(now_us);
        if let Some(code) = self.time_fault(&a, host.is_some(), now_us) {
            self.on_time_fault(code, now_us);
        }
        let host_ns = host.unwrap_or(0);
        self.trigger_start(host_ns);
        let (reference, ff_ref) = self.reference(&a, host_ns);

        // Feedforward and PID on our own axis (`min` lets the compiler drop
        // the bounds checks: no panic path in the tick).
        let i = a.axis.min(2);
        let mut ff = 0.0;
        if self.cfg.feedforward != 0.0 && self.hold.is_some() {
            match law::feedforward(&self.model, &self.cfg, &ff_ref, i) {
                Some(t) => ff = t,
                None => {
                    if matches!(self.state, State::Running) {
                        self.begin_stop(StopReason::Fault(FaultCode::Kinematics), true, now_us);
                    }
                }
            }
        }
        let out = law::step(
            &mut self.law,
            &Gains::new(&self.cfg, &a),
            reference.q[i],
            q,
            ff,
        );
        if let Some(code) = self.motion_fault(out.error, q) {
            self.begin_stop(StopReason::Fault(code), false, now_us);
        }
        motor.set_torque(out.torque * self.cfg.direction);

        self.stats.torque = out.torque;
        self.stats.following_error = out.error;
        self.stats.q = q;
        self.stats.v = self.vel;
        self.stats.reference = reference;
        self.periodic(now_us);
    }

    /// Reads the encoder: our position (m), and the filtered velocity.
    fn measure<E: Encoder>(&mut self, a: &Active, enc: &mut E) -> f32 {
        let q = to_f32(enc.read_counts()) * a.inv_cpm;
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

    /// Supervision of the time base and the peers: the fault it calls for, if any.
    fn time_fault(&self, a: &Active, has_host_time: bool, now_us: u64) -> Option<FaultCode> {
        let lost = self.sync.lost(now_us, a.sync_timeout_us) || !has_host_time;
        if lost && matches!(self.state, State::Armed | State::Running) {
            Some(FaultCode::LostSync)
        } else if self.state == State::Running && self.peer_silent(a, now_us) {
            Some(FaultCode::PeerLost)
        } else {
            None
        }
    }

    fn on_time_fault(&mut self, code: FaultCode, now_us: u64) {
        match self.state {
            State::Armed => self.fault_now(code),
            // Without a time base, keep stepping on the local clock.
            _ => self.begin_stop(StopReason::Fault(code), false, now_us),
        }
    }

    /// Armed with a start time that has come: Running from its plan time 0.
    fn trigger_start(&mut self, host_ns: i64) {
        if self.state == State::Armed
            && let Some(t0) = self.start_ns
            && host_ns >= t0
        {
            self.state = State::Running;
            self.scaling = TimeScaling::nominal(t0, 0);
            self.stop_reason = None;
            self.stats.started_at_ns = Some(host_ns);
        }
    }

    /// The position reference now, and the motion the feedforward is taken
    /// from: on the path when Running or Stopping, else the hold pose.
    fn reference(&mut self, a: &Active, host_ns: i64) -> (JointMotion<f32>, JointMotion<f32>) {
        let moving = matches!(self.state, State::Running | State::Stopping);
        let reference = if moving {
            self.path_reference(a, host_ns)
        } else {
            None
        };
        let reference = match reference {
            Some(r) => r,
            None => self.hold_reference(),
        };
        // The torque computed now acts from the next tick on (and is held for
        // one tick): evaluate the feedforward 1.5 ticks ahead on the path.
        let ff_ref = if matches!(self.state, State::Running | State::Stopping) {
            self.lookahead(host_ns + to_i64(FF_LOOKAHEAD_NS_PER_S * a.dt))
                .unwrap_or(reference)
        } else {
            reference
        };
        (reference, ff_ref)
    }

    /// Supervision of the motion (Running): following error beyond its
    /// bound, or a measured position outside the soft limits (accepted
    /// segments stay inside them: a runaway axis), stopped along the path.
    fn motion_fault(&self, error: f32, q: f32) -> Option<FaultCode> {
        if self.state != State::Running {
            None
        } else if error.abs() > self.cfg.following_error_max {
            Some(FaultCode::FollowingError)
        } else if !(q >= self.cfg.soft_limit_min && q <= self.cfg.soft_limit_max) {
            Some(FaultCode::SoftLimit)
        } else {
            None
        }
    }

    fn hold_reference(&self) -> JointMotion<f32> {
        let mut m = JointMotion::default();
        if let Some(h) = self.hold {
            m.q = h;
        }
        if let Some(a) = &self.active {
            m.q[a.axis.min(2)] = self.hold_own;
        }
        m
    }

    /// The path motion at host time `host_ns` without changing any state.
    fn lookahead(&self, host_ns: i64) -> Option<JointMotion<f32>> {
        let mut sc = self.scaling;
        let sc = sc.at(host_ns);
        let seg = self
            .queue
            .iter()
            .find(|g| sc.s_ns < g.end_ns())
            .or_else(|| self.queue.back())?;
        Some(scale(&seg.eval(sc.s_ns), sc.sigma, sc.sigma_d, sc.sigma_dd))
    }

    /// Reference on the path (Running/Stopping); handles queue advance, the
    /// end of the plan, the end of a stop and underrun.
    fn path_reference(&mut self, a: &Active, host_ns: i64) -> Option<JointMotion<f32>> {
        let sc = self.scaling.at(host_ns);
        while self.queue.len() > 1 {
            match self.queue.front() {
                Some(f) if sc.s_ns >= f.end_ns() => {
                    self.queue.pop_front();
                }
                _ => break,
            }
        }
        // Read the front in place (a copy of a segment costs the tick ~100 instructions).
        let front = self.queue.front()?;
        let path = front.eval(sc.s_ns);
        let (front_last, front_end_ns) = (front.last, front.end_ns());
        self.current_seq = front.seq;
        self.plan_ns = sc.s_ns;
        let m = scale(&path, sc.sigma, sc.sigma_d, sc.sigma_dd);
        self.hold = Some(m.q);
        self.hold_own = m.q[a.axis.min(2)];

        let at_rest = self.scaling.phase == Phase::Rest;
        let last_queued = self.queue.back().map(|b| b.last).unwrap_or(false);
        if self.state == State::Stopping && at_rest {
            match self.stop_reason {
                Some(StopReason::Fault(code)) => {
                    self.state = State::Fault;
                    self.fault = code;
                    self.queue.clear();
                }
                _ => {
                    self.flush();
                    self.state = State::Idle;
                }
            }
            return Some(m);
        }
        if self.state == State::Running {
            if front_last && sc.s_ns >= front_end_ns {
                // Plan complete: hold the end.
                self.flush();
                self.state = State::Idle;
                return Some(m);
            }
            let ahead = self.queued_end_ns - sc.s_ns;
            let need = TimeScaling::stop_distance_ns(a.stop_ns) + a.margin_ns;
            if !last_queued
                && matches!(self.scaling.phase, Phase::Nominal | Phase::Accel)
                && ahead < need
            {
                self.begin_stop(
                    StopReason::Fault(FaultCode::Underrun),
                    false,
                    self.last_local_us,
                );
            }
        }
        Some(m)
    }

    fn periodic(&mut self, now_us: u64) {
        let (hb_us, tel_us) = match &self.active {
            Some(a) => (a.heartbeat_us.max(MIN_HEARTBEAT_US), a.telemetry_us),
            None => (UNCONFIGURED_HEARTBEAT_US, 0),
        };
        if now_us >= self.next_heartbeat_us {
            self.next_heartbeat_us = now_us + hb_us;
            let hb = Heartbeat {
                state: self.state as u8,
                fault: self.fault as u8,
                queue_depth: self.queue.len() as u8,
                protocol_version: PROTOCOL_VERSION,
                config_crc: self.config_crc(),
            };
            let f = hb.to_frame(self.node_id);
            self.send(f);
            let timeout = self
                .active
                .as_ref()
                .map(|a| a.sync_timeout_us)
                .unwrap_or(UNCONFIGURED_SYNC_TIMEOUT_US);
            let ext = HeartbeatExt {
                next_seq: self.next_seq,
                rejects: self.stats.rejects,
                tx_errors: self.errors.0,
                rx_errors: self.errors.1,
                last_reject: self.stats.last_reject,
                sync_ok: self.sync.is_synced(now_us, timeout) as u8,
            };
            let f = ext.to_frame(self.node_id);
            self.send(f);
            // At most one group of periodic frames per tick (bounds the
            // tick's worst case): telemetry due now goes out next tick.
            return;
        }
        if tel_us > 0 && now_us >= self.next_telemetry_us {
            self.next_telemetry_us = now_us + tel_us;
            let t = Telemetry {
                position: self.stats.q,
                velocity: self.stats.v,
            };
            let f = t.to_frame(self.node_id);
            self.send(f);
            let t = TelemetryExt {
                torque: self.stats.torque,
                following_error: self.stats.following_error,
            };
            let f = t.to_frame(self.node_id);
            self.send(f);
        }
    }

    /// Buffered plan time ahead of the current plan time (ns), for tests and monitors.
    pub fn buffered_end_ns(&self) -> i64 {
        self.queued_end_ns
    }
}
