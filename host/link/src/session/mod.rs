//! One upload of one plan to the three drive nodes: a non-blocking state
//! machine driven by [`Session::poll`] over any [`CanPort`].
//!
//! The phases, in order: heartbeats from every node (protocol version
//! checked, faults cleared, Reset), configuration written, committed and
//! checked ([`configure`]), clocks synchronised ([`time_sync`], all along),
//! the first segments streamed ([`stream`]), Arm and a common Start
//! ([`start`]), the rest streamed, then every node back at rest. What the
//! host knows of each node is a [`NodeView`] ([`nodes`]). This file only
//! decodes what arrives and moves between the phases.

mod configure;
mod error;
pub mod nodes;
mod options;
mod outbox;
mod start;
mod stream;
mod time_sync;

pub use error::UploadError;
pub use nodes::{CommandAnswer, NODES, NodeView};
pub use options::SessionOptions;
pub use start::{ARM_RESENDS, START_RETRY_US};

use triquint_shared::plan::Plan;
use triquint_shared::protocol::{
    CommandCode, DriveConfig, FaultCode, Msg, PROTOCOL_VERSION, State, WireSegment, decode,
};

use self::configure::Configuration;
use self::nodes::{Nodes, node_index};
use self::outbox::Outbox;
use self::start::StartSequence;
use self::stream::Stream;
use self::time_sync::TimeSyncMaster;
use crate::{CanPort, Received};

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

/// One upload of one plan to the three nodes.
pub struct Session {
    opts: SessionOptions,
    phase: Phase,
    phase_since: u64,
    nodes: Nodes,
    out: Outbox,
    sync: TimeSyncMaster,
    config: Configuration,
    stream: Stream,
    start: StartSequence,
    plan_end_us: u64,
    faults: Vec<FaultReport>,
}

impl Session {
    /// A session for `plan` with the given per-node configurations.
    pub fn new(
        plan: &Plan,
        configs: [DriveConfig; NODES],
        opts: SessionOptions,
    ) -> Result<Self, UploadError> {
        let segments = plan
            .wire_segments()
            .map_err(|(seq, source)| UploadError::Segment { seq, source })?;
        Ok(Self::with_segments(segments, configs, opts))
    }

    /// A session that only writes and checks the configurations (no motion):
    /// drives report their position once configured.
    pub fn configure(configs: [DriveConfig; NODES], mut opts: SessionOptions) -> Self {
        opts.configure_only = true;
        Self::with_segments(Vec::new(), configs, opts)
    }

    fn with_segments(
        segments: Vec<WireSegment>,
        configs: [DriveConfig; NODES],
        opts: SessionOptions,
    ) -> Self {
        let stream = Stream::new(segments, opts.fd);
        Self {
            plan_end_us: stream.plan_end_us(),
            opts,
            phase: Phase::Discover,
            phase_since: 0,
            nodes: Nodes::default(),
            out: Outbox::default(),
            sync: TimeSyncMaster::default(),
            config: Configuration::new(configs),
            stream,
            start: StartSequence::default(),
            faults: Vec::new(),
        }
    }

    pub fn faults(&self) -> &[FaultReport] {
        &self.faults
    }

    /// The segments as they go on the wire, in order.
    pub fn segments(&self) -> &[WireSegment] {
        &self.stream.segments
    }

    /// Segments retransmitted so far.
    pub fn retransmits(&self) -> u64 {
        self.stream.retransmits
    }

    /// Host time (µs) of the start (0 before).
    pub fn start_us(&self) -> u64 {
        self.start.start_us
    }

    /// Where the session is, for progress displays.
    pub fn progress(&self) -> Progress {
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
            segments_acked: self.stream.acked(),
            segments: self.stream.segments.len(),
            started: self.start.start_us != 0,
            plan_end_us: self.plan_end_us,
        }
    }

    /// What the host last heard from each node (node i + 1 at index i).
    pub fn nodes(&self) -> &[NodeView; NODES] {
        &self.nodes.0
    }

    /// Last reported state and fault code of nodes 1–3 (`None`: never heard).
    pub fn node_states(&self) -> [(Option<State>, u8); NODES] {
        self.nodes.0.map(|v| (v.state, v.fault))
    }

    fn set_phase(&mut self, p: Phase, now: u64) {
        self.phase = p;
        self.phase_since = now;
    }

    /// Takes in one received frame.
    fn handle(&mut self, rx: &Received) -> Result<(), UploadError> {
        if rx.own {
            self.sync.confirmed(rx);
            return Ok(());
        }
        let Ok((msg, node)) = decode(&rx.frame) else {
            return Ok(());
        };
        let Some(i) = node_index(node) else {
            return Ok(());
        };
        let v = &mut self.nodes.0[i];
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
                self.stream.acknowledged(i, &a, rx.t_us)?;
            }
            Msg::CommandAck(a) => v.last_answer = Some(a.into()),
            Msg::Emergency(e) => {
                self.faults.push(FaultReport {
                    node,
                    code: FaultCode::from_u8(e.code).unwrap_or(FaultCode::None),
                    t_us: rx.t_us,
                });
            }
            Msg::ConfigValue { index, value } => self.config.value(node, index, value),
            _ => {}
        }
        Ok(())
    }

    /// `Err(Timeout)` naming `node` once the phase has lasted longer than
    /// `response_timeout_us`.
    fn timeout(&self, now: u64, what: &'static str, node: u8) -> Result<(), UploadError> {
        if now.saturating_sub(self.phase_since) > self.opts.response_timeout_us {
            return Err(UploadError::Timeout { node, what });
        }
        Ok(())
    }

    /// Advances the session; `Ok(Some(outcome))` when finished.
    pub fn poll<P: CanPort>(&mut self, port: &mut P) -> Result<Option<Outcome>, UploadError> {
        let now = port.now_us();
        while let Some(rx) = port.recv()? {
            self.handle(&rx)?;
        }
        // Time sync, fast until every node is synced.
        let synced = self.nodes.all(|v| v.sync_ok);
        self.sync.poll(now, synced, &self.opts, &mut self.out);
        match self.phase {
            Phase::Discover => self.discover(now)?,
            Phase::Configure => {
                if self
                    .config
                    .committed(now, &self.nodes, &self.opts, &mut self.out)?
                {
                    self.set_phase(Phase::VerifyConfig, now);
                } else {
                    let node = Configuration::uncommitted(&self.nodes);
                    self.timeout(now, "committing the configuration", node)?;
                }
            }
            Phase::VerifyConfig => self.verify_config(now)?,
            Phase::ReadBack => {
                if let Some(e) = self.config.read_back_error(&self.nodes) {
                    return Err(e);
                }
                self.timeout(now, "reading back its configuration", 1)?;
            }
            Phase::Sync => {
                let since = self.phase_since;
                if self
                    .nodes
                    .all(|v| v.sync_ok && v.sync_seen_at.is_some_and(|t| t > since))
                {
                    self.set_phase(Phase::Fill, now);
                } else {
                    let node = self.nodes.first(|v| !v.sync_ok);
                    self.timeout(now, "synchronising its clock", node)?;
                }
            }
            Phase::Fill => {
                self.stream
                    .poll(now, &self.nodes, &self.opts, &mut self.out)?;
                let cap = self.nodes.min_capacity();
                let n_seg = self.stream.segments.len();
                let want = if cap == 0 { 1 } else { cap.min(n_seg) };
                let want = want.min(self.opts.stall_after.unwrap_or(usize::MAX)).max(1);
                if self.stream.all_acked_through(want) {
                    self.start.arm(now, &mut self.out);
                    self.set_phase(Phase::Arm, now);
                } else {
                    self.timeout(now, "acknowledging the first segments", 1)?;
                }
            }
            Phase::Arm => {
                let answers = self.start.arm_answers(&self.nodes);
                if self
                    .start
                    .poll_arm(now, &self.nodes, &self.opts, &mut self.out)?
                {
                    self.set_phase(Phase::Stream, now);
                } else {
                    let node = answers
                        .iter()
                        .position(Option::is_none)
                        .map_or(1, |i| i as u8 + 1);
                    self.timeout(now, "answering Arm", node)?;
                }
            }
            Phase::Stream => {
                self.start.resend_start(now, &self.nodes, &mut self.out);
                if !self.faults.is_empty() {
                    self.set_phase(Phase::Finish, now);
                } else {
                    self.stream
                        .poll(now, &self.nodes, &self.opts, &mut self.out)?;
                    if self.stream.all_acked_through(self.stream.segments.len()) {
                        self.set_phase(Phase::Finish, now);
                    }
                }
            }
            Phase::Finish => self.finish(now)?,
            Phase::Done => {}
        }
        self.out.flush(port)?;
        if self.phase == Phase::Done && self.out.is_empty() {
            let completed =
                self.faults.is_empty() && self.nodes.all(|v| v.state == Some(State::Idle));
            return Ok(Some(Outcome {
                completed,
                faults: self.faults.clone(),
                start_us: self.start.start_us,
                frames_sent: self.out.sent,
                segment_frames_sent: self.stream.segment_frames,
                retransmits: self.stream.retransmits,
                rejects_seen: self.stream.rejects_seen,
            }));
        }
        Ok(None)
    }

    /// Every node heard: protocol version checked, faults cleared, Reset,
    /// then the configuration written (or only checked).
    fn discover(&mut self, now: u64) -> Result<(), UploadError> {
        if !self.nodes.all(|v| v.heartbeat_at.is_some()) {
            let node = self.nodes.first(|v| v.heartbeat_at.is_none());
            return self.timeout(now, "waiting for its heartbeat", node);
        }
        for (i, v) in self.nodes.0.iter().enumerate() {
            if v.version != PROTOCOL_VERSION {
                return Err(UploadError::Version {
                    node: i as u8 + 1,
                    got: v.version,
                    want: PROTOCOL_VERSION,
                });
            }
        }
        if self.nodes.any(|v| v.state == Some(State::Fault)) {
            self.out.command(0, CommandCode::ClearFault, 0);
        }
        self.out.command(0, CommandCode::Reset, 0);
        if self.opts.configure {
            self.config.start(now, &mut self.out);
            self.set_phase(Phase::Configure, now);
        } else {
            self.set_phase(Phase::VerifyConfig, now);
        }
        Ok(())
    }

    /// A heartbeat newer than this phase from every node: its active
    /// configuration CRC must be the plan's (else read it back).
    fn verify_config(&mut self, now: u64) -> Result<(), UploadError> {
        let since = self.phase_since;
        if !self
            .nodes
            .all(|v| v.heartbeat_at.is_some_and(|t| t > since))
        {
            let node = self
                .nodes
                .first(|v| v.heartbeat_at.is_none_or(|t| t <= since));
            return self.timeout(now, "reporting its configuration", node);
        }
        match self.config.differing(&self.nodes) {
            None if self.opts.configure_only => self.set_phase(Phase::Done, now),
            None => self.set_phase(Phase::Sync, now),
            Some(i) => {
                self.config.read_back(i, &mut self.out);
                self.set_phase(Phase::ReadBack, now);
            }
        }
        Ok(())
    }

    /// After the plan's end: every node reports rest (Idle or Fault), or a
    /// fault has had `finish_grace_us` to play out.
    fn finish(&mut self, now: u64) -> Result<(), UploadError> {
        let end = self.start.start_us + self.plan_end_us;
        let since = self.phase_since;
        let settled = self.nodes.all(|v| {
            v.heartbeat_at.is_some_and(|t| t > end.max(since))
                && matches!(v.state, Some(State::Idle) | Some(State::Fault))
        });
        let faulted = !self.faults.is_empty();
        if settled || (faulted && now > since + self.opts.finish_grace_us) {
            self.set_phase(Phase::Done, now);
        } else if now > end + self.opts.finish_grace_us {
            return Err(UploadError::Timeout {
                node: self.nodes.first(|v| !matches!(v.state, Some(State::Idle))),
                what: "finishing the plan",
            });
        }
        Ok(())
    }
}
