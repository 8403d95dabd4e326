//! Fault stops at seeded instants: the host goes silent (its session no
//! longer polled: no segment, no time sync, no frame at all) at plan times
//! drawn from a seeded generator, and the drives stop on their own. The
//! first to notice faults (Underrun: its queue runs short; or LostSync: no
//! time sync within the sync timeout) and stops along the path; its
//! Emergency stops the others (PeerEmergency). Every run must end with
//! every drive in Fault, at rest, the platform on the planned path
//! throughout, the stop no longer than the full ramp the drives run (the
//! configured one, or their queue's own where longer) and on average
//! shorter (the ramp for the path it passes through, docs/protocol.md "A
//! ramp for a fault stop"), and every node's ramp dated to the same
//! instant. The figures are printed (`--nocapture`).
//!
//! On these plans the drives' queues hold more plan than the longest a
//! silence goes unnoticed (a sync period and the sync timeout), so the
//! first fault is LostSync, never Underrun; and a run depends only on the
//! last time sync before the silence, so instants within one sync period
//! give the same run. A node that notices the lost sync itself dates its
//! stop at the instant the sync was lost in host time, and a peer that
//! takes an Emergency at the sender's plan time, so every axis stops on
//! the same σ(t) although they notice up to a frame time (~150 µs) apart.

use std::collections::BTreeMap;

use triquint_link::{DriveConfigs, SessionOptions};
use triquint_shared::plan::Plan;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{FaultCode, State};
use triquint_sim::testplan;

use super::stop_harness::{
    Ending, Path, Run, SETTLE_NS, bounds, branch_runs, committed_plan, seeded_instants,
};

/// How long the silent host leaves the drives to end in Fault (ns).
const FAULT_WITHIN_NS: u64 = 3_000_000_000;
/// A fault stop may take this much longer than the full ramp: the
/// detection's tick and the Emergency's way to the peers (s).
const STOP_SLACK_S: f64 = 0.05;

#[test]
fn a_fault_stop_at_40_instants_of_the_15_segment_move_ends_on_the_path() {
    fault_stops_end_on_the_path(
        "15 segments in 0.9 s",
        &testplan::point_to_point(15, 0.9, 0.03).unwrap(),
        40,
        135,
    );
}

#[test]
fn a_fault_stop_at_30_instants_of_case_1_ends_on_the_path() {
    fault_stops_end_on_the_path("Case I", &committed_plan("case1-spline"), 30, 137);
}

#[test]
fn a_fault_stop_at_40_instants_of_the_2_ms_every_tenth_plan_ends_on_the_path() {
    fault_stops_end_on_the_path(
        "2 ms every tenth",
        &testplan::helix(100, 20.0, Some(0.002)).unwrap(),
        40,
        136,
    );
}

#[test]
fn a_fault_stop_at_30_instants_of_case_2_ends_on_the_path() {
    fault_stops_end_on_the_path("Case II", &committed_plan("case2-spline"), 30, 138);
}

#[test]
fn a_fault_stop_at_30_instants_of_the_spiral_ends_on_the_path() {
    fault_stops_end_on_the_path("spiral", &committed_plan("spiral-spline"), 30, 139);
}

/// One run whose host fell silent.
#[derive(Clone, Debug)]
struct FaultStop {
    /// Plan time at which the host fell silent (s).
    at_s: f64,
    /// The first node to stop on a fault of its own (not a peer's), and
    /// that fault.
    detector: Option<(u8, FaultCode)>,
    /// Each node's fault at the end.
    faults: [FaultCode; 3],
    /// From the first node Stopping to the last in Fault (true time, s).
    stop_s: f64,
    /// Each node's ramp as it entered Stopping (ns; 0: never Stopping).
    ramps_ns: [i64; 3],
    /// The spread of the host times the nodes' ramps began at (s): each
    /// dates its stop to the instant the sync was lost or to the
    /// Emergency's sender's plan time.
    skew_s: f64,
    /// The largest of any drive's own stop ramp for its queue (ns).
    own_ramp_ns: i64,
    /// Largest |joint jerk| of any drive's reference while Stopping (m/s³).
    jerk: f64,
    /// Where it ended, against the path, from the silence on.
    ending: Ending,
    /// Every node in Fault at the end.
    clean: bool,
}

/// The host falls silent now: the drives run on alone until every one is
/// in Fault (at most [`FAULT_WITHIN_NS`]), then [`SETTLE_NS`] more.
fn fall_silent(mut run: Run, plan: &Plan, at_s: f64) -> FaultStop {
    let silent = run.sim.now_ns();
    let in_fault = |run: &Run| run.sim.nodes.iter().all(|n| n.node.state() == State::Fault);
    let mut ramps_ns = [0; 3];
    let mut began_ns = [None; 3];
    while !in_fault(&run) && run.sim.now_ns() < silent + FAULT_WITHIN_NS {
        run.sim.run_until(run.sim.now_ns() + 100_000).unwrap();
        run.track_ramps();
        for (i, n) in run.sim.nodes.iter().enumerate() {
            if began_ns[i].is_none() && n.node.state() == State::Stopping {
                let scaling = n.node.drive.scaling();
                ramps_ns[i] = scaling.ramp_ns;
                began_ns[i] = Some(scaling.t0_ns);
            }
        }
    }
    let Run {
        mut sim,
        own_ramp_ns,
        ..
    } = run;
    sim.run_until(sim.now_ns() + SETTLE_NS).unwrap();
    // Each node's first entry into `state` after the silence (true time).
    let entered = |i: usize, state: State| {
        sim.nodes[i]
            .states
            .iter()
            .find(|(t, s)| *t >= silent && *s == state)
            .map(|x| x.0)
    };
    let first_fault = |i: usize| {
        sim.nodes[i]
            .faults
            .iter()
            .find(|f| f.t_ns >= silent)
            .map(|f| f.code)
    };
    let mut by_stop: Vec<(u64, usize)> = (0..3)
        .filter_map(|i| entered(i, State::Stopping).map(|t| (t, i)))
        .collect();
    by_stop.sort();
    let detector = by_stop.iter().find_map(|&(_, i)| {
        first_fault(i)
            .filter(|c| *c != FaultCode::PeerEmergency)
            .map(|c| (sim.nodes[i].node.node_id(), c))
    });
    let stopping = by_stop.first().map_or(u64::MAX, |x| x.0);
    let faulted = (0..3)
        .map(|i| entered(i, State::Fault).unwrap_or(u64::MAX))
        .max()
        .unwrap_or(u64::MAX);
    let clean = sim.nodes.iter().all(|n| n.node.state() == State::Fault);
    // The path from a little before the silence to where the drives came
    // to rest (plan time).
    let rest_plan_s = sim
        .nodes
        .iter()
        .map(|n| n.node.drive.plan_ns() as f64 * 1e-9)
        .fold(at_s, f64::max);
    let path = Path::new(plan, at_s - 0.1, rest_plan_s + 0.1);
    FaultStop {
        at_s,
        detector,
        faults: [0, 1, 2].map(|i| sim.nodes[i].node.drive.fault()),
        stop_s: if faulted == u64::MAX || stopping == u64::MAX {
            f64::INFINITY
        } else {
            faulted.saturating_sub(stopping) as f64 * 1e-9
        },
        ramps_ns,
        skew_s: match (
            began_ns.iter().flatten().min(),
            began_ns.iter().flatten().max(),
        ) {
            (Some(a), Some(b)) => (b - a) as f64 * 1e-9,
            _ => 0.0,
        },
        own_ramp_ns,
        jerk: sim
            .nodes
            .iter()
            .map(|n| n.max_stop_jerk as f64)
            .fold(0.0, f64::max),
        ending: Ending::of(&sim, &path, silent),
        clean,
    }
}

/// "Code ×count" of each code in `codes`, in code order.
fn tally(codes: impl Iterator<Item = Option<FaultCode>>) -> String {
    let mut counts: BTreeMap<u8, (String, usize)> = BTreeMap::new();
    for c in codes {
        let (key, name) = c.map_or((0, "none".to_string()), |c| (c as u8, format!("{c:?}")));
        counts.entry(key).or_insert((name, 0)).1 += 1;
    }
    let parts: Vec<String> = counts
        .values()
        .map(|(name, k)| format!("{name} ×{k}"))
        .collect();
    parts.join(", ")
}

/// The host falls silent at `n` seeded instants of `plan` in its middle:
/// from 0.05 s on, and not within the full ramp of its end, nor within the
/// longest the drives can take to miss the time syncs (a sync period and
/// the sync timeout), where the plan could end before they fault. Asserts
/// each run and prints the figures.
fn fault_stops_end_on_the_path(name: &str, plan: &Plan, n: usize, seed: u64) {
    let settings = DriveSettings::default();
    let configs = DriveConfigs::for_plan(plan, &settings).unwrap();
    let full_s = configs.stop_time_s;
    let unnoticed_s =
        settings.sync_timeout + SessionOptions::default().sync_period_us as f64 * 1e-6;
    let instants = seeded_instants(seed, n, 0.05..plan.total_time_s - full_s.max(unnoticed_s));
    let runs = branch_runs(plan, &configs, &instants, |run, at_s| {
        fall_silent(run, plan, at_s)
    });
    let bound = |r: &FaultStop| full_s.max(r.own_ramp_ns as f64 * 1e-9) + STOP_SLACK_S;
    // The stop's jerk within the drives' budget B_s.
    let b = bounds(plan, &configs);
    let unsafe_endings: Vec<&FaultStop> = runs
        .iter()
        .filter(|r| {
            !r.clean
                || !matches!(
                    r.detector,
                    Some((_, FaultCode::Underrun | FaultCode::LostSync))
                )
                || r.ending.is_unsafe()
                || r.stop_s > bound(r)
                || r.jerk > b.jerk * 1.001
        })
        .collect();
    let worst = |f: fn(&FaultStop) -> f64| runs.iter().map(f).fold(0.0, f64::max);
    let stops = runs.iter().map(|r| r.stop_s);
    let (min, max) = (
        stops.clone().fold(f64::INFINITY, f64::min),
        stops.clone().fold(0.0, f64::max),
    );
    let mean = stops.sum::<f64>() / runs.len().max(1) as f64;
    let ramps = runs.iter().flat_map(|r| r.ramps_ns).filter(|r| *r > 0);
    let (ramp_min, ramp_max) = ramps.fold((i64::MAX, 0), |(lo, hi), r| (lo.min(r), hi.max(r)));
    let (ramp_min, ramp_max) = (ramp_min as f64 * 1e-9, ramp_max as f64 * 1e-9);
    let own_ramp = worst(|r| r.own_ramp_ns as f64 * 1e-9);
    let worst_bound = runs.iter().map(bound).fold(0.0, f64::max);
    let detected = tally(runs.iter().map(|r| r.detector.map(|d| d.1)));
    let nodes = tally(runs.iter().flat_map(|r| r.faults.map(Some)));
    let skew_us = worst(|r| r.skew_s) * 1e6;
    let off_um = worst(|r| r.ending.off_path_m) * 1e6;
    let worst_at = runs
        .iter()
        .max_by(|a, b| a.ending.off_path_m.total_cmp(&b.ending.off_path_m))
        .map_or(0.0, |r| r.at_s);
    let rest_um = worst(|r| r.ending.rest_off_path_m) * 1e6;
    let rest_speed = worst(|r| r.ending.rest_speed);
    let jerk = worst(|r| r.jerk);
    eprintln!(
        "{name}: {n} fault stops ({} unsafe), T_s {full_s:.3} s: mean stop {mean:.3} s (×{:.3} of T_s), \
         min {min:.3} s, max {max:.3} s (bound {worst_bound:.3} s), detected by {detected} \
         (nodes' faults {nodes}), ramps run {ramp_min:.3}–{ramp_max:.3} s, drives' own ramp up to \
         {own_ramp:.3} s, stop instants apart up to {skew_us:.0} µs; worst off path {off_um:.2} µm \
         (silent at {worst_at:.3} s; at rest {rest_um:.2} µm), rest speed {rest_speed:.1e} m/s, \
         worst stop jerk {jerk:.3} of {:.3} m/s³",
        unsafe_endings.len(),
        mean / full_s,
        b.jerk,
    );
    assert!(unsafe_endings.is_empty(), "{name}: {unsafe_endings:#?}");
    // The ramp for the path the stop passes through, not the largest held:
    // the full ramp on every run would be ×1.
    assert!(
        mean < 0.85 * full_s,
        "{name}: mean fault stop {mean:.3} s against T_s {full_s:.3} s"
    );
    // Every node's σ(t) dated to the same instant (docs/protocol.md, "A
    // ramp for a fault stop"): one frame time apart would be ~140 µs.
    assert!(skew_us < 50.0, "{name}: stops {skew_us:.0} µs apart");
}
