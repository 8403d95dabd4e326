//! Streaming capacity end to end: plans of many short segments
//! on the in-process virtual hardware, classic CAN and CAN-FD, each
//! checked against the streamability rule (`protocol::streaming`) before
//! it runs; the figures are printed (`--nocapture`) for docs/protocol.md.

use triquint_firmware::QUEUE_CAPACITY;
use triquint_firmware::segment::Seg;
use triquint_link::{DriveConfigs, UploadError};
use triquint_shared::Limits;
use triquint_shared::plan::Plan;
use triquint_shared::protocol::compact::{Chain, DeviationBound};
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::segment::COEFF_SCALE;
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
/// segment executed, at least `min_compact` segments sent compact; prints
/// the bus load, and with `full_too` also that of every segment sent in
/// full (protocol version 3's frames) for the ratio.
fn runs_on_both_buses(name: &str, plan: &Plan, full_too: bool, min_compact: u64) {
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
            if compact {
                assert!(r.compact_sent >= min_compact, "{what}: {}", r.compact_sent);
            }
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

/// What a drive holds of a segment against the plan's f64 segment, per
/// derivative by time (position to jerk), worst over a plan.
#[derive(Clone, Copy, Debug, Default)]
struct Worst {
    /// The wire form (integer units, compact ones as rebuilt).
    wire: [f64; 4],
    /// The held form (`Seg`: f32 normalised coefficients, duration in µs).
    held: [f64; 4],
}

/// k!/(k−m)!: the factor of b_k in the m-th derivative by τ.
fn falling(k: usize, m: usize) -> f64 {
    (0..m).map(|i| (k - i) as f64).product()
}

/// Per derivative m, Σ_k k!/(k−m)! |c_k| / h^m: how far coefficient errors
/// c_k of a normalised segment move its m-th derivative at most.
fn spread(c: &[f64; 6], h: f64) -> [f64; 4] {
    core::array::from_fn(|m| {
        (m..6).map(|k| falling(k, m) * c[k].abs()).sum::<f64>() / h.powi(m as i32)
    })
}

/// Position and its first three derivatives by time at τ of a normalised polynomial.
fn eval_normalised(b: &[f64; 6], tau: f64, h: f64) -> [f64; 4] {
    core::array::from_fn(|m| {
        (m..6)
            .map(|k| falling(k, m) * b[k] * tau.powi((k - m) as i32))
            .sum::<f64>()
            / h.powi(m as i32)
    })
}

/// Sends `plan` through the link's chain (no bus): how many segments go
/// compact, and how far what a drive holds is from the plan's f64
/// segments, sampled 21 times a segment. Asserts at every sample the
/// stated bounds: the wire form within [`DeviationBound::DEFAULT`] plus the
/// full encoding's rounding (half a unit of 2⁻⁴⁰ m a coefficient); the
/// held form within that plus the f32 rounding of each coefficient
/// (2⁻²⁴ |b_k|, round to nearest).
fn chain_figures(plan: &Plan) -> (usize, Worst) {
    let d = DeviationBound::DEFAULT;
    let bound = [d.position, d.velocity, d.acceleration, d.jerk];
    let mut chain = Chain::default();
    let (mut compact, mut worst) = (0, Worst::default());
    let wire = plan.wire_segments().unwrap();
    for (i, (w, s)) in wire.iter().zip(&plan.segments).enumerate() {
        let sent = chain.next(w, wire.get(i + 1));
        compact += sent.is_compact() as usize;
        let h = w.duration_us as f64 * 1e-6;
        let wire = sent.held().normalised_f64();
        let held = Seg::from_wire(sent.held(), 0).b;
        let q = s.quintic();
        let encoding = spread(&[0.5 * COEFF_SCALE; 6], h);
        for j in 0..3 {
            let held = held[j].map(f64::from);
            let f32_rounding = spread(&held.map(|x| x * f64::from(f32::EPSILON) * 0.5), h);
            for i in 0..=20 {
                let tau = i as f64 / 20.0;
                let want = q.eval(tau * s.duration_s);
                let want = [want.q[j], want.qd[j], want.qdd[j], want.qddd[j]];
                let got_wire = eval_normalised(&wire[j], tau, h);
                let got_held = eval_normalised(&held, tau, h);
                for m in 0..4 {
                    let ew = (got_wire[m] - want[m]).abs();
                    let eh = (got_held[m] - want[m]).abs();
                    // The f64 evaluations' own rounding.
                    let slack = 1e-12 * (want[m].abs() + spread(&wire[j], h)[m]);
                    assert!(
                        ew <= bound[m] + encoding[m] + slack,
                        "wire, derivative {m}: {ew:e}"
                    );
                    assert!(
                        eh <= bound[m] + encoding[m] + f32_rounding[m] + slack,
                        "held, derivative {m}: {eh:e}"
                    );
                    worst.wire[m] = worst.wire[m].max(ew);
                    worst.held[m] = worst.held[m].max(eh);
                }
            }
        }
    }
    (compact, worst)
}

#[test]
fn compact_segments_stay_within_the_bound_of_the_f64_plan() {
    for (name, plan, min_compact) in [
        ("15 segments", point_to_point(15, 0.9, 0.03), 14),
        // The segment after each 2 ms one, 111 times longer, continues
        // the short one's end in fine units (its integer end jerk,
        // magnified 111³, would break the bound).
        ("2 ms every tenth", helix(100, 20.0, Some(0.002)), 99),
        // Only the first in full: each continuation corrects the
        // deviation it inherits (without that, one in 24 re-anchored).
        ("400 segments of 50 ms", helix(400, 20.0, None), 399),
    ] {
        let (compact, w) = chain_figures(&plan);
        eprintln!(
            "{name}: {compact} of {} compact; worst against the f64 plan (q, q', q'', q'''): \
             wire form {:.3e} m, {:.3e} m/s, {:.3e} m/s², {:.3e} m/s³; \
             held form {:.3e} m, {:.3e} m/s, {:.3e} m/s², {:.3e} m/s³",
            plan.segments.len(),
            w.wire[0],
            w.wire[1],
            w.wire[2],
            w.wire[3],
            w.held[0],
            w.held[1],
            w.held[2],
            w.held[3],
        );
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
    // The first in full: this test plan starts with a jerk.
    runs_on_both_buses("15 segments in 0.9 s", &plan, true, 14);
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
    // The segments after the 2 ms ones too (fine units).
    runs_on_both_buses("2 ms every tenth", &plan, true, 99);
}

#[test]
fn a_2000_segment_plan_streams() {
    let plan = helix(2000, 100.0, None);
    assert_eq!(rule(&plan).check(&durations(&plan)), Ok(()));
    // The first too: it starts at rest within the bound (from rest).
    runs_on_both_buses("2000 segments", &plan, false, 2000);
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

#[test]
fn the_vm_suites_fixtures_pass_the_check_and_the_streaming_rule() {
    for (name, plan) in testplan::streaming_fixtures().unwrap() {
        let failed: Vec<_> = triquint_planner::check(&plan)
            .unwrap()
            .into_iter()
            .filter(|r| !r.ok)
            .collect();
        assert!(failed.is_empty(), "{name}: {failed:?}");
        assert_eq!(rule(&plan).check(&durations(&plan)), Ok(()), "{name}");
    }
}
