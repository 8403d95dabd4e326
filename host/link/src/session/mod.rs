//! One upload of one plan to the three drive nodes: a non-blocking state
//! machine driven by [`Session::poll`] over any [`CanPort`].
//!
//! The phases, in order: heartbeats from every node (protocol version
//! checked, faults cleared, Reset), configuration written, committed and
//! checked (`configure`), clocks synchronised (`time_sync`, all along),
//! the first segments streamed (`stream`), Arm and a common Start
//! (`start`), the rest streamed, then every node back at rest. What the
//! host knows of each node is a [`NodeView`] ([`nodes`]). This file only
//! decodes what arrives and moves between the phases.

mod configure;
mod error;
mod feed;
pub mod nodes;
mod options;
mod outbox;
mod path_ramps;
mod plan_clock;
mod start;
mod stream;
mod time_sync;

pub use error::UploadError;
pub use feed::Feed;
pub use nodes::{AXES, CommandAnswer, NodeView};
pub use options::SessionOptions;
pub use start::{ARM_RESENDS, START_RETRY_US};

use triquint_shared::plan::Plan;
use triquint_shared::protocol::streaming::StreamRule;
use triquint_shared::protocol::{
    CommandCode, DriveConfig, FaultCode, Msg, PROTOCOL_VERSION, State, WireSegment, decode,
};

use self::configure::Configuration;
use self::feed::FeedState;
use self::nodes::Nodes;
use self::outbox::Outbox;
use self::path_ramps::PathRamps;
use self::plan_clock::PlanClock;
use self::start::StartSequence;
use self::stream::Stream;
use self::time_sync::TimeSyncMaster;
use crate::Drive;
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
    /// Plan time the drives have reached, as estimated from their reports (µs).
    pub plan_time_us: u64,
    /// A drive reports a feed hold.
    pub held: bool,
    /// The feed override the drives hold (per mille): acknowledged last,
    /// or reported in the answer to Arm; `None`: not known.
    pub override_permille: Option<u32>,
    /// A stop was acknowledged: the plan ends early, at rest on its path.
    pub stopped: bool,
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
    /// Stopped on request (a Stop or QuickStop acknowledged) before its end.
    pub stopped: bool,
    pub faults: Vec<FaultReport>,
    /// Host time (µs) of the start.
    pub start_us: u64,
    pub frames_sent: u64,
    pub segment_frames_sent: u64,
    /// Segments sent (resends included), and how many of them compact.
    pub segments_sent: u64,
    pub compact_sent: u64,
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

/// One upload of one plan to the three nodes (a clone goes on from the
/// same point: tests branch a run).
#[derive(Clone)]
pub struct Session {
    opts: SessionOptions,
    phase: Phase,
    phase_since: u64,
    polled: bool,
    nodes: Nodes,
    out: Outbox,
    sync: TimeSyncMaster,
    config: Configuration,
    stream: Stream,
    start: StartSequence,
    plan_end_us: u64,
    faults: Vec<FaultReport>,
    /// The plan's first via-point (m) and the joints there, for an Arm
    /// refused for distance.
    plan_start: Option<PlanStart>,
    feed: FeedState,
    clock: PlanClock,
    /// The configured override cap (σ).
    override_cap: f64,
    /// Streamability of the plan by the configuration (its capacity is
    /// the drives', known once they acknowledge a segment).
    stream_rule: StreamRule,
    /// The ramp a stop carries for the path ahead of its instant.
    path_ramps: PathRamps,
}

/// Where a plan starts.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanStart {
    /// Platform position (m).
    pub r: [f64; 3],
    /// Joint positions (m).
    pub q: [f64; 3],
}

impl Session {
    /// A session for `plan` with the given per-node configurations.
    pub fn new(
        plan: &Plan,
        configs: [DriveConfig; AXES],
        opts: SessionOptions,
    ) -> Result<Self, UploadError> {
        let segments = plan.wire_segments().map_err(|e| UploadError::Segment {
            seq: e.index,
            source: e.source,
        })?;
        let mut s = Self::with_segments(segments, configs, opts);
        s.plan_start = match (plan.via_points_m.first(), plan.segments.first()) {
            (Some(r), Some(seg)) => Some(PlanStart {
                r: *r,
                q: [seg.coeffs[0][0], seg.coeffs[1][0], seg.coeffs[2][0]],
            }),
            _ => None,
        };
        Ok(s)
    }

    /// A session that only writes and checks the configurations (no motion):
    /// drives report their position once configured.
    pub fn configure(configs: [DriveConfig; AXES], mut opts: SessionOptions) -> Self {
        opts.configure_only = true;
        opts.require_homed = false;
        Self::with_segments(Vec::new(), configs, opts)
    }

    fn with_segments(
        segments: Vec<WireSegment>,
        configs: [DriveConfig; AXES],
        opts: SessionOptions,
    ) -> Self {
        let path_ramps = PathRamps::new(&segments, &configs[0]);
        let stream = Stream::new(segments, opts.fd, opts.compact);
        let override_cap = configs[0].override_cap.max(1.0) as f64;
        let c = &configs[0];
        let stream_rule = StreamRule::new(
            0,
            c.stop_time as f64,
            c.underrun_margin as f64,
            c.heartbeat_period as f64,
        );
        Self {
            stream_rule,
            path_ramps,
            plan_end_us: stream.plan_end_us(),
            opts,
            phase: Phase::Discover,
            phase_since: 0,
            polled: false,
            nodes: Nodes::new(configs.map(|c| c.node_id as u8)),
            out: Outbox::default(),
            sync: TimeSyncMaster::default(),
            config: Configuration::new(configs),
            stream,
            start: StartSequence::default(),
            faults: Vec::new(),
            plan_start: None,
            feed: FeedState::default(),
            clock: PlanClock::default(),
            override_cap,
        }
    }

    /// Queues a feed command to every drive, sent at the next poll ahead of
    /// everything else with that poll's host time; returns its token (see
    /// [`Session::answers`]). Any time: before Start the drives latch a
    /// hold or an override.
    pub fn feed(&mut self, f: Feed) -> u8 {
        self.feed.queue(f, &mut self.out)
    }

    /// Each drive's answer to the command with `token`, once it gave one.
    pub fn answers(&self, token: u8) -> [Option<CommandAnswer>; AXES] {
        self.feed.answers(token).unwrap_or_else(|| {
            self.nodes
                .0
                .map(|v| v.last_answer.filter(|a| a.token == token))
        })
    }

    /// The override cap the drives are configured with (σ).
    pub fn override_cap(&self) -> f64 {
        self.override_cap
    }

    pub fn faults(&self) -> &[FaultReport] {
        &self.faults
    }

    /// The plan's segments in full, in order.
    pub fn segments(&self) -> &[WireSegment] {
        &self.stream.segments
    }

    /// Every version of a segment sent so far: (sequence number, body CRC
    /// of the segment a node holds once it takes it in). A compact segment
    /// is held as rebuilt from the one sent before it.
    pub fn versions(&self) -> &[(u16, u32)] {
        &self.stream.versions
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
            plan_time_us: self.clock.plan_us().min(self.plan_end_us),
            held: self.clock.held,
            override_permille: self.feed.override_permille,
            stopped: self.feed.stopped,
        }
    }

    /// What the host last heard from each node (axis i + 1's at index i).
    pub fn nodes(&self) -> &[NodeView; AXES] {
        &self.nodes.0
    }

    /// Last reported state and fault code of each node, axis 1 first (`None`: never heard).
    pub fn node_states(&self) -> [(Option<State>, u8); AXES] {
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
        if let Msg::Command(c) = msg {
            // Another station's command (a second process, the web page).
            self.feed.seen(&c);
            return Ok(());
        }
        let Some(i) = self.nodes.index(node) else {
            return Ok(());
        };
        let v = &mut self.nodes.0[i];
        match msg {
            Msg::Heartbeat(h) => {
                v.heartbeat(&h, rx.t_us);
                // A fault in a heartbeat counts once motion is under way (an
                // Emergency frame may be lost); before, a faulted node is
                // refused or cleared in discovery.
                let moving = matches!(self.phase, Phase::Arm | Phase::Stream | Phase::Finish);
                // A stop whose acknowledgement was missed.
                if moving && h.fault == 0 && h.state == State::Stopping as u8 {
                    self.feed.stopped = true;
                }
                if moving && h.fault != 0 && !self.faults.iter().any(|f| f.node == node) {
                    self.faults.push(FaultReport {
                        node,
                        code: FaultCode::from_u8(h.fault).unwrap_or(FaultCode::None),
                        t_us: rx.t_us,
                    });
                }
            }
            Msg::HeartbeatExt(h) => v.heartbeat_ext(&h, rx.t_us),
            Msg::Telemetry(t) => v.position = Some(t.position),
            Msg::SegmentAck(a) => {
                v.next_seq = a.next_seq;
                v.depth = a.depth;
                v.capacity = a.capacity;
                // Once stopped, the drives refuse what is still on its way.
                match self
                    .stream
                    .acknowledged(i, self.nodes.drive(i), &a, rx.t_us)
                {
                    Err(_) if self.feed.stopped => {}
                    r => r?,
                }
            }
            Msg::CommandAck(a) => {
                v.last_answer = Some(a.into());
                self.feed.answered(i, &a);
            }
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

    /// Every node is [`Session::node_synced_to_this_session`].
    fn synced_to_this_session(&self, since: u64) -> bool {
        self.nodes
            .all(|v| self.node_synced_to_this_session(v, since))
    }

    /// Node `v` reports a valid sync in a heartbeat received after `since`
    /// and after the session's syncs could have moved its time base
    /// (`TimeSyncMaster::of_this_session`).
    fn node_synced_to_this_session(&self, v: &NodeView, since: u64) -> bool {
        v.sync_ok
            && v.sync_seen_at
                .is_some_and(|t| t > since && self.sync.of_this_session(t))
    }

    /// `Err(Timeout)` naming `node` once the phase has lasted longer than
    /// `response_timeout_us`.
    fn timeout(&self, now: u64, what: &'static str, node: Drive) -> Result<(), UploadError> {
        if now.saturating_sub(self.phase_since) > self.opts.response_timeout_us {
            return Err(UploadError::Timeout { node, what });
        }
        Ok(())
    }

    /// Advances the session; `Ok(Some(outcome))` when finished.
    pub fn poll<P: CanPort>(&mut self, port: &mut P) -> Result<Option<Outcome>, UploadError> {
        let now = port.now_us();
        // The first phase's clock starts at the first poll, whatever the
        // port's clock reads then.
        if !self.polled {
            self.polled = true;
            self.phase_since = now;
        }
        while let Some(rx) = port.recv()? {
            self.handle(&rx)?;
        }
        // Time sync, fast until every node is synced.
        let synced = self.synced_to_this_session(0);
        self.sync.poll(now, synced, &self.opts, &mut self.out);
        // A stop while the plan runs carries the ramp for the path ahead
        // of the clock's estimate (the clock as of the last poll: the
        // estimate's margin covers a poll's interval).
        let running = matches!(self.phase, Phase::Stream | Phase::Finish) && !self.clock.held;
        let (ramps, plan_us) = (&self.path_ramps, self.clock.plan_us() as f64);
        self.feed.send(now, &mut self.out, |f| match f {
            Feed::Stop | Feed::Hold if running => ramps.dated(plan_us, false),
            Feed::QuickStop if running => ramps.dated(plan_us, true),
            _ => 0,
        });
        self.clock.override_permille = self.feed.override_permille;
        self.clock.update(now, self.start.start_us, &self.nodes);
        let before_start = !matches!(self.phase, Phase::Stream | Phase::Finish | Phase::Done);
        if self.feed.stopped && before_start {
            // Stopped before anything moved: every node back to Idle.
            self.out.command(0, CommandCode::Reset, 0);
            self.set_phase(Phase::Done, now);
        }
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
                let node = self.config.reading_back().unwrap_or(self.nodes.id(0));
                self.timeout(
                    now,
                    "reading back its configuration",
                    self.nodes.drive_of(node),
                )?;
            }
            Phase::Sync => {
                let since = self.phase_since;
                if self.synced_to_this_session(since) {
                    self.set_phase(Phase::Fill, now);
                } else {
                    // The first node not yet synced on this session's base
                    // (one synced on an old base is named too).
                    let node = self
                        .nodes
                        .first(|v| !self.node_synced_to_this_session(v, since));
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
                    self.check_streamable(cap)?;
                    self.start.arm(now, &mut self.out);
                    self.set_phase(Phase::Arm, now);
                } else {
                    let node = self.nodes.first(|v| (v.next_seq as usize) < want);
                    self.timeout(now, "acknowledging the first segments", node)?;
                }
            }
            Phase::Arm => {
                let answers = self.start.arm_answers(&self.nodes);
                let armed = match self
                    .start
                    .poll_arm(now, &self.nodes, &self.opts, &mut self.out)
                {
                    Ok(a) => a,
                    Err(e) => return Err(self.arm_refused(e, port)),
                };
                if armed {
                    self.set_phase(Phase::Stream, now);
                } else {
                    let node = self
                        .nodes
                        .drive(answers.iter().position(Option::is_none).unwrap_or(0));
                    self.timeout(now, "answering Arm", node)?;
                }
            }
            Phase::Stream => {
                self.start.resend_start(now, &self.nodes, &mut self.out);
                if !self.faults.is_empty() || self.feed.stopped {
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
            let stopped = self.feed.stopped;
            let completed = !stopped
                && self.faults.is_empty()
                && self.nodes.all(|v| v.state == Some(State::Idle));
            return Ok(Some(Outcome {
                completed,
                stopped,
                faults: self.faults.clone(),
                start_us: self.start.start_us,
                frames_sent: self.out.sent,
                segment_frames_sent: self.stream.segment_frames,
                segments_sent: self.stream.segments_sent,
                compact_sent: self.stream.compact_sent,
                retransmits: self.stream.retransmits,
                rejects_seen: self.stream.rejects_seen,
            }));
        }
        Ok(None)
    }

    /// An Arm refusal: every node back to Idle (Reset, nothing moved), and
    /// for a refusal for distance, how far each axis is from the plan's start.
    /// Refuses, before Arm, a plan that queues of `capacity` segments
    /// cannot stream at σ = 1 (`protocol::streaming`).
    fn check_streamable(&mut self, capacity: usize) -> Result<(), UploadError> {
        if capacity == 0 {
            return Ok(());
        }
        self.stream_rule.capacity = capacity;
        let d: Vec<u32> = self.stream.segments.iter().map(|s| s.duration_us).collect();
        self.stream_rule
            .check(&d)
            .map_err(|s| UploadError::Unstreamable {
                capacity,
                first: s.first,
                last: s.last,
                run_us: s.run_us,
                need_us: s.need_us,
            })
    }

    fn arm_refused<P: CanPort>(&mut self, e: UploadError, port: &mut P) -> UploadError {
        self.out.command(0, CommandCode::Reset, 0);
        let _ = self.out.flush(port);
        let UploadError::Refused { node, code, .. } = e else {
            return e;
        };
        match (code, self.plan_start) {
            (Some(FaultCode::ArmTooFar), Some(start)) => UploadError::ArmTooFar {
                node,
                distances_mm: [0, 1, 2].map(|i| {
                    self.nodes.0[i]
                        .position
                        .map(|q| (q as f64 - start.q[i]) * 1e3)
                }),
                start_mm: start.r.map(|x| x * 1e3),
            },
            (Some(FaultCode::NotHomed), _) => UploadError::NotHomed { node },
            _ => e,
        }
    }

    /// Every node heard: protocol version checked, homed, not faulted
    /// (or faults cleared on request), Reset, then the configuration
    /// written (or only checked).
    fn discover(&mut self, now: u64) -> Result<(), UploadError> {
        let heard = |v: &nodes::NodeView| v.heartbeat_at.is_some() && v.sync_seen_at.is_some();
        if !self.nodes.all(heard) {
            let node = self.nodes.first(|v| !heard(v));
            return self.timeout(now, "waiting for its heartbeat", node);
        }
        for v in &self.nodes.0 {
            if v.version != PROTOCOL_VERSION {
                return Err(UploadError::Version {
                    node: self.nodes.drive_of(v.id),
                    got: v.version,
                    want: PROTOCOL_VERSION,
                });
            }
        }
        if let Some(v) = self.nodes.0.iter().find(|v| v.state == Some(State::Fault)) {
            if !self.opts.clear_faults {
                return Err(UploadError::Faulted {
                    node: self.nodes.drive_of(v.id),
                    code: FaultCode::from_u8(v.fault),
                });
            }
            self.out.command(0, CommandCode::ClearFault, 0);
            self.faults.clear();
        }
        if self.opts.require_homed
            && let Some(v) = self.nodes.0.iter().find(|v| !v.homed)
        {
            return Err(UploadError::NotHomed {
                node: self.nodes.drive_of(v.id),
            });
        }
        self.out.command(0, CommandCode::Reset, 0);
        self.sync.follow_from_now();
        if self.opts.configure {
            let unlock = self.opts.unlock_ceilings;
            self.config.start(now, &self.nodes, unlock, &mut self.out);
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
            None => {
                if let Some(pm) = self.opts.feed_override {
                    self.feed(Feed::Override(pm));
                }
                self.set_phase(Phase::Sync, now)
            }
            Some(i) => {
                self.config.read_back(i, &mut self.out);
                self.set_phase(Phase::ReadBack, now);
            }
        }
        Ok(())
    }

    /// After the plan's end (or a stop): every node reports rest (Idle or
    /// Fault), or a fault has had `finish_grace_us` to play out. The
    /// deadline follows the plan time the drives reached (a hold stands
    /// it still), and a node silent for `response_timeout_us` ends it.
    fn finish(&mut self, now: u64) -> Result<(), UploadError> {
        let since = self.phase_since;
        let faulted = !self.faults.is_empty();
        // Not before the plan can have ended (at the highest override).
        let earliest = if faulted || self.feed.stopped {
            since
        } else {
            let fastest = (self.plan_end_us as f64 / self.override_cap) as u64;
            since.max(self.start.start_us + fastest)
        };
        // At rest: Idle or Fault; after a stop before Start, Loaded.
        let stopped = self.feed.stopped;
        let settled = self.nodes.all(|v| {
            v.heartbeat_at.is_some_and(|t| t > earliest)
                && (matches!(v.state, Some(State::Idle) | Some(State::Fault))
                    || (stopped && v.state == Some(State::Loaded)))
        });
        let silent = self.nodes.0.iter().find(|v| {
            v.heartbeat_at
                .is_none_or(|t| now.saturating_sub(t) > self.opts.response_timeout_us)
        });
        if settled || (faulted && now > since + self.opts.finish_grace_us) {
            self.set_phase(Phase::Done, now);
        } else if self.clock.plan_us() > self.plan_end_us + self.opts.finish_grace_us {
            return Err(UploadError::Timeout {
                node: self.nodes.first(|v| !matches!(v.state, Some(State::Idle))),
                what: "finishing the plan",
            });
        } else if let Some(v) = silent {
            return Err(UploadError::Timeout {
                node: self.nodes.drive_of(v.id),
                what: "finishing the plan (no heartbeat)",
            });
        }
        Ok(())
    }
}
