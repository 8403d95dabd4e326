//! The simulation run behind `triquint simulate`: the host's upload session
//! over the in-process bus to three simulated drives and the plant.

use nalgebra::Vector3;
use triquint_link::configs::PlanConfigError;
use triquint_link::{DriveConfigs, FaultReport, Session, SessionOptions, UploadError};
use triquint_shared::plan::Plan;
use triquint_shared::protocol::config::DriveSettings;
use triquint_sim::flex::{AccelSample, FlexError, FlexParams};
use triquint_sim::host_port::SimPort;
use triquint_sim::metrics;
use triquint_sim::plant_model::PlantKind;
use triquint_sim::report::RunReport;
use triquint_sim::sim::{Sample, SimError};
use triquint_sim::vibration::SETTLE_WINDOW_S;
use triquint_sim::{Sim, SimConfig};

use super::measure::run_report;

/// Options of a simulation run.
#[derive(Clone, Debug)]
pub struct SimulateOptions {
    pub fd: bool,
    pub feedforward: bool,
    pub rate_hz: f64,
    pub sim: SimConfig,
    pub session: SessionOptions,
    pub settings: DriveSettings,
    /// Initial joint position minus the plan's start (m).
    pub start_offset_m: [f64; 3],
    /// Host poll interval (µs).
    pub host_poll_us: u64,
    /// Return a refused Arm as an error instead of a report with the fault.
    pub strict: bool,
    /// The plant, and the flexible one's parameters.
    pub plant: PlantKind,
    pub flex: FlexParams,
}

impl Default for SimulateOptions {
    fn default() -> Self {
        Self {
            fd: false,
            feedforward: true,
            rate_hz: 1000.0,
            sim: SimConfig::default(),
            session: SessionOptions::default(),
            settings: DriveSettings::default(),
            start_offset_m: [0.0; 3],
            host_poll_us: 100,
            strict: false,
            plant: PlantKind::Rigid,
            flex: FlexParams::default(),
        }
    }
}

/// Why a simulation could not run to an outcome.
#[derive(Debug, thiserror::Error)]
pub enum SimulateError {
    #[error(transparent)]
    Upload(#[from] UploadError),
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The plan has no segments: nothing to run.
    #[error("the plan has no segments")]
    NoSegments,
    /// The plan has no position at its end time (a total time not a number).
    #[error("the plan has no end")]
    NoEnd,
    /// A 7-phase reference needs a move; the plan's path is closed.
    #[error(
        "a 7-phase profile needs a move: the plan's start and end are the same (a closed path; seven-phase-path retimes the path instead)"
    )]
    ClosedPath,
    #[error("plan: {0}")]
    Config(#[from] PlanConfigError),
    #[error("flexible plant: {0}")]
    Flex(#[from] FlexError),
    #[error("the simulation did not finish within {0:.1} s of simulated time")]
    Timeout(f64),
}

/// What a run measured: the run report every simulated run writes (the
/// JSON of `simulate --json`), and what only the in-process run has.
#[derive(Clone, Debug)]
pub struct SimReport {
    pub run: RunReport,
    /// Faults as the host's session saw them.
    pub faults: Vec<FaultReport>,
    /// Faults as the nodes raised them (true time).
    pub faults_on_nodes: Vec<triquint_sim::sim::FaultEvent>,
    /// Segment frames per segment sent (full and compact, resends included).
    pub frames_per_segment: f64,
    /// Segments sent (resends included), and how many of them compact.
    pub segments_sent: u64,
    pub compact_sent: u64,
    pub retransmits: u64,
    /// True-time spread of the nodes' first Running tick (ns; `None` when
    /// not every node started).
    pub start_skew_ns: Option<u64>,
    pub tick_ns: u64,
    pub f32_eval_error_m: f64,
    /// Host time (µs) of the start.
    pub start_us: u64,
    pub sim_time_s: f64,
    pub samples: Vec<Sample>,
    /// The flexible plant's accelerometer (empty on the rigid one).
    pub accel: Vec<AccelSample>,
}

/// The spread of the drives' start times, `None` unless every drive
/// started (a spread over some of them would look like a good start).
pub(crate) fn start_skew_ns(started: impl IntoIterator<Item = Option<u64>>) -> Option<u64> {
    let mut range: Option<(u64, u64)> = None;
    for t in started {
        let t = t?;
        range = Some(range.map_or((t, t), |(lo, hi)| (lo.min(t), hi.max(t))));
    }
    range.map(|(lo, hi)| hi - lo)
}

/// Uploads `plan` through the host session to three simulated drives and runs it.
pub fn simulate(plan: &Plan, opts: &SimulateOptions) -> Result<SimReport, SimulateError> {
    let mut settings = opts.settings.clone();
    settings.control_rate = opts.rate_hz;
    settings.feedforward = opts.feedforward;
    let DriveConfigs {
        nodes: configs,
        stop_time_s: ts,
        ..
    } = DriveConfigs::for_plan(plan, &settings)?;
    let mut sim_cfg = opts.sim.clone();
    sim_cfg.fd = opts.fd;
    sim_cfg.rate_hz = opts.rate_hz;
    // The simulated machine is the configured one: its encoder scales and
    // motor directions are the settings'.
    sim_cfg.counts_per_metre = settings.counts_per_metre;
    sim_cfg.motor_direction = settings.direction;
    sim_cfg.brake = settings.brake;
    // Record at most 1 kHz.
    sim_cfg.record_every = (opts.rate_hz / 1000.0).round().max(1.0) as u32;
    let q0 = plan
        .segments
        .first()
        .map(|s| s.quintic().eval(0.0).q)
        .ok_or(SimulateError::NoSegments)?
        + Vector3::from(opts.start_offset_m);
    let mut sim = match opts.plant {
        PlantKind::Rigid => Sim::new(&plan.robot, q0, sim_cfg),
        PlantKind::Flexible => Sim::flexible(&plan.robot, q0, sim_cfg, &opts.flex)?,
    };
    let mut sopts = opts.session.clone();
    sopts.fd = opts.fd;
    let mut session = Session::new(plan, configs, sopts)?;
    let limit_s = plan.total_time_s + 30.0;
    let outcome = loop {
        let mut port = SimPort {
            sim: &mut sim,
            tx_queue: 32,
        };
        match session.poll(&mut port) {
            Ok(Some(o)) => break o,
            Ok(None) => {}
            Err(e) => return Err(e.into()),
        }
        let t = sim.now_ns() + opts.host_poll_us * 1000;
        if t as f64 * 1e-9 > limit_s {
            return Err(SimulateError::Timeout(limit_s));
        }
        sim.run_until(t)?;
    };
    // The flexible machine rings on after the plan: hold it a settle window.
    let end_s = outcome.start_us as f64 * 1e-6 + plan.total_time_s;
    if sim.plant.flexible().is_some() {
        let until = ((end_s + SETTLE_WINDOW_S) * 1e9).ceil() as u64;
        while sim.now_ns() < until {
            let t = (sim.now_ns() + opts.host_poll_us * 1000).min(until);
            sim.run_until(t)?;
        }
    }
    let skew = start_skew_ns(sim.nodes.iter().map(|n| n.started_ns));
    let now = sim.now_ns().max(1);
    let mut run = run_report(
        plan,
        &sim,
        outcome.start_us * 1000,
        outcome.segment_frames_sent,
        ts,
        None,
    );
    run.completed = outcome.completed;
    if let Some(flex) = sim.plant.flexible() {
        let end = plan.at(plan.total_time_s).ok_or(SimulateError::NoEnd)?;
        run.vibration = flex
            .residual(end_s, SETTLE_WINDOW_S, Vector3::from(end.q))
            .map_err(|source| SimError::Plant { t_s: end_s, source })?;
    }
    Ok(SimReport {
        run,
        faults: outcome.faults.clone(),
        faults_on_nodes: sim.faults(),
        frames_per_segment: outcome.segment_frames_sent as f64
            / outcome.segments_sent.max(1) as f64,
        segments_sent: outcome.segments_sent,
        compact_sent: outcome.compact_sent,
        retransmits: outcome.retransmits,
        start_skew_ns: skew,
        tick_ns: (1e9 / opts.rate_hz) as u64,
        f32_eval_error_m: metrics::f32_eval_error(plan, 1000),
        start_us: outcome.start_us,
        sim_time_s: now as f64 * 1e-9,
        samples: std::mem::take(&mut sim.samples),
        accel: sim
            .plant
            .flexible()
            .map_or_else(Vec::new, |f| f.accel.clone()),
    })
}
