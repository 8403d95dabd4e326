//! Streaming capacity end to end: plans of many short segments
//! on the in-process virtual hardware, classic CAN and CAN-FD, each
//! checked against the streamability rule (`protocol::streaming`) before
//! it runs; the figures are printed (`--nocapture`) for docs/protocol.md.

use triquint_firmware::QUEUE_CAPACITY;
use triquint_link::{DriveConfigs, UploadError};
use triquint_shared::Limits;
use triquint_shared::plan::Plan;
use triquint_shared::protocol::compact::{Chain, DeviationBound};
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::streaming::StreamRule;
use triquint_sim::testplan;

use super::simulate::{SimulateError, SimulateOptions, simulate};

/// The rule for `plan` on this firmware's queue, default settings.
fn rule(plan: &Plan) -> StreamRule {
    let s = DriveSettings::default();
    let c = DriveConfigs::for_plan(plan, &s).unwrap();
    StreamRule::new(
        QUEUE_CAPACITY,
        c.stop_time_s,
        s.underrun_margin,
        s.heartbeat_period,
    )
}

fn durations(plan: &Plan) -> Vec<u32> {
    plan.wire_segments()
        .unwrap()
        .iter()
        .map(|w| w.duration_us)
        .collect()
}

/// Runs `plan` on classic CAN and CAN-FD: completed, no fault, every
/// segment executed; prints the bus load, and with `full_too` also that of
/// every segment sent in full (protocol version 3's frames) for the ratio.
fn runs_on_both_buses(name: &str, plan: &Plan, full_too: bool) {
    let r = rule(plan);
    let shortest = r.shortest_run(&durations(plan));
    eprintln!(
        "{name}: queue {}, look-ahead + refill {:.3} s, shortest run {:?} s",
        r.capacity,
        r.need_us() as f64 * 1e-6,
        shortest.map(|s| s.run_us as f64 * 1e-6)
    );
    for fd in [false, true] {
        let mut loads = Vec::new();
        for compact in if full_too {
            vec![true, false]
        } else {
            vec![true]
        } {
            let mut o = SimulateOptions {
                fd,
                ..SimulateOptions::default()
            };
            o.session.compact = compact;
            let r = simulate(plan, &o).unwrap();
            let what = format!("{name} fd={fd} compact={compact}");
            assert!(r.run.completed, "{what}: faults {:?}", r.faults_on_nodes);
            assert!(
                r.faults.is_empty() && r.faults_on_nodes.is_empty(),
                "{what}"
            );
            assert_eq!(compact, r.compact_sent > 0, "{what}");
            eprintln!(
                "{what}: {} segments, {:.3} s, {:.2} frames/segment ({} of {} sent compact), bus load {:.4} (segments {:.4}), {} retransmissions",
                plan.segments.len(),
                plan.total_time_s,
                r.frames_per_segment,
                r.compact_sent,
                r.segments_sent,
                r.run.bus_load,
                r.run.segment_bus_load,
                r.retransmits
            );
            loads.push((r.frames_per_segment, r.run.bus_load, r.run.segment_bus_load));
        }
        if let [c, f] = loads[..] {
            eprintln!(
                "{name} fd={fd}: compact / full: frames per segment x{:.3}, bus load x{:.3}, segment bus load x{:.3}",
                c.0 / f.0,
                c.1 / f.1,
                c.2 / f.2
            );
        }
    }
}

fn point_to_point(n: usize, t: f64, d: f64) -> Plan {
    testplan::point_to_point(n, t, d).unwrap()
}

fn helix(n: usize, t: f64, short: Option<f64>) -> Plan {
    testplan::helix(n, t, short).unwrap()
}

/// Sends `plan` through the link's chain (no bus): how many segments go
/// compact, and the largest position difference (m) between what a drive
/// holds and the plan's f64 segments, sampled 20 times a segment.
fn chain_figures(plan: &Plan) -> (usize, f64) {
    let mut chain = Chain::default();
    let (mut compact, mut worst) = (0, 0.0f64);
    for (w, s) in plan.wire_segments().unwrap().iter().zip(&plan.segments) {
        let sent = chain.next(w);
        compact += sent.is_compact() as usize;
        let b = sent.held().normalised_f64();
        let q = s.quintic();
        for i in 0..=20 {
            let tau = i as f64 / 20.0;
            let want = q.eval(tau * s.duration_s).q;
            for j in 0..3 {
                let got = b[j].iter().rev().fold(0.0, |acc, x| acc * tau + x);
                worst = worst.max((got - want[j]).abs());
            }
        }
    }
    (compact, worst)
}

#[test]
fn compact_segments_stay_within_the_bound_of_the_f64_plan() {
    let bound = DeviationBound::DEFAULT.position;
    for (name, plan, min_compact) in [
        ("15 segments", point_to_point(15, 0.9, 0.03), 14),
        // The segment after each 2 ms one goes in full.
        ("2 ms every tenth", helix(100, 20.0, Some(0.002)), 90),
        // About one in twenty re-anchors: f32 rounding of b_4, b_5 leaves
        // an end jerk error that the chain integrates.
        ("400 segments of 50 ms", helix(400, 20.0, None), 370),
    ] {
        let (compact, worst) = chain_figures(&plan);
        eprintln!(
            "{name}: {compact} of {} compact, drive segments within {worst:.3e} m of the f64 plan",
            plan.segments.len()
        );
        // The bound, plus the full encoding's own rounding (2^-40 m a coefficient).
        assert!(worst <= bound + 1e-11, "{name}: {worst:e} m");
        assert!(compact >= min_compact, "{name}: {compact} compact");
    }
}

#[test]
fn a_fifteen_segment_move_under_a_second_streams() {
    let plan = point_to_point(15, 0.9, 0.03);
    assert_eq!(plan.segments.len(), 15);
    // Within the limits, so the stop ramp is the plan's own.
    let l = Limits::default();
    for j in 0..3 {
        assert!(plan.max_abs.jerk[j] <= l.jerk && plan.max_abs.velocity[j] <= l.velocity);
    }
    assert_eq!(rule(&plan).check(&durations(&plan)), Ok(()));
    runs_on_both_buses("15 segments in 0.9 s", &plan, true);
}

#[test]
fn a_2_ms_segment_every_tenth_streams() {
    let plan = helix(100, 20.0, Some(0.002));
    assert_eq!(
        plan.segments
            .iter()
            .filter(|s| s.duration_s < 0.0025)
            .count(),
        10
    );
    assert_eq!(rule(&plan).check(&durations(&plan)), Ok(()));
    runs_on_both_buses("2 ms every tenth", &plan, true);
}

#[test]
fn a_2000_segment_plan_streams() {
    let plan = helix(2000, 100.0, None);
    assert_eq!(rule(&plan).check(&durations(&plan)), Ok(()));
    runs_on_both_buses("2000 segments", &plan, false);
}

#[test]
fn an_unstreamable_plan_is_refused_before_anything_moves() {
    // 300 segments in 3 s: 10 ms each, far less than the look-ahead in a
    // queue's worth.
    let plan = helix(300, 3.0, None);
    let e = rule(&plan).check(&durations(&plan)).unwrap_err();
    assert!(e.run_us < e.need_us);
    let o = SimulateOptions::default();
    match simulate(&plan, &o) {
        Err(SimulateError::Upload(UploadError::Unstreamable {
            capacity,
            first,
            last,
            ..
        })) => {
            assert_eq!(capacity, QUEUE_CAPACITY);
            assert_eq!(last - first + 1, QUEUE_CAPACITY - 1);
        }
        other => panic!("not refused: {:?}", other.map(|r| r.run.completed)),
    }
}
