//! What a run measured: tracking error against the host's f64 plan, torque,
//! bus load, start skew, and the f32-vs-f64 evaluation error of the drives.

use triquint_firmware::segment::Seg;
use triquint_shared::plan::{Plan, Segment, eval};
use triquint_shared::protocol::WireSegment;

use crate::sim::Sample;

/// Per-axis tracking statistics over the plan's duration.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Tracking {
    pub rms_error_m: [f64; 3],
    pub max_error_m: [f64; 3],
    pub samples: usize,
}

/// Plan position of every joint at plan time `t` (s), clamped to the plan
/// ([`Plan::at`]); zeros for a plan with no segments, NaN for a NaN `t`.
pub fn plan_position(plan: &Plan, t: f64) -> [f64; 3] {
    segments_position(&plan.segments, t)
}

/// Position of every joint at time `t` (s) along consecutive segments
/// ([`eval::at`]: the start position before them, the end position after);
/// zeros for no segments, NaN for a NaN `t`.
pub fn segments_position(segments: &[Segment], t: f64) -> [f64; 3] {
    segments_position_within(segments, eval::duration(segments), t)
}

/// [`segments_position`] with the segments' duration already known.
fn segments_position_within(segments: &[Segment], duration: f64, t: f64) -> [f64; 3] {
    match eval::at_within(segments, duration, t) {
        Some(s) => s.q,
        None if t.is_nan() && !segments.is_empty() => [f64::NAN; 3],
        None => [0.0; 3],
    }
}

/// Tracking error of the plant (true joint positions) against the f64 plan
/// at true time − start, over [start, start + total time].
pub fn tracking(plan: &Plan, start_ns: u64, samples: &[Sample]) -> Tracking {
    tracking_segments(&plan.segments, plan.total_time_s, start_ns, samples)
}

/// [`tracking`] against consecutive segments lasting `total_time_s`.
pub fn tracking_segments(
    segments: &[Segment],
    total_time_s: f64,
    start_ns: u64,
    samples: &[Sample],
) -> Tracking {
    let end_ns = start_ns + (total_time_s * 1e9) as u64;
    // Summed once: a run's samples times its segments would be quadratic.
    let duration = eval::duration(segments);
    let mut sum = [0.0; 3];
    let mut out = Tracking::default();
    for s in samples
        .iter()
        .filter(|s| s.t_ns >= start_ns && s.t_ns <= end_ns)
    {
        let t = (s.t_ns - start_ns) as f64 * 1e-9;
        let r = segments_position_within(segments, duration, t.min(total_time_s));
        for j in 0..3 {
            let e = s.q[j] - r[j];
            sum[j] += e * e;
            out.max_error_m[j] = out.max_error_m[j].max(e.abs());
        }
        out.samples += 1;
    }
    for j in 0..3 {
        out.rms_error_m[j] = (sum[j] / out.samples.max(1) as f64).sqrt();
    }
    out
}

/// A received wire segment as a plan segment starting at `t0_s`: the
/// normalised-time coefficients b_jk (m) back to c_jk = b_jk / h^k.
pub fn segment_from_wire(w: &WireSegment, t0_s: f64) -> Segment {
    let h = w.duration_us as f64 * 1e-6;
    let b = w.normalised_f64();
    let coeffs = b.map(|row| {
        let mut c = [0.0; 6];
        let mut hk = 1.0;
        for k in 0..6 {
            c[k] = row[k] / hk;
            hk *= h;
        }
        c
    });
    Segment {
        t0_s,
        duration_s: h,
        coeffs,
    }
}

/// Largest |q_f32 − q_f64| (m) over a whole plan: each segment goes through
/// the wire encoding as the link sends it (compact segments rebuilt from the
/// one before) and the drive's f32 normalised-time evaluation, sampled
/// `per_segment` times, against the plan's f64 coefficients.
pub fn f32_eval_error(plan: &Plan, per_segment: usize) -> f64 {
    let mut worst: f64 = 0.0;
    let mut start_ns = 0i64;
    let mut chain = triquint_shared::protocol::compact::Chain::default();
    let Ok(wire) = plan.wire_segments() else {
        return f64::INFINITY;
    };
    for (i, (w, s)) in wire.iter().zip(&plan.segments).enumerate() {
        // As the drive holds it: compact segments rebuilt from the one before.
        let seg = Seg::from_wire(chain.next(w, wire.get(i + 1)).held(), start_ns);
        let q = s.quintic();
        for k in 0..=per_segment {
            let d_ns = seg.duration_ns() * k as i64 / per_segment as i64;
            let a = seg.eval(start_ns + d_ns);
            let b = q.eval(d_ns as f64 * 1e-9);
            for j in 0..3 {
                worst = worst.max((a.q[j] as f64 - b.q[j]).abs());
            }
        }
        start_ns = seg.end_ns();
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testplan;

    #[test]
    fn f32_drive_evaluation_tracks_the_f64_plan_within_a_micrometre() {
        for plan in [
            testplan::paper_case1().unwrap(),
            testplan::paper_case2().unwrap(),
            testplan::spiral(121, 3.0, 30.0).unwrap(),
        ] {
            let e = f32_eval_error(&plan, 2000);
            assert!(e < 1e-6, "f32 evaluation error {e:e} m");
            assert!(e > 0.0, "f32 must differ from f64 somewhere");
        }
    }

    #[test]
    fn wire_segments_give_back_the_plan() {
        let plan = testplan::paper_case2().unwrap();
        let mut t0 = 0.0;
        let mut got = Vec::new();
        for (i, s) in plan.segments.iter().enumerate() {
            let w = WireSegment::from_quintic(i as u16, &s.quintic(), 0).unwrap();
            let seg = segment_from_wire(&w, t0);
            t0 += seg.duration_s;
            got.push(seg);
        }
        assert!((t0 - plan.total_time_s).abs() < 1e-9);
        for k in 0..=500 {
            let t = plan.total_time_s * k as f64 / 500.0;
            let (a, b) = (plan_position(&plan, t), segments_position(&got, t));
            for j in 0..3 {
                assert!((a[j] - b[j]).abs() < 1e-9, "t {t}: {} vs {}", a[j], b[j]);
            }
        }
    }

    /// The planner's plans through the shared evaluation: duration, the end
    /// sample, q/v/a continuity at every knot, rest outside the plan.
    #[test]
    fn real_plans_evaluate_consistently() {
        for plan in [
            testplan::paper_case1().unwrap(),
            testplan::paper_case2().unwrap(),
            testplan::spiral(121, 3.0, 30.0).unwrap(),
        ] {
            let d = plan.duration();
            assert!((d - plan.total_time_s).abs() < 1e-9);
            let samples: Vec<_> = plan.sample(1e-3).unwrap().collect();
            assert_eq!(samples.last().map(|s| s.0), Some(d));
            for (t, s) in samples.iter().step_by(97) {
                assert_eq!(plan_position(&plan, *t), s.q);
            }
            for (i, s) in plan.segments.iter().enumerate().skip(1) {
                assert_eq!(plan.segment_at(s.t0_s).map(|(k, _)| k), Some(i));
                let before = plan.segments[i - 1].quintic().end();
                let after = plan.at(s.t0_s).unwrap();
                for j in 0..3 {
                    assert!((before.q[j] - after.q[j]).abs() < 1e-9);
                    assert!((before.qd[j] - after.v[j]).abs() < 1e-8);
                    assert!((before.qdd[j] - after.a[j]).abs() < 1e-7);
                }
            }
            let end = plan.at(d + 1.0).unwrap();
            assert_eq!((end.v, end.a, end.jerk), ([0.0; 3], [0.0; 3], [0.0; 3]));
            let (a, b) = (plan_position(&plan, d + 1.0), plan_position(&plan, d));
            assert!((0..3).all(|j| (a[j] - b[j]).abs() < 1e-12));
            assert_eq!(plan_position(&plan, -1.0), plan_position(&plan, 0.0));
        }
    }

    #[test]
    fn position_of_no_segments_is_zero_and_of_nan_is_nan() {
        assert_eq!(segments_position(&[], 0.5), [0.0; 3]);
        let plan = testplan::paper_case1().unwrap();
        assert!(plan_position(&plan, f64::NAN).iter().all(|q| q.is_nan()));
    }

    #[test]
    fn plan_position_is_continuous_across_segments() {
        let plan = testplan::paper_case2().unwrap();
        for s in &plan.segments[1..] {
            let a = plan_position(&plan, s.t0_s - 1e-9);
            let b = plan_position(&plan, s.t0_s + 1e-9);
            for j in 0..3 {
                assert!((a[j] - b[j]).abs() < 1e-8);
            }
        }
    }
}
