//! The run report of an in-process run, from the simulator's records: one
//! function for `simulate` and the fault runs, so that what they report
//! cannot drift apart.

use triquint_shared::plan::Plan;
use triquint_shared::protocol::State;
use triquint_sim::Sim;
use triquint_sim::metrics;
use triquint_sim::report::{JsonFault, RunReport};

/// What `sim` recorded running `plan`: times from `start_ns` (true time;
/// the tracking is measured from it, fault times are relative to it),
/// `segment_frames` segment parts sent by the host, drives configured with
/// the stop ramp `stop_ramp_s`. `reset`: a node power-cycled during the run.
/// `completed` is left false: whether the run completed is the caller's.
pub(crate) fn run_report(
    plan: &Plan,
    sim: &Sim,
    start_ns: u64,
    segment_frames: u64,
    stop_ramp_s: f64,
    reset: Option<usize>,
) -> RunReport {
    let now = sim.now_ns().max(1);
    // Whole microseconds (the host's clock) exactly as `start_us * 1e-6`.
    let start_s = (start_ns / 1000) as f64 * 1e-6 + (start_ns % 1000) as f64 * 1e-9;
    let started: Vec<u64> = sim.nodes.iter().filter_map(|n| n.started_ns).collect();
    let (stop_ns, stopped_within_buffer) = stop_figures(sim, plan.segments.len(), reset);
    let mut run = RunReport {
        peak_torque_nm: [0, 1, 2].map(|i| sim.nodes[i].peak_torque as f64),
        bus_load: sim.bus.busy_ns() as f64 / now as f64,
        frames: sim.bus.frames(),
        faults: sim
            .faults()
            .iter()
            .map(|f| JsonFault::new(f, f.t_ns as f64 * 1e-9 - start_s))
            .collect(),
        completed: false,
        segment_bus_load: sim.bus.segment_busy_ns() as f64 / now as f64,
        segment_frames,
        segments: plan.segments.len(),
        plan_time_s: plan.total_time_s,
        duration_s: now as f64 * 1e-9,
        start_skew_us: match (started.iter().min(), started.iter().max()) {
            (Some(a), Some(b)) => (b - a) as f64 * 1e-3,
            _ => 0.0,
        },
        executed: sim
            .nodes
            .iter()
            .map(|n| n.executed.iter().map(|e| (e.1, e.2)).collect())
            .collect(),
        stop_s: stop_ns.map(|t| t as f64 * 1e-9),
        stopped_within_buffer,
        max_stop_jerk: [0, 1, 2].map(|i| sim.nodes[i].max_stop_jerk as f64),
        stop_ramp_s,
        override_cap: RunReport::override_cap_of(sim.nodes.iter().filter_map(|n| n.node.config())),
        ..RunReport::default()
    };
    run.set_tracking(&metrics::tracking(plan, start_ns, &sim.samples));
    run
}

/// From the first fault on any node (true ns) to every axis that was
/// running at rest, and whether each stopped node came to rest inside the
/// plan time it had buffered. `reset`: a node power-cycled during the run
/// (it has no motor to stop).
pub fn stop_figures(sim: &Sim, n_segments: usize, reset: Option<usize>) -> (Option<u64>, bool) {
    let first_fault_ns = sim.faults().first().map(|f| f.t_ns);
    let started = sim.nodes.iter().any(|n| n.started_ns.is_some());
    // Rest: the first tick in Fault after the first fault, for every node
    // that was running (the reset node has no motor to stop).
    let mut rest_ns: Option<u64> = Some(0);
    let mut within = true;
    for (i, n) in sim.nodes.iter().enumerate() {
        if Some(i) == reset || n.started_ns.is_none() {
            continue;
        }
        let at = first_fault_ns.and_then(|f| {
            n.states
                .iter()
                .find(|(t, s)| *t >= f && *s == State::Fault)
                .map(|x| x.0)
        });
        let finished = n.node.state() == State::Idle && n.executed.len() == n_segments;
        rest_ns = match (rest_ns, at) {
            (Some(a), Some(b)) => Some(a.max(b)),
            (Some(a), None) if finished => Some(a),
            _ => None,
        };
        // Past the buffered end is allowed only when the buffer ended with
        // the plan's last segment: the plan ends at rest, so the path does too.
        let had_last = n.executed.iter().any(|e| e.1 as usize + 1 == n_segments);
        if n.node.state() == State::Fault
            && n.node.plan_ns() > n.node.buffered_end_ns()
            && !had_last
        {
            within = false;
        }
    }
    let stop_time_ns = match (first_fault_ns, rest_ns) {
        (Some(f), Some(r)) if started => Some(r.saturating_sub(f)),
        _ => None,
    };
    (stop_time_ns, within)
}
