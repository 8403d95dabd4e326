//! Input shaping that stays piecewise quintic: a plan convolved with a few
//! positive impulses (ZV, ZVD, EI for a frequency and damping ratio), one
//! shaper for all three joints so the joint path keeps its shape in time.
//!
//! The shaped motion is q̃(t) = Σ Aₖ q(t − tₖ), with q held at its start
//! before 0 and at its end after T. Each copy is the plan shifted by tₖ, so
//! between the union of the shifted knots every copy is one quintic (or a
//! constant), and the sum is a quintic: the shaped plan is the plan's
//! segments, shifted, re-expanded about the new knots and added. It is C3
//! wherever the plan is, starts and ends at rest, and since the Aₖ are
//! positive and sum to 1 its |v|, |a|, |jerk| stay within the plan's. Torque
//! is not linear in q, and the path between via-points changes: `check`
//! re-proves the shaped plan (torque, travel, C3, the records).

use triquint_shared::plan::Plan;

use crate::check::max_abs;
use crate::error::PlanError;

/// The shapers of Klipper's `input_shaper` that are a few positive impulses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shaper {
    /// Zero vibration: two impulses over half a period.
    Zv,
    /// Zero vibration and derivative: three impulses over a period, robust
    /// to the frequency.
    Zvd,
    /// Extra insensitive (5 % vibration tolerance): three impulses over a
    /// period, robust to ±20 % of the frequency.
    Ei,
}

/// Vibration tolerance of EI (Klipper's 1/SHAPER_VIBRATION_REDUCTION).
const EI_TOLERANCE: f64 = 0.05;

/// Impulse times (s, whole microseconds, the first 0) and positive
/// amplitudes summing to 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Impulses {
    pub times_s: Vec<f64>,
    pub amplitudes: Vec<f64>,
}

impl Impulses {
    /// The shaper's impulses for a mode at `hz` with damping ratio `damping`.
    pub fn new(shaper: Shaper, hz: f64, damping: f64) -> Result<Self, PlanError> {
        if !(hz.is_finite() && hz > 0.0 && hz <= 1000.0) {
            return Err(PlanError::InvalidJob {
                field: "shaper.frequency".into(),
                reason: format!("must be in (0, 1000] Hz, got {hz}"),
            });
        }
        if !(damping.is_finite() && (0.0..1.0).contains(&damping)) {
            return Err(PlanError::InvalidJob {
                field: "shaper.damping".into(),
                reason: format!("must be in [0, 1), got {damping}"),
            });
        }
        let df = (1.0 - damping * damping).sqrt();
        let k = (-damping * std::f64::consts::PI / df).exp();
        let td = 1.0 / (hz * df);
        let (a, t): (Vec<f64>, Vec<f64>) = match shaper {
            Shaper::Zv => (vec![1.0, k], vec![0.0, 0.5 * td]),
            Shaper::Zvd => (vec![1.0, 2.0 * k, k * k], vec![0.0, 0.5 * td, td]),
            Shaper::Ei => {
                let a1 = 0.25 * (1.0 + EI_TOLERANCE);
                (
                    vec![a1, 0.5 * (1.0 - EI_TOLERANCE) * k, a1 * k * k],
                    vec![0.0, 0.5 * td, td],
                )
            }
        };
        let sum: f64 = a.iter().sum();
        Ok(Self {
            // Whole microseconds, so the shaped knots stay whole too.
            times_s: t.iter().map(|t| (t * 1e6).round() * 1e-6).collect(),
            amplitudes: a.iter().map(|a| a / sum).collect(),
        })
    }

    /// How much longer the shaped motion lasts (s).
    pub fn duration_s(&self) -> f64 {
        self.times_s.last().copied().unwrap_or(0.0)
    }
}

fn us(t: f64) -> i64 {
    (t * 1e6).round() as i64
}

/// Coefficients of p(τ + s) in τ, for p with coefficients `c` (Taylor shift).
fn shifted(c: &[f64; 6], s: f64) -> [f64; 6] {
    let binom = |n: usize, k: usize| -> f64 {
        (0..k).fold(1.0, |b, i| b * (n - i) as f64 / (i + 1) as f64)
    };
    let mut out = [0.0; 6];
    for (m, o) in out.iter_mut().enumerate() {
        *o = (m..6)
            .map(|k| c[k] * binom(k, m) * s.powi((k - m) as i32))
            .sum();
    }
    out
}

/// `plan` convolved with `impulses`: a plan that starts where it starts, ends
/// where it ends, `impulses.duration_s()` later, with its maxima recomputed.
/// Its total-time limit grows by the shaper's duration; every other limit,
/// the robot and the travel are the plan's, for `check` to prove again. Its
/// via-points are the first and the last: shaping moves the path off the
/// others ([`via_point_deviation`]).
pub fn shape(plan: &Plan, impulses: &Impulses) -> Result<Plan, PlanError> {
    let invalid = |reason: &str| PlanError::InvalidJob {
        field: "plan".into(),
        reason: reason.into(),
    };
    let (Some(first), Some(last)) = (plan.segments.first(), plan.segments.last()) else {
        return Err(invalid("no segments to shape"));
    };
    // Held before and after: only a plan at rest at both ends stays C3.
    let at_rest = |s: Option<triquint_shared::plan::JointState>| {
        s.is_some_and(|s| {
            s.v.iter()
                .chain(&s.a)
                .chain(&s.jerk)
                .all(|x| x.abs() <= 1e-9)
        })
    };
    if !at_rest(plan.at(0.0)) || !at_rest(plan.at(plan.total_time_s)) {
        return Err(invalid("shaping needs a plan that starts and ends at rest"));
    }
    let starts: Vec<i64> = plan.segments.iter().map(|s| us(s.t0_s)).collect();
    let end = us(last.t0_s + last.duration_s);
    let shifts: Vec<i64> = impulses.times_s.iter().map(|&t| us(t)).collect();
    let mut knots: Vec<i64> = shifts
        .iter()
        .flat_map(|&d| starts.iter().chain([&end]).map(move |&b| b + d))
        .collect();
    knots.sort_unstable();
    knots.dedup();
    let q_start = first.coeffs.map(|c| c[0]);
    let q_end = plan
        .at(plan.total_time_s)
        .map(|s| s.q)
        .ok_or_else(|| invalid("no end"))?;
    let mut segments = Vec::with_capacity(knots.len());
    for w in knots.windows(2) {
        let (u0, u1) = (w[0], w[1]);
        let mut coeffs = [[0.0; 6]; 3];
        for (&d, &a) in shifts.iter().zip(&impulses.amplitudes) {
            let local = u0 - d;
            let copy: [[f64; 6]; 3] = if local < 0 {
                q_start.map(|q| [q, 0.0, 0.0, 0.0, 0.0, 0.0])
            } else if local >= end {
                q_end.map(|q| [q, 0.0, 0.0, 0.0, 0.0, 0.0])
            } else {
                // The knots include every shifted boundary: the interval
                // lies inside one segment of this copy.
                let k = starts.partition_point(|&s| s <= local) - 1;
                let s = (local - starts[k]) as f64 * 1e-6;
                plan.segments[k].coeffs.map(|c| shifted(&c, s))
            };
            for j in 0..3 {
                for m in 0..6 {
                    coeffs[j][m] += a * copy[j][m];
                }
            }
        }
        segments.push(triquint_shared::plan::Segment {
            t0_s: u0 as f64 * 1e-6,
            duration_s: (u1 - u0) as f64 * 1e-6,
            coeffs,
        });
    }
    let mut shaped = plan.clone();
    shaped.intervals_s = segments.iter().map(|s| s.duration_s).collect();
    shaped.total_time_s = (knots[knots.len() - 1] - knots[0]) as f64 * 1e-6;
    shaped.limits.total_time += impulses.duration_s();
    shaped.knots_m = segments
        .iter()
        .map(|s| s.coeffs.map(|c| c[0]))
        .chain([q_end])
        .collect();
    shaped.segments = segments;
    if let (Some(a), Some(b)) = (plan.via_points_m.first(), plan.via_points_m.last()) {
        shaped.via_points_m = vec![*a, *b];
    }
    shaped.max_abs = max_abs(&shaped, crate::check::TORQUE_CHECK_SAMPLES)
        .map_err(|e| invalid(&e.to_string()))?;
    Ok(shaped)
}

/// For each knot of `plan`, the joint-space distance (m, largest joint) of
/// the shaped plan from it at the same time plus the shaper's mean delay
/// Σ Aₖtₖ: how far shaping moves the path off the plan's knots (and so off
/// its via-points).
pub fn via_point_deviation(plan: &Plan, shaped: &Plan, impulses: &Impulses) -> Vec<f64> {
    let delay: f64 = impulses
        .times_s
        .iter()
        .zip(&impulses.amplitudes)
        .map(|(t, a)| t * a)
        .sum();
    let mut t = 0.0;
    let mut out = Vec::with_capacity(plan.knots_m.len());
    for (k, q) in plan.knots_m.iter().enumerate() {
        let s = shaped.at(t + delay).map_or(f64::INFINITY, |s| {
            (0..3).map(|j| (s.q[j] - q[j]).abs()).fold(0.0, f64::max)
        });
        out.push(s);
        t += plan.intervals_s.get(k).copied().unwrap_or(0.0);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::check;
    use crate::load::parse_plan;

    /// Paper Case I's min-max-jerk plan (the planner comes after this layer).
    fn case1() -> Plan {
        parse_plan(include_str!("../../../testdata/hil/paper-case1.json")).unwrap()
    }

    #[test]
    fn impulses_are_positive_sum_to_one_and_zero_the_mode() {
        for shaper in [Shaper::Zv, Shaper::Zvd, Shaper::Ei] {
            let (f, z) = (25.5, 0.026);
            let imp = Impulses::new(shaper, f, z).unwrap();
            assert!(imp.amplitudes.iter().all(|a| *a > 0.0));
            assert!((imp.amplitudes.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            // Residual of a damped mode after the impulses, relative to one impulse.
            let w = 2.0 * std::f64::consts::PI * f;
            let wd = w * (1.0 - z * z).sqrt();
            let tn = imp.duration_s();
            let (mut c, mut s) = (0.0, 0.0);
            for (t, a) in imp.times_s.iter().zip(&imp.amplitudes) {
                let e = a * (-z * w * (tn - t)).exp();
                c += e * (wd * t).cos();
                s += e * (wd * t).sin();
            }
            let v = (c * c + s * s).sqrt();
            let bound = if shaper == Shaper::Ei { 0.051 } else { 1e-3 };
            assert!(v < bound, "{shaper:?}: {v}");
        }
        assert!(Impulses::new(Shaper::Zv, 0.0, 0.1).is_err());
        assert!(Impulses::new(Shaper::Zv, 30.0, 1.0).is_err());
        assert!(Impulses::new(Shaper::Zv, f64::NAN, 0.1).is_err());
    }

    #[test]
    fn a_shaped_plan_is_a_c3_plan_within_the_original_bounds() {
        let p = case1();
        for shaper in [Shaper::Zv, Shaper::Zvd, Shaper::Ei] {
            let imp = Impulses::new(shaper, 25.5, 0.026).unwrap();
            let s = shape(&p, &imp).unwrap();
            assert!((s.total_time_s - p.total_time_s - imp.duration_s()).abs() < 1e-9);
            // The convolution, pointwise.
            for k in 0..=200 {
                let t = s.total_time_s * k as f64 / 200.0;
                let want: [f64; 3] = core::array::from_fn(|j| {
                    imp.times_s
                        .iter()
                        .zip(&imp.amplitudes)
                        .map(|(d, a)| a * p.at(t - d).unwrap().q[j])
                        .sum()
                });
                let got = s.at(t).unwrap().q;
                for j in 0..3 {
                    assert!((got[j] - want[j]).abs() < 1e-12, "{shaper:?} t {t}");
                }
            }
            // check proves it again: C3, rest at both ends, limits, travel, records.
            let rows = check(&s).unwrap();
            assert!(
                rows.iter().all(|r| r.ok),
                "{shaper:?}: {:?}",
                rows.iter().filter(|r| !r.ok).collect::<Vec<_>>()
            );
            for j in 0..3 {
                assert!(s.max_abs.velocity[j] <= p.max_abs.velocity[j] * (1.0 + 1e-9));
                assert!(s.max_abs.acceleration[j] <= p.max_abs.acceleration[j] * (1.0 + 1e-9));
                assert!(s.max_abs.jerk[j] <= p.max_abs.jerk[j] * (1.0 + 1e-9));
            }
            let dev = via_point_deviation(&p, &s, &imp);
            let moving = parse_plan(include_str!(
                "../../../testdata/protocol/plans/case2-spline.json"
            ))
            .unwrap();
            assert!(shape(&moving, &imp).is_err());
            assert_eq!(dev.len(), p.knots_m.len());
            // Off the knots by less than what the platform moves in the shaper's time.
            let v = p.max_abs.velocity.iter().fold(0.0, |a: f64, b| a.max(*b));
            assert!(dev.iter().all(|d| *d <= v * imp.duration_s()), "{dev:?}");
        }
    }
}
