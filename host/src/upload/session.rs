//! The upload session state machine.

use std::collections::VecDeque;

use triquint_shared::plan::Plan;
use triquint_shared::protocol::segment::SegmentError;
use triquint_shared::protocol::{
    Command, CommandCode, DriveConfig, FaultCode, Frame, Msg, PARAM_COUNT, PARAMS, Reject, State,
    TimeSync, WireSegment, config_write_frame, decode,
};

use super::{CanPort, PortError, Received};

/// Timing and policy of a session.
#[derive(Clone, Debug, PartialEq)]
pub struct SessionOptions {
    pub fd: bool,
    /// Write the configuration before checking it (else only check).
    pub configure: bool,
    /// Most segments unacknowledged at once.
    pub window: usize,
    pub retransmit_timeout_us: u64,
    pub max_retransmits: u32,
    pub sync_period_us: u64,
    /// Sync period until every node reports a valid sync.
    pub fast_sync_period_us: u64,
    /// Start time ahead of the Start command.
    pub start_lead_us: u64,
    /// Waiting for nodes (heartbeats, acknowledgements).
    pub response_timeout_us: u64,
    /// A set-up command (configuration, Arm) not answered within this is
    /// sent again: a configuration refused or unanswered at most
    /// `setup_resends` times, Arm at most twice (see [`ARM_RESENDS`]).
    pub setup_retry_us: u64,
    pub setup_resends: u32,
    /// After the plan's end, how long nodes may take to report Idle.
    pub finish_grace_us: u64,
    /// Test hook: stop streaming after this many segments (provokes underrun).
    pub stall_after: Option<usize>,
    /// Only configure the nodes (and check the configuration), no motion.
    pub configure_only: bool,
}

impl Default for SessionOptions {
    fn default() -> Self {
        Self {
            fd: false,
            configure: true,
            window: 4,
            retransmit_timeout_us: 50_000,
            max_retransmits: 5,
            sync_period_us: 100_000,
            fast_sync_period_us: 10_000,
            start_lead_us: 50_000,
            response_timeout_us: 2_000_000,
            setup_retry_us: 30_000,
            setup_resends: 4,
            finish_grace_us: 5_000_000,
            stall_after: None,
            configure_only: false,
        }
    }
}

/// Progress of a session.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Progress {
    pub phase: &'static str,
    /// Segments every node has acknowledged.
    pub segments_acked: usize,
    pub segments: usize,
    /// Start command sent.
    pub started: bool,
    /// Plan duration (µs).
    pub plan_end_us: u64,
}

/// A fault a node reported (Emergency frame or heartbeat).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultReport {
    pub node: u8,
    pub code: FaultCode,
    /// Host time (µs) the report arrived.
    pub t_us: u64,
}

/// Why an upload cannot go on.
#[derive(Debug, thiserror::Error)]
pub enum UploadError {
    #[error(transparent)]
    Port(#[from] PortError),
    #[error("segment {seq}: {source}")]
    Segment {
        seq: usize,
        #[source]
        source: SegmentError,
    },
    #[error("node {node}: no answer while {what}")]
    Timeout { node: u8, what: &'static str },
    #[error(
        "node {node}: configuration differs from the plan's: `{param}` is {node_value} on the node, {plan_value} in the plan"
    )]
    ConfigMismatch {
        node: u8,
        param: &'static str,
        node_value: f32,
        plan_value: f32,
    },
    #[error(
        "node {node}: configuration CRC 0x{node_crc:08X} differs from the plan's 0x{plan_crc:08X}"
    )]
    ConfigCrc {
        node: u8,
        node_crc: u32,
        plan_crc: u32,
    },
    #[error("node {node}: protocol version {got}, expected {want}")]
    Version { node: u8, got: u8, want: u8 },
    #[error("node {node} rejected segment {seq}: {reason}")]
    Rejected {
        node: u8,
        seq: u16,
        reason: &'static str,
    },
    #[error("segment {seq}: not acknowledged by node {node} after {tries} transmissions")]
    Retransmits { node: u8, seq: usize, tries: u32 },
    #[error("node {node} refused {command}: {code}")]
    Refused {
        node: u8,
        command: &'static str,
        code: &'static str,
    },
}

impl UploadError {
    /// Is this the plan's or the machine's configuration (bad input, exit 2)?
    pub fn is_config(&self) -> bool {
        matches!(
            self,
            UploadError::ConfigMismatch { .. } | UploadError::ConfigCrc { .. }
        )
    }
    /// Is this a motion fault (exit 5)?
    pub fn is_motion_fault(&self) -> bool {
        matches!(self, UploadError::Refused { .. })
    }
}

/// How a session ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Outcome {
    pub completed: bool,
    pub faults: Vec<FaultReport>,
    /// Host time (µs) of the start.
    pub start_us: u64,
    pub frames_sent: u64,
    pub segment_frames_sent: u64,
    pub retransmits: u64,
    pub rejects_seen: u64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Phase {
    Discover,
    Configure,
    VerifyConfig,
    ReadBack,
    Sync,
    Fill,
    Arm,
    Stream,
    Finish,
    Done,
}

#[derive(Clone, Copy, Debug, Default)]
struct NodeView {
    heartbeat_at: Option<u64>,
    state: Option<State>,
    fault: u8,
    config_crc: u32,
    version: u8,
    sync_ok: bool,
    sync_seen_at: Option<u64>,
    next_seq: u16,
    depth: u8,
    capacity: u8,
    last_ack: Option<(u8, u8, u8, u32)>, // (command, token, result, value)
}

#[derive(Clone, Debug)]
struct InFlight {
    seq: usize,
    sent_at: u64,
    tries: u32,
    acked: [bool; 3],
    /// Resend requested by a rejection (not counted as a try).
    early: bool,
}

/// One upload of one plan to the three nodes.
pub struct Session {
    opts: SessionOptions,
    segments: Vec<WireSegment>,
    configs: [DriveConfig; 3],
    plan_end_us: u64,
    phase: Phase,
    phase_since: u64,
    nodes: [NodeView; 3],
    out: VecDeque<Frame>,
    token: u8,
    sync_seq: u8,
    next_sync_us: u64,
    last_sync_tx_us: u32,
    next_to_send: usize,
    in_flight: Vec<InFlight>,
    readback: Option<(u8, [Option<f32>; PARAM_COUNT])>,
    /// Per node: token of the latest ConfigCommit, when it went out, resends.
    commit: [(u8, u64, u32); 3],
    /// Token of the Arm, when it last went out, resends.
    arm: (u8, u64, u32),
    /// Token of the Start, when it last went out.
    start_cmd: (u8, u64),
    start_us: u64,
    faults: Vec<FaultReport>,
    frames_sent: u64,
    segment_frames: u64,
    retransmits: u64,
    rejects_seen: u64,
}

/// Arm resends, `setup_retry_us` apart: all within the drives' 100 ms
/// repeat window of the first, so a drive that did arm (its answer lost)
/// answers again instead of executing Arm twice (which it would refuse).
pub const ARM_RESENDS: u32 = 2;

/// Start resends to a drive that has not answered, this far apart, only
/// before the start time (`start_lead_us` after the first) and within the
/// repeat window: a drive that missed Start would stop every axis (`PeerLost`).
const START_RETRY_US: u64 = 10_000;

/// A segment is resent on a rejection only if its last transmission is older
/// than this: a full window of classic segments takes about 11 ms on the wire.
const RESEND_GUARD_US: u64 = 15_000;

fn node_index(node: u8) -> Option<usize> {
    (1..=3).contains(&node).then(|| node as usize - 1)
}

impl Session {
    /// A session for `plan` with the given per-node configurations.
    pub fn new(
        plan: &Plan,
        configs: [DriveConfig; 3],
        opts: SessionOptions,
    ) -> Result<Self, UploadError> {
        let segments = plan
            .wire_segments()
            .map_err(|(seq, source)| UploadError::Segment { seq, source })?;
        Ok(Self::with_segments(segments, configs, opts))
    }

    /// A session that only writes and checks the configurations (no motion):
    /// drives report their position once configured.
    pub fn configure(configs: [DriveConfig; 3], mut opts: SessionOptions) -> Self {
        opts.configure_only = true;
        Self::with_segments(Vec::new(), configs, opts)
    }

    fn with_segments(
        segments: Vec<WireSegment>,
        configs: [DriveConfig; 3],
        opts: SessionOptions,
    ) -> Self {
        let plan_end_us = segments.iter().map(|s| s.duration_us as u64).sum();
        Self {
            opts,
            segments,
            configs,
            plan_end_us,
            phase: Phase::Discover,
            phase_since: 0,
            nodes: [NodeView::default(); 3],
            out: VecDeque::new(),
            token: 0,
            sync_seq: 0,
            next_sync_us: 0,
            last_sync_tx_us: 0,
            next_to_send: 0,
            in_flight: Vec::new(),
            readback: None,
            commit: [(0, 0, 0); 3],
            arm: (0, 0, 0),
            start_cmd: (0, 0),
            start_us: 0,
            faults: Vec::new(),
            frames_sent: 0,
            segment_frames: 0,
            retransmits: 0,
            rejects_seen: 0,
        }
    }

    pub fn faults(&self) -> &[FaultReport] {
        &self.faults
    }

    /// The segments as they go on the wire, in order.
    pub fn segments(&self) -> &[WireSegment] {
        &self.segments
    }

    /// Segments retransmitted so far.
    pub fn retransmits(&self) -> u64 {
        self.retransmits
    }

    /// Host time (µs) of the start (0 before).
    pub fn start_us(&self) -> u64 {
        self.start_us
    }

    /// Where the session is, for progress displays.
    pub fn progress(&self) -> Progress {
        let acked = self.next_to_send.saturating_sub(self.in_flight.len());
        Progress {
            phase: match self.phase {
                Phase::Discover => "waiting for heartbeats",
                Phase::Configure => "configuring",
                Phase::VerifyConfig | Phase::ReadBack => "checking the configuration",
                Phase::Sync => "synchronising clocks",
                Phase::Fill => "filling the queues",
                Phase::Arm => "arming",
                Phase::Stream => "running, streaming",
                Phase::Finish => "running",
                Phase::Done => "done",
            },
            segments_acked: acked,
            segments: self.segments.len(),
            started: self.start_us != 0,
            plan_end_us: self.plan_end_us,
        }
    }

    /// Last reported state and fault code of nodes 1–3 (`None`: never heard).
    pub fn node_states(&self) -> [(Option<State>, u8); 3] {
        self.nodes.map(|v| (v.state, v.fault))
    }

    fn command(&mut self, node: u8, code: CommandCode, arg: u32) -> u8 {
        self.token = self.token.wrapping_add(1);
        let c = Command {
            command: code as u8,
            token: self.token,
            arg,
        };
        self.out.push_back(c.to_frame(node));
        self.token
    }

    /// Writes node `i`'s configuration and commits it (a new token each
    /// time); `resends` counts the earlier attempts.
    fn send_config(&mut self, i: usize, now: u64, resends: u32) {
        self.write_config(i);
        self.commit_config(i, now, resends);
    }

    fn write_config(&mut self, i: usize) {
        for (k, val) in self.configs[i].to_values().iter().enumerate() {
            self.out
                .push_back(config_write_frame(i as u8 + 1, k as u8, *val));
        }
    }

    fn commit_config(&mut self, i: usize, now: u64, resends: u32) {
        let token = self.command(
            i as u8 + 1,
            CommandCode::ConfigCommit,
            self.configs[i].crc(),
        );
        self.commit[i] = (token, now, resends);
    }

    /// Configure phase: `Ok(true)` once every node committed its
    /// configuration. A commit refused (a configuration write was lost) or
    /// not answered is sent again, configuration and all, up to
    /// `setup_resends` times.
    fn configured(&mut self, now: u64) -> Result<bool, UploadError> {
        let mut done = 0;
        for i in 0..3 {
            let (token, sent_at, resends) = self.commit[i];
            let can_resend = resends < self.opts.setup_resends;
            match self.nodes[i].last_ack {
                Some((c, _, 0, _)) if c == CommandCode::ConfigCommit as u8 => done += 1,
                // The latest commit was refused.
                Some((c, t, _, crc)) if c == CommandCode::ConfigCommit as u8 && t == token => {
                    if !can_resend {
                        return Err(UploadError::ConfigCrc {
                            node: i as u8 + 1,
                            node_crc: crc,
                            plan_crc: self.configs[i].crc(),
                        });
                    }
                    self.send_config(i, now, resends + 1);
                }
                _ if can_resend && now.saturating_sub(sent_at) > self.opts.setup_retry_us => {
                    self.send_config(i, now, resends + 1);
                }
                _ => {}
            }
        }
        Ok(done == 3)
    }

    /// Start again (same token) to each drive that has not answered it,
    /// while the start time is ahead.
    fn resend_start(&mut self, now: u64) {
        let (token, sent_at) = self.start_cmd;
        if now + START_RETRY_US >= self.start_us || now.saturating_sub(sent_at) < START_RETRY_US {
            return;
        }
        let acks = self.acks_for(token);
        for i in (0..3).filter(|&i| acks[i].is_none()) {
            let c = Command {
                command: CommandCode::Start as u8,
                token,
                arg: self.start_us as u32,
            };
            self.out.push_front(c.to_frame(i as u8 + 1));
        }
        self.start_cmd.1 = now;
    }

    fn set_phase(&mut self, p: Phase, now: u64) {
        self.phase = p;
        self.phase_since = now;
    }

    fn handle(&mut self, rx: &Received) -> Result<(), UploadError> {
        if rx.own {
            if rx.frame.id == TimeSync::DEF.addr.id(0) {
                self.last_sync_tx_us = rx.t_us as u32;
            }
            return Ok(());
        }
        let Ok((msg, node)) = decode(&rx.frame) else {
            return Ok(());
        };
        let Some(i) = node_index(node) else {
            return Ok(());
        };
        let v = &mut self.nodes[i];
        match msg {
            Msg::Heartbeat(h) => {
                v.heartbeat_at = Some(rx.t_us);
                v.state = State::from_u8(h.state);
                v.fault = h.fault;
                v.config_crc = h.config_crc;
                v.version = h.protocol_version;
                v.depth = h.queue_depth;
                if h.fault != 0 && !self.faults.iter().any(|f| f.node == node) {
                    self.faults.push(FaultReport {
                        node,
                        code: FaultCode::from_u8(h.fault).unwrap_or(FaultCode::None),
                        t_us: rx.t_us,
                    });
                }
            }
            Msg::HeartbeatExt(h) => {
                v.sync_ok = h.sync_ok != 0;
                v.sync_seen_at = Some(rx.t_us);
                v.next_seq = h.next_seq;
            }
            Msg::SegmentAck(a) => {
                v.next_seq = a.next_seq;
                v.depth = a.depth;
                v.capacity = a.capacity;
                let reason = Reject::from_u8(a.result);
                match reason {
                    Some(Reject::Accepted) | Some(Reject::Duplicate) => {
                        if let Some(f) = self.in_flight.iter_mut().find(|f| f.seq == a.seq as usize)
                        {
                            f.acked[i] = true;
                        }
                    }
                    Some(Reject::BadCrc | Reject::OutOfOrder | Reject::Incomplete) => {
                        self.rejects_seen += 1;
                        // Resend at once the segment this node needs next (the
                        // rejected one may only be queued behind a lost one),
                        // unless it went out moments ago and may be on its way.
                        // A resend on a rejection is not a timeout: it does not
                        // use up the segment's tries.
                        let need = a.next_seq as usize;
                        if let Some(f) = self.in_flight.iter_mut().find(|f| f.seq == need)
                            && !f.acked[i]
                            && rx.t_us.saturating_sub(f.sent_at) > RESEND_GUARD_US
                        {
                            f.sent_at = 0;
                            f.early = true;
                        }
                    }
                    Some(Reject::QueueFull) => {
                        self.rejects_seen += 1;
                    }
                    other => {
                        return Err(UploadError::Rejected {
                            node,
                            seq: a.seq,
                            reason: other.map_or("unknown reason", |r| r.name()),
                        });
                    }
                }
            }
            Msg::CommandAck(a) => v.last_ack = Some((a.command, a.token, a.result, a.value)),
            Msg::Emergency(e) => {
                self.faults.push(FaultReport {
                    node,
                    code: FaultCode::from_u8(e.code).unwrap_or(FaultCode::None),
                    t_us: rx.t_us,
                });
            }
            Msg::ConfigValue { index, value } => {
                if let Some((n, vals)) = &mut self.readback
                    && *n == node
                    && let Some(slot) = vals.get_mut(index as usize)
                {
                    *slot = Some(value);
                }
            }
            _ => {}
        }
        Ok(())
    }

    fn acks_for(&self, token: u8) -> [Option<u8>; 3] {
        self.nodes.map(|v| match v.last_ack {
            Some((_, t, r, _)) if t == token => Some(r),
            _ => None,
        })
    }

    fn timeout(
        &self,
        now: u64,
        what: &'static str,
        missing: impl Fn(usize) -> bool,
    ) -> Result<(), UploadError> {
        if now.saturating_sub(self.phase_since) > self.opts.response_timeout_us {
            let node = (0..3).find(|&i| missing(i)).map_or(1, |i| i as u8 + 1);
            return Err(UploadError::Timeout { node, what });
        }
        Ok(())
    }

    /// Credit: highest sequence number (exclusive) every node can take now.
    fn credit(&self) -> usize {
        self.nodes
            .iter()
            .map(|v| {
                let cap = if v.capacity == 0 {
                    1
                } else {
                    v.capacity as usize
                };
                (v.next_seq as usize).saturating_sub(v.depth as usize) + cap
            })
            .min()
            .unwrap_or(0)
    }

    fn queue_segment(&mut self, seq: usize) {
        if let Some(s) = self.segments.get(seq) {
            for f in s.frames(self.opts.fd) {
                self.out.push_back(f);
                self.segment_frames += 1;
            }
        }
    }

    fn stream(&mut self, now: u64) -> Result<(), UploadError> {
        self.in_flight.retain(|f| !f.acked.iter().all(|a| *a));
        // Retransmissions.
        for k in 0..self.in_flight.len() {
            let f = &self.in_flight[k];
            if now.saturating_sub(f.sent_at) > self.opts.retransmit_timeout_us
                && self.out.len() < 64
            {
                if f.tries > self.opts.max_retransmits {
                    let node = (0..3).find(|&i| !f.acked[i]).map_or(1, |i| i as u8 + 1);
                    return Err(UploadError::Retransmits {
                        node,
                        seq: f.seq,
                        tries: f.tries,
                    });
                }
                let seq = f.seq;
                if !f.early {
                    self.in_flight[k].tries += 1;
                }
                self.in_flight[k].early = false;
                self.in_flight[k].sent_at = now;
                self.retransmits += 1;
                self.queue_segment(seq);
            }
        }
        let limit = self
            .opts
            .stall_after
            .unwrap_or(usize::MAX)
            .min(self.segments.len());
        while self.next_to_send < limit
            && self.in_flight.len() < self.opts.window
            && self.next_to_send < self.credit()
            && self.out.len() < 64
        {
            let seq = self.next_to_send;
            self.queue_segment(seq);
            self.in_flight.push(InFlight {
                seq,
                sent_at: now,
                tries: 1,
                acked: [false; 3],
                early: false,
            });
            self.next_to_send += 1;
        }
        Ok(())
    }

    fn all_acked_through(&self, n: usize) -> bool {
        self.next_to_send >= n && self.in_flight.iter().all(|f| f.seq >= n)
    }

    /// Advances the session; `Ok(Some(outcome))` when finished.
    pub fn poll<P: CanPort>(&mut self, port: &mut P) -> Result<Option<Outcome>, UploadError> {
        let now = port.now_us();
        while let Some(rx) = port.recv()? {
            self.handle(&rx)?;
        }
        // Time sync, fast until every node is synced.
        if now >= self.next_sync_us {
            self.sync_seq = self.sync_seq.wrapping_add(1);
            let s = TimeSync {
                seq: self.sync_seq,
                prev_tx_us: self.last_sync_tx_us,
            };
            self.out.push_front(s.to_frame(0));
            let fast = self.nodes.iter().any(|v| !v.sync_ok);
            self.next_sync_us = now
                + if fast {
                    self.opts.fast_sync_period_us
                } else {
                    self.opts.sync_period_us
                };
        }
        let n_seg = self.segments.len();
        match self.phase {
            Phase::Discover => {
                if self.nodes.iter().all(|v| v.heartbeat_at.is_some()) {
                    for (i, v) in self.nodes.iter().enumerate() {
                        if v.version != triquint_shared::protocol::PROTOCOL_VERSION {
                            return Err(UploadError::Version {
                                node: i as u8 + 1,
                                got: v.version,
                                want: triquint_shared::protocol::PROTOCOL_VERSION,
                            });
                        }
                    }
                    if self.nodes.iter().any(|v| v.state == Some(State::Fault)) {
                        self.command(0, CommandCode::ClearFault, 0);
                    }
                    self.command(0, CommandCode::Reset, 0);
                    if self.opts.configure {
                        for i in 0..3 {
                            self.write_config(i);
                        }
                        for i in 0..3 {
                            self.commit_config(i, now, 0);
                        }
                        self.set_phase(Phase::Configure, now);
                    } else {
                        self.set_phase(Phase::VerifyConfig, now);
                    }
                } else {
                    let nodes = self.nodes;
                    self.timeout(now, "waiting for its heartbeat", |i| {
                        nodes[i].heartbeat_at.is_none()
                    })?;
                }
            }
            Phase::Configure => {
                if self.configured(now)? {
                    self.set_phase(Phase::VerifyConfig, now);
                } else {
                    let nodes = self.nodes;
                    self.timeout(now, "committing the configuration", |i| {
                        !matches!(nodes[i].last_ack, Some((c, _, _, _)) if c == CommandCode::ConfigCommit as u8)
                    })?;
                }
            }
            Phase::VerifyConfig => {
                // A heartbeat newer than this phase from every node.
                let since = self.phase_since;
                let fresh = self
                    .nodes
                    .iter()
                    .all(|v| v.heartbeat_at.is_some_and(|t| t > since));
                if fresh {
                    let bad = (0..3).find(|&i| self.nodes[i].config_crc != self.configs[i].crc());
                    match bad {
                        None if self.opts.configure_only => self.set_phase(Phase::Done, now),
                        None => self.set_phase(Phase::Sync, now),
                        Some(i) => {
                            let node = i as u8 + 1;
                            self.readback = Some((node, [None; PARAM_COUNT]));
                            self.command(node, CommandCode::ReadConfig, 0);
                            self.set_phase(Phase::ReadBack, now);
                        }
                    }
                } else {
                    let nodes = self.nodes;
                    self.timeout(now, "reporting its configuration", |i| {
                        nodes[i].heartbeat_at.is_none_or(|t| t <= since)
                    })?;
                }
            }
            Phase::ReadBack => {
                if let Some((node, vals)) = self.readback
                    && vals.iter().all(Option::is_some)
                {
                    let i = node as usize - 1;
                    let want = self.configs[i].to_values();
                    for (k, p) in PARAMS.iter().enumerate() {
                        let got = vals[k].unwrap_or(f32::NAN);
                        if got.to_bits() != want[k].to_bits() {
                            return Err(UploadError::ConfigMismatch {
                                node,
                                param: p.name,
                                node_value: got,
                                plan_value: want[k],
                            });
                        }
                    }
                    // Same values written, yet a different active CRC: not committed.
                    return Err(UploadError::ConfigCrc {
                        node,
                        node_crc: self.nodes[i].config_crc,
                        plan_crc: self.configs[i].crc(),
                    });
                }
                self.timeout(now, "reading back its configuration", |_| true)?;
            }
            Phase::Sync => {
                let since = self.phase_since;
                if self
                    .nodes
                    .iter()
                    .all(|v| v.sync_ok && v.sync_seen_at.is_some_and(|t| t > since))
                {
                    self.set_phase(Phase::Fill, now);
                } else {
                    let nodes = self.nodes;
                    self.timeout(now, "synchronising its clock", |i| !nodes[i].sync_ok)?;
                }
            }
            Phase::Fill => {
                self.stream(now)?;
                let cap = self
                    .nodes
                    .iter()
                    .map(|v| v.capacity as usize)
                    .min()
                    .unwrap_or(0);
                let want = if cap == 0 { 1 } else { cap.min(n_seg) };
                let want = want.min(self.opts.stall_after.unwrap_or(usize::MAX)).max(1);
                if self.all_acked_through(want) {
                    let token = self.command(0, CommandCode::Arm, 0);
                    self.arm = (token, now, 0);
                    self.set_phase(Phase::Arm, now);
                } else {
                    self.timeout(now, "acknowledging the first segments", |_| true)?;
                }
            }
            Phase::Arm => {
                let (token, sent_at, resends) = self.arm;
                let acks = self.acks_for(token);
                if acks.iter().any(Option::is_none)
                    && resends < ARM_RESENDS
                    && now.saturating_sub(sent_at) > self.opts.setup_retry_us
                {
                    // The same command (same token) to each silent node: one
                    // that did arm answers again, one that missed it arms.
                    for i in (0..3).filter(|&i| acks[i].is_none()) {
                        let c = Command {
                            command: CommandCode::Arm as u8,
                            token,
                            arg: 0,
                        };
                        self.out.push_back(c.to_frame(i as u8 + 1));
                    }
                    self.arm = (token, now, resends + 1);
                }
                if acks.iter().all(Option::is_some) {
                    if let Some(i) = acks.iter().position(|r| *r != Some(0)) {
                        let code = acks[i]
                            .and_then(FaultCode::from_u8)
                            .unwrap_or(FaultCode::None);
                        return Err(UploadError::Refused {
                            node: i as u8 + 1,
                            command: "Arm",
                            code: code.name(),
                        });
                    }
                    let start = now + self.opts.start_lead_us;
                    let token = self.command(0, CommandCode::Start, start as u32);
                    self.start_cmd = (token, now);
                    self.start_us = start;
                    self.set_phase(Phase::Stream, now);
                } else {
                    self.timeout(now, "answering Arm", |i| acks[i].is_none())?;
                }
            }
            Phase::Stream => {
                self.resend_start(now);
                if !self.faults.is_empty() {
                    self.set_phase(Phase::Finish, now);
                } else {
                    self.stream(now)?;
                    if self.all_acked_through(n_seg) {
                        self.set_phase(Phase::Finish, now);
                    }
                }
            }
            Phase::Finish => {
                let end = self.start_us + self.plan_end_us;
                let settled = self.nodes.iter().all(|v| {
                    v.heartbeat_at
                        .is_some_and(|t| t > end.max(self.phase_since))
                        && matches!(v.state, Some(State::Idle) | Some(State::Fault))
                });
                let faulted = !self.faults.is_empty();
                if settled || (faulted && now > self.phase_since + self.opts.finish_grace_us) {
                    self.set_phase(Phase::Done, now);
                } else if now > end + self.opts.finish_grace_us {
                    let nodes = self.nodes;
                    return Err(UploadError::Timeout {
                        node: (0..3)
                            .find(|&i| !matches!(nodes[i].state, Some(State::Idle)))
                            .map_or(1, |i| i as u8 + 1),
                        what: "finishing the plan",
                    });
                }
            }
            Phase::Done => {}
        }
        // Transmit what the port takes.
        while let Some(f) = self.out.front() {
            if !port.send(f)? {
                break;
            }
            self.frames_sent += 1;
            self.out.pop_front();
        }
        if self.phase == Phase::Done && self.out.is_empty() {
            let completed =
                self.faults.is_empty() && self.nodes.iter().all(|v| v.state == Some(State::Idle));
            return Ok(Some(Outcome {
                completed,
                faults: self.faults.clone(),
                start_us: self.start_us,
                frames_sent: self.frames_sent,
                segment_frames_sent: self.segment_frames,
                retransmits: self.retransmits,
                rejects_seen: self.rejects_seen,
            }));
        }
        Ok(None)
    }
}
