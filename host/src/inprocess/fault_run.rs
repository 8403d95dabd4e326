//! One plan run on the virtual hardware under a seeded fault scenario, with
//! everything the fault tests and the soak check: what each node executed
//! (sequence and body CRC, against the host's segments), when it detected
//! the fault, when every axis was at rest, the jerk of the stop, and the
//! fault codes in the Emergency frames and heartbeats on the bus. Reported
//! as every simulated run is, a [`RunReport`], with the fault run's own
//! figures in its `fault_run`.

use triquint_firmware::QUEUE_CAPACITY;
use triquint_link::{DriveConfigs, Session, SessionOptions};
use triquint_shared::machine::Ceilings;
use triquint_shared::plan::Plan;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{FaultCode, Msg, State, WireSegment, decode};
use triquint_sim::host_port::SimPort;
use triquint_sim::report::{Ending, FaultRunFigures, RunReport};
use triquint_sim::testplan::sampled_max_abs;
use triquint_sim::{FaultWindow, Sim, SimConfig};

use super::measure::run_report;

/// A segment made bad on purpose before the upload.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum BadSegment {
    /// Segment k with a t⁵ term of twice the plan's jerk limit at its end:
    /// beyond the limits, still C3.
    Limits(usize),
    /// Segment k starts with a velocity 0.02 m/s off its predecessor's end (not C3).
    Kink(usize),
}

/// An axis its machine file describes wrongly (the drives are configured
/// from the file, the virtual machine is the real one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Miswired {
    /// Its `direction` flipped (motor and encoder sign both).
    Direction,
    /// Its encoder's counts per metre times this.
    Scale(f64),
}

/// The drives' ceilings set against the plan (a host that skips its own
/// check): every case must be refused by the drives, never run whole.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum AboveCeiling {
    /// One ceiling (0 velocity, 1 acceleration, 2 jerk) at this fraction
    /// (< 1) of the plan's own exact maximum.
    Segment(usize, f64),
    /// Every ceiling at this factor (≥ 1) of the plan's maxima, below them
    /// at the override cap the host sized from the plan's limits.
    OverrideCap(f64),
    /// Ceilings at the plan's limits, the stop ramps sent this fraction
    /// of their size.
    StopRamp(f64),
    /// The drives commissioned with one ceiling as in [`Segment`](Self::Segment),
    /// then the host configures them with the default (top) ceilings, as
    /// from a machine file raised without maintenance: the ceiling lock
    /// must refuse that commit.
    Locked(usize, f64),
}

/// What goes wrong during one run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Scenario {
    /// Bus-level faults (see [`triquint_sim::faults`]).
    pub windows: Vec<FaultWindow>,
    pub seed: u64,
    pub fd: bool,
    /// The host process dies at this true time (ns): no more frames from it.
    pub host_killed_ns: Option<u64>,
    /// Node index (0–2) power-cycled at a true time (ns).
    pub node_reset: Option<(usize, u64)>,
    /// At this time a rogue copy of the host sends the next
    /// [`BURST_SEGMENTS`] segments at once, ignoring flow control.
    pub burst_ns: Option<u64>,
    pub bad_segment: Option<BadSegment>,
    /// Every axis has a holding brake (configuration `brake`; the virtual
    /// machine holds still where a drive's power stage is off).
    pub brakes: bool,
    /// An external torque on one axis: (axis, from, until true time in
    /// ns, N·m).
    pub push: Option<(usize, u64, u64, f64)>,
    /// One axis (0–2) described wrongly.
    pub miswired: Option<(usize, Miswired)>,
    pub above_ceiling: Option<AboveCeiling>,
    /// The host opens the drives' maintenance window before its commit
    /// (`upload`'s session with `unlock_ceilings`).
    pub unlock_ceilings: bool,
}

/// The ceilings and ramp factor of `case` for `plan`.
fn ceilings_for(plan: &Plan, case: AboveCeiling) -> (Ceilings, f64) {
    let m = triquint_shared::plan::figures::kinematics(&plan.segments);
    let top = |x: [f64; 3]| x.into_iter().fold(0.0, f64::max);
    let peaks = [top(m.velocity), top(m.acceleration), top(m.jerk)];
    let mut c = Ceilings::default();
    let set = |c: &mut Ceilings, v: [f64; 3]| {
        (c.velocity, c.acceleration, c.jerk) = (v[0], v[1], v[2]);
    };
    match case {
        AboveCeiling::Segment(which, f) => {
            let mut v = [c.velocity, c.acceleration, c.jerk];
            v[which.min(2)] = f * peaks[which.min(2)];
            set(&mut c, v);
            (c, 1.0)
        }
        AboveCeiling::OverrideCap(f) => {
            set(&mut c, peaks.map(|x| f * x));
            (c, 1.0)
        }
        AboveCeiling::StopRamp(f) => {
            let l = &plan.limits;
            set(&mut c, [l.velocity, l.acceleration, l.jerk]);
            (c, f)
        }
        // The run's own configuration: the top ceilings.
        AboveCeiling::Locked(..) => (c, 1.0),
    }
}

/// Configures the drives of `sim` with `settings` for `plan`, no motion
/// (the machine as commissioned before the run).
fn commission(sim: &mut Sim, plan: &Plan, settings: &DriveSettings, fd: bool) -> Option<()> {
    let configs = DriveConfigs::for_plan(plan, settings).ok()?.nodes;
    let opts = SessionOptions {
        fd,
        ..SessionOptions::default()
    };
    let mut session = Session::configure(configs, opts);
    loop {
        let mut port = SimPort {
            sim: &mut *sim,
            tx_queue: 32,
        };
        if session.poll(&mut port).ok()?.is_some() {
            return Some(());
        }
        let t = sim.now_ns() + 100_000;
        if t > 5_000_000_000 {
            return None;
        }
        sim.run_until(t).ok()?;
    }
}

fn spoil(plan: &Plan, bad: BadSegment) -> Plan {
    let mut p = plan.clone();
    match bad {
        BadSegment::Limits(k) => {
            let jerk = plan.limits.jerk;
            if let Some(s) = p.segments.get_mut(k) {
                // A t⁵ term: jerk 60 c t², twice the limit at the end; it
                // still starts where its predecessor ends (C3), so the
                // drives refuse it for its limits.
                let h = s.duration_s;
                for row in s.coeffs.iter_mut() {
                    row[5] += 2.0 * jerk / (60.0 * h * h);
                }
            }
        }
        BadSegment::Kink(k) => {
            if let Some(s) = p.segments.get_mut(k) {
                s.coeffs[0][1] += 0.02;
            }
        }
    }
    // The maxima of the plan as spoiled, as if the planner had written it
    // (the drives' stop ramps are sized from them).
    if let Ok(m) = sampled_max_abs(&p) {
        p.max_abs = m;
    }
    p
}

/// Segments a burst sends at once: more than a node's queue holds.
pub const BURST_SEGMENTS: usize = QUEUE_CAPACITY + 4;

const EMERGENCY_IDS: core::ops::RangeInclusive<u16> = 0x010..=0x013;

/// Runs `plan` under `sc` at 1 kHz and measures it.
pub fn run(plan: &Plan, sc: &Scenario) -> RunReport {
    let plan = match sc.bad_segment {
        Some(b) => spoil(plan, b),
        None => plan.clone(),
    };
    let mut settings = DriveSettings::default();
    if sc.brakes {
        settings.brake = [true; 3];
    }
    match sc.miswired {
        Some((i, Miswired::Direction)) => {
            settings.direction[i] = -settings.direction[i];
            settings.counts_per_metre[i] = -settings.counts_per_metre[i];
        }
        Some((i, Miswired::Scale(k))) => settings.counts_per_metre[i] *= k,
        None => {}
    }
    let ramp_factor = match sc.above_ceiling {
        Some(case) => {
            let (c, f) = ceilings_for(&plan, case);
            settings.ceilings = c;
            f
        }
        None => 1.0,
    };
    let DriveConfigs {
        nodes: mut configs,
        stop_time_s: stop_ramp_s,
        ..
    } = DriveConfigs::for_plan(&plan, &settings).expect("plan maxima");
    for c in &mut configs {
        c.stop_time *= ramp_factor as f32;
        c.quick_stop_time *= ramp_factor as f32;
    }
    // What the drives must refuse: a segment above a ceiling, or an
    // override cap that takes the plan above one. A short stop ramp they
    // raise to their own (docs/protocol.md, "Stop ramp"): running it whole
    // is right, within the stop budget.
    let must_refuse = match sc.above_ceiling {
        Some(AboveCeiling::Segment(..)) => true,
        Some(AboveCeiling::Locked(..)) => !sc.unlock_ceilings,
        Some(AboveCeiling::OverrideCap(_)) => {
            let m = triquint_shared::plan::figures::kinematics(&plan.segments);
            let [v, a, j] = m.largest();
            let k = configs[0].override_cap as f64;
            let c = &settings.ceilings;
            let over = 1.0 + triquint_shared::protocol::contract::RELATIVE_LIMIT_MARGIN as f64;
            k * v > c.velocity * over
                || k * k * a > c.acceleration * over
                || k * k * k * j > c.jerk * over
        }
        Some(AboveCeiling::StopRamp(_)) | None => false,
    };
    let mut cfg = SimConfig {
        fd: sc.fd,
        record_every: 1,
        brake: settings.brake,
        push: sc.push,
        ..SimConfig::default()
    };
    cfg.bus.capture = true;
    let q0 = plan.segments[0].quintic().eval(0.0).q;
    let mut sim = Sim::with_faults(&plan.robot, q0, cfg, sc.windows.clone(), sc.seed);
    if let Some(AboveCeiling::Locked(which, f)) = sc.above_ceiling {
        let (c, _) = ceilings_for(&plan, AboveCeiling::Segment(which, f));
        let tight = DriveSettings {
            ceilings: c,
            ..settings.clone()
        };
        commission(&mut sim, &plan, &tight, sc.fd).expect("commissioned");
    }
    let opts = SessionOptions {
        fd: sc.fd,
        finish_grace_us: 500_000,
        unlock_ceilings: sc.unlock_ceilings,
        ..SessionOptions::default()
    };
    let mut session = Session::new(&plan, configs, opts).expect("encodable plan");
    let wire = session.segments().to_vec();
    let mut host_alive = true;
    let mut host_error = None;
    let mut outcome = None;
    let mut burst_done = false;
    let mut reset_done = false;
    let limit_ns = ((plan.total_time_s + 15.0) * 1e9) as u64;
    let mut quiet_since: Option<u64> = None;
    // A node that is bus-off reports its final state only once back on
    // the bus: quiescence counts from the last bus-off's end.
    let bus_back_ns = sc
        .windows
        .iter()
        .filter(|w| matches!(w.fault, triquint_sim::Fault::BusOff { .. }))
        .map(|w| w.until_ns)
        .filter(|&t| t < limit_ns)
        .max()
        .unwrap_or(0);
    loop {
        let now = sim.now_ns();
        if sc.host_killed_ns.is_some_and(|t| now >= t) {
            host_alive = false;
        }
        if host_alive && outcome.is_none() {
            let mut port = SimPort {
                sim: &mut sim,
                tx_queue: 32,
            };
            match session.poll(&mut port) {
                Ok(Some(o)) => outcome = Some(o),
                Ok(None) => {}
                Err(e) => {
                    // The host gives up (as the CLI exits): it falls silent.
                    host_error = Some(e.to_string());
                    host_alive = false;
                }
            }
        } else {
            // A dead host's socket: whatever arrives is never read.
            while sim.host_receive().is_some() {}
        }
        if let Some(t) = sc.burst_ns
            && !burst_done
            && now >= t
        {
            burst_done = true;
            let next = sim.nodes[0].node.next_seq() as usize;
            for s in wire.iter().skip(next).take(BURST_SEGMENTS) {
                for f in s.frames(sc.fd) {
                    sim.host_send(f);
                }
            }
        }
        if let Some((i, t)) = sc.node_reset
            && !reset_done
            && now >= t
        {
            reset_done = true;
            sim.reset_node(i);
        }
        let t = now + 100_000;
        if let Err(e) = sim.run_until(t) {
            host_error = Some(format!("virtual machine: {e}"));
            break;
        }
        // Quiescent: nobody armed, running or stopping, and the host finished or silent.
        let busy = sim.nodes.iter().any(|n| {
            matches!(
                n.node.state(),
                State::Armed | State::Running | State::Stopping
            )
        });
        if !busy && (outcome.is_some() || !host_alive) {
            let q = (*quiet_since.get_or_insert(t)).max(bus_back_ns);
            // Let a few heartbeats report the final state.
            if t >= q + 300_000_000 {
                break;
            }
        } else {
            quiet_since = None;
        }
        if t > limit_ns {
            break;
        }
    }
    // Tracking and fault times from the start time the host commanded (the
    // host's clock is true time here), as `simulate` measures them; without
    // one (a burst or a replay started the drives), from the first Running
    // tick of any node. The first tick lags the start by up to a tick
    // period, which would read as tracking error of velocity × that lag.
    let first_start = match session.start_us() {
        0 => sim.nodes.iter().filter_map(|n| n.started_ns).min(),
        us => Some(us * 1000),
    };
    let mut report = run_report(
        &plan,
        &sim,
        first_start.unwrap_or(0),
        outcome.map_or(0, |o| o.segment_frames_sent),
        stop_ramp_s,
        sc.node_reset.map(|r| r.0),
    );
    let versions = session.versions().to_vec();
    let mut figures = fault_figures(&plan, &sim, sc, must_refuse, &wire, &versions, &report);
    figures.host_error = host_error;
    figures.retransmits = session.retransmits();
    figures.sync_timeout_ns = (settings.sync_timeout * 1e9) as u64;
    report.completed = figures.ending == Ending::Completed;
    report.fault_run = Some(figures);
    report
}

/// The fault run's own figures; `run` is the common report of the same run.
fn fault_figures(
    plan: &Plan,
    sim: &Sim,
    sc: &Scenario,
    must_refuse: bool,
    wire: &[WireSegment],
    versions: &[(u16, u32)],
    run: &RunReport,
) -> FaultRunFigures {
    let tick_ns = (1e9 / sim.cfg.rate_hz) as u64;
    let bad = sc.bad_segment.map(|b| match b {
        BadSegment::Limits(k) | BadSegment::Kink(k) => k,
    });
    let reset = sc.node_reset.map(|r| r.0);
    // What a drive may hold of segment k: a version the session sent
    // (compact ones as rebuilt), or the plan's segment in full (the burst).
    let mut sent: Vec<(u16, u32)> = versions.to_vec();
    sent.extend(wire.iter().map(|w| (w.seq, w.body_crc())));
    let mut corrupted = 0;
    let mut whole = true;
    for (i, seqs) in run.executed.iter().enumerate() {
        for &(seq, c) in seqs {
            let good = sent.contains(&(seq, c));
            if !good || Some(seq as usize) == bad {
                corrupted += 1;
            }
        }
        let in_order = seqs.iter().map(|e| e.0 as usize).eq(0..wire.len());
        if !in_order || Some(i) == reset {
            whole = false;
        }
    }
    let codes = [0, 1, 2].map(|i| sim.nodes[i].node.fault());
    let faults = sim.faults();
    let first_fault_ns = faults.first().map(|f| f.t_ns);
    let started = sim.nodes.iter().any(|n| n.started_ns.is_some());
    // Emergency arrival → first stopping tick, for nodes still running then.
    let mut e2s: Option<f64> = None;
    for n in &sim.nodes {
        let Some(arr) = n.emergency_rx_ns else {
            continue;
        };
        let running_at_arrival = n
            .states
            .iter()
            .rev()
            .find(|(t, _)| *t <= arr)
            .is_some_and(|(_, s)| *s == State::Running);
        if !running_at_arrival {
            continue;
        }
        if let Some((t, _)) = n
            .states
            .iter()
            .find(|(t, s)| *t >= arr && matches!(s, State::Stopping | State::Fault))
        {
            let ticks = (t - arr) as f64 / tick_ns as f64;
            e2s = Some(e2s.map_or(ticks, |x: f64| x.max(ticks)));
        }
    }
    let mut emergency_codes = Vec::new();
    let mut heartbeat_codes = Vec::new();
    let mut last_sync_ns = None;
    for &(t, station, f) in &sim.bus.capture {
        match decode(&f) {
            Ok((Msg::Emergency(e), node)) if EMERGENCY_IDS.contains(&f.id) && station <= 3 => {
                if let Some(c) = FaultCode::from_u8(e.code) {
                    emergency_codes.push((node, c));
                }
            }
            Ok((Msg::Heartbeat(h), node)) if h.fault != 0 && station <= 3 => {
                if let Some(c) = FaultCode::from_u8(h.fault)
                    && !heartbeat_codes.contains(&(node, c))
                {
                    heartbeat_codes.push((node, c));
                }
            }
            Ok((Msg::TimeSync(_), _)) if station == 0 => {
                let dropped = sc.windows.iter().any(|w| {
                    w.fault == triquint_sim::Fault::Loss { rate: 1.0 }
                        && w.ids.contains(&f.id)
                        && (w.from_ns..w.until_ns).contains(&t)
                });
                if !dropped {
                    last_sync_ns = Some(t);
                }
            }
            _ => {}
        }
    }
    let lost_sync_ns = faults
        .iter()
        .find(|f| f.code == FaultCode::LostSync)
        .map(|f| f.t_ns);
    let mut rejects = [0u32; triquint_shared::protocol::Reject::TABLE.len()];
    for n in &sim.nodes {
        for (k, r) in rejects.iter_mut().enumerate() {
            *r += n.node.stats.reason_counts[k] as u32;
        }
    }
    let max_stop_jerk = run.worst_stop_jerk();
    let any_fault = codes.iter().any(|c| *c != FaultCode::None) || !faults.is_empty();
    let all_idle = sim.nodes.iter().all(|n| n.node.state() == State::Idle);
    let running_left = sim.nodes.iter().any(|n| {
        matches!(
            n.node.state(),
            State::Running | State::Stopping | State::Armed
        )
    });
    let plan_jerk = sampled_max_abs(plan)
        .map(|m| m.jerk.iter().fold(0.0f64, |a, b| a.max(*b)))
        .unwrap_or(f64::INFINITY);
    let lim = plan.limits.jerk;
    // The stop's jerk budget B_s (docs/protocol.md, "Stop ramp"): the
    // limit, or the plan's own jerk at the override cap plus half the
    // limit, within the ceiling. A stop from σ ≤ 1 sized for its path (a
    // fault's, a dated Stop's) may use all of it.
    let cap = run.override_cap;
    let ceiling = sim
        .nodes
        .iter()
        .filter_map(|n| n.node.config())
        .map(|c| c.ceiling_jerk as f64)
        .fold(f64::INFINITY, f64::min);
    let stop_jerk_bound = lim.max(plan_jerk * cap.powi(3) + 0.5 * lim).min(ceiling) * 1.001;
    // The fault reactions (docs/protocol.md): with brakes every Fault at
    // rest is torque off; a miswired axis faults naming what is wrong.
    let reaction_wrong = sc.brakes
        && sim
            .nodes
            .iter()
            .any(|n| n.node.state() == State::Fault && !n.node.drive.is_torque_off());
    let miswire_missed = sc.miswired.is_some_and(|(i, _)| {
        !matches!(
            codes[i],
            FaultCode::WrongDirection | FaultCode::WrongScale | FaultCode::FollowingError
        )
    });
    // A plan above the drives' ceilings must never run whole.
    let ceiling_missed = must_refuse && whole;
    let ending = if corrupted > 0
        || ceiling_missed
        || running_left
        || max_stop_jerk > stop_jerk_bound
        || reaction_wrong
        || miswire_missed
    {
        Ending::Unsafe
    } else if whole && all_idle && !any_fault {
        Ending::Completed
    } else if !started {
        Ending::NotStarted
    } else if run.stop_s.is_some() && run.stopped_within_buffer {
        Ending::Stopped
    } else {
        Ending::Unsafe
    };
    FaultRunFigures {
        ending,
        codes,
        corrupted_executions: corrupted,
        executed_whole_plan: whole,
        first_fault_ns,
        stop_jerk_bound,
        emergency_to_stop_ticks: e2s,
        emergency_codes,
        heartbeat_codes,
        last_sync_ns,
        lost_sync_ns,
        host_error: None,
        retransmits: 0,
        rejects,
        injected: sim.faults.as_ref().map(|f| f.stats).unwrap_or_default(),
        tick_ns,
        start_ns: sim.nodes.iter().filter_map(|n| n.started_ns).min(),
        sync_timeout_ns: 0,
    }
}
