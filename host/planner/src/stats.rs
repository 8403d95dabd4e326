//! Per-joint statistics of a plan (paper Tables 5/8): max and time-averaged
//! |v|, |a|, |jerk| and |τ|, and per-segment maxima.
//!
//! Velocity, acceleration and jerk are polynomials per segment (quartic,
//! cubic, quadratic), so their maxima are exact (the [`poly`](super::poly)
//! functions) and their means too: ∫|p′| between the roots of p′ is a
//! change of p. Torque is sampled on [`TORQUE_INTERVALS`] intervals per
//! segment, the grid maximum refined by golden-section search, and averaged
//! by Simpson's rule. The path's distance from the straight segments
//! between the via-points ([`PathDeviation`]) is sampled densely, with a
//! bound between samples.

use nalgebra::{Matrix3, Vector3};
use serde::Serialize;
use triquint_shared::Model;
use triquint_shared::dynamics;
use triquint_shared::kinematics::Pose;
use triquint_shared::plan::{Plan, Segment};

use crate::extrema::{argmax_abs_on_interval, derivative, integral_abs_on_interval};

/// Torque grid intervals per segment (even, for Simpson's rule; ≥ 200).
pub const TORQUE_INTERVALS: usize = 256;
/// Longest time between two samples of the path's deviation (s).
pub const DEVIATION_STEP_S: f64 = 2e-4;

/// The dynamics (forward kinematics) failed along the trajectory.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("segment {segment} at t = {time_s:.6} s: {source}")]
pub struct StatsError {
    pub segment: usize,
    pub time_s: f64,
    pub source: triquint_shared::KinematicsError,
}

/// Max and time-averaged absolute value of one quantity, per joint.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Quantity {
    /// max |x| per joint (continuous time; torque on the refined grid).
    pub max: [f64; 3],
    /// Plan time (s) at which each maximum occurs.
    pub argmax_s: [f64; 3],
    /// (1/T) ∫ |x| dt per joint.
    pub mean: [f64; 3],
}

/// Maxima of one segment, per joint.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SegmentStats {
    /// 1-based, as in the paper (h1 runs from P1 to P2).
    pub index: usize,
    pub t0_s: f64,
    pub duration_s: f64,
    pub max_velocity: [f64; 3],
    pub max_acceleration: [f64; 3],
    pub max_jerk: [f64; 3],
    pub max_torque: [f64; 3],
}

/// Everything the report prints.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PlanStats {
    /// Σ h (s): the plan's duration.
    pub total_time_s: f64,
    pub intervals_s: Vec<f64>,
    /// m/s
    pub velocity: Quantity,
    /// m/s²
    pub acceleration: Quantity,
    /// m/s³
    pub jerk: Quantity,
    /// N·m
    pub torque: Quantity,
    pub segments: Vec<SegmentStats>,
    /// How far the platform leaves the straight segments between the via-points.
    pub path_deviation: PathDeviation,
}

/// The platform's largest distance from the straight Cartesian segment
/// between the via-points it is travelling between, sampled at most
/// [`DEVIATION_STEP_S`] apart, with a certified bound between samples.
///
/// The certificate. With the struts' unit vectors as the rows of U (d_i/l)
/// and R = diag(d_iz/l), ∂r/∂q = U⁻¹R (paper eq. 21), so ‖∂r/∂q‖ ≤
/// max R / σ_min(U). Over a sample interval the joints travel at most
/// ρ = |q̇|·Δt (|q̇| the Euclidean norm of each joint's exact largest speed in
/// the segment). If ‖∂r/∂q‖ ≤ K along it, the platform moves at most Kρ, so
/// each row of U moves at most (Kρ + ρ)/l, ‖ΔU‖ ≤ (√3Kρ + ρ)/l (Frobenius),
/// and by Weyl σ_min falls at most that much; then ‖∂r/∂q‖ ≤ g(K) =
/// (max R + (K + 1)ρ/l) / (σ_min(U) − (√3K + 1)ρ/l). A K with g(K) < K is
/// therefore a bound on the whole interval (the first time ‖∂r/∂q‖ reached
/// K it would be at most g(K)), read from the sample at either end. The
/// distance from a segment is 1-Lipschitz in r, so between samples at
/// distances d₀ and d₁ it is at most (d₀ + d₁ + Kρ)/2. Exact but for the
/// floating-point arithmetic of the samples (no interval arithmetic).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PathDeviation {
    /// Largest sampled distance (m).
    pub max_m: f64,
    /// Plan time of that sample (s).
    pub at_s: f64,
    /// The distance anywhere is at most this (m), as above.
    pub bound_m: f64,
    /// Longest time between two samples (s), at most [`DEVIATION_STEP_S`].
    pub step_s: f64,
    /// The bound the plan records (m, format 6), which `check` proves
    /// `bound_m` within; None when it records none.
    pub limit_m: Option<f64>,
}

/// How many times an interval whose bound is above the target is halved.
const REFINEMENTS: usize = 12;

/// Distance of `p` from the segment a–b.
fn from_segment(p: Vector3<f64>, a: Vector3<f64>, b: Vector3<f64>) -> f64 {
    let ab = b - a;
    let u = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (p - (a + ab * u)).norm()
}

/// A bound on ‖∂r/∂q‖ over every pose the joints reach within a path of
/// length `rho` (m) from `pose` ([`PathDeviation`]'s certificate), or None
/// when the path is too long for one.
fn jacobian_bound(pose: &Pose<f64>, l: f64, rho: f64) -> Option<f64> {
    let u = Matrix3::from_rows(&pose.struts.map(|d| (d / l).transpose()));
    let sigma = u.singular_values().min();
    let rise = pose
        .struts
        .iter()
        .fold(0.0, |m: f64, d| m.max(d.z.abs() / l));
    let g = |k: f64| {
        let den = sigma - (3f64.sqrt() * k + 1.0) * rho / l;
        (den > 0.0).then(|| (rise + (k + 1.0) * rho / l) / den)
    };
    let mut k = g(0.0)?;
    for _ in 0..8 {
        k = g(k)?;
    }
    let k = k * (1.0 + 1e-6) + 1e-12;
    g(k).filter(|&gk| gk < k).map(|_| k)
}

/// For each segment of a (validated) plan, the via-points it runs between:
/// the via-points are knots in order, at the knots nearest their IK images.
fn via_of_segments(plan: &Plan, model: &Model<f64>) -> Vec<usize> {
    let mut at = vec![0usize; plan.via_points_m.len()];
    let mut next = 0;
    for (i, p) in plan.via_points_m.iter().enumerate() {
        let Ok(pose) = Pose::from_cartesian(model, Vector3::from(*p)) else {
            continue;
        };
        let dist = |k: usize| {
            (0..3)
                .map(|j| (plan.knots_m[k][j] - pose.q[j]).abs())
                .fold(0.0, f64::max)
        };
        let last = plan.knots_m.len() - 1;
        let k = if i + 1 == plan.via_points_m.len() {
            last
        } else {
            (next..=last)
                .min_by(|&a, &b| dist(a).total_cmp(&dist(b)))
                .unwrap_or(next)
        };
        at[i] = k;
        next = k + 1;
    }
    (0..plan.segments.len())
        .map(|k| {
            at.iter()
                .rposition(|&knot| knot <= k)
                .unwrap_or(0)
                .min(at.len() - 2)
        })
        .collect()
}

/// The path's deviation of a (validated) plan ([`PathDeviation`]).
pub fn path_deviation(plan: &Plan) -> Result<PathDeviation, StatsError> {
    path_deviation_within(plan, f64::INFINITY)
}

/// [`path_deviation`] with the bound the plan records, certified against
/// it as `check` does.
pub fn recorded_deviation(plan: &Plan) -> Result<PathDeviation, StatsError> {
    let limit = plan.max_deviation_m;
    Ok(PathDeviation {
        limit_m: limit,
        ..path_deviation_within(plan, limit.unwrap_or(f64::INFINITY))?
    })
}

/// [`path_deviation`], with every sample interval whose bound is above
/// `target_m` halved (up to `REFINEMENTS` times) until it is not: the
/// bound then proves `target_m` whenever the path stays below it by more
/// than the last halving's share.
pub fn path_deviation_within(plan: &Plan, target_m: f64) -> Result<PathDeviation, StatsError> {
    let model = plan.robot.model::<f64>();
    if plan.via_points_m.len() < 2 || plan.knots_m.len() != plan.segments.len() + 1 {
        // Not a validated plan: no segments between via-points to measure.
        return Ok(PathDeviation::default());
    }
    let via = via_of_segments(plan, &model);
    let mut out = PathDeviation::default();
    for (k, seg) in plan.segments.iter().enumerate() {
        let a = Vector3::from(plan.via_points_m[via[k]]);
        let b = Vector3::from(plan.via_points_m[via[k] + 1]);
        let h = seg.duration_s;
        let n = (h / DEVIATION_STEP_S).ceil().max(1.0) as usize;
        let step = h / n as f64;
        out.step_s = out.step_s.max(step);
        // The joints' exact largest speed in the segment.
        let qd = (0..3)
            .map(|j| argmax_abs_on_interval(&derivative(&seg.coeffs[j]), 0.0, h).1)
            .map(|v| v * v)
            .sum::<f64>()
            .sqrt();
        let sample = |t: f64| {
            let q = seg.quintic().eval(t).q;
            Pose::from_joints(&model, q)
                .map(|pose| (from_segment(pose.r, a, b), pose))
                .map_err(|source| StatsError {
                    segment: k + 1,
                    time_s: seg.t0_s + t,
                    source,
                })
        };
        let mut before = sample(0.0)?;
        for i in 1..=n {
            let t1 = if i == n { h } else { step * i as f64 };
            let after = sample(t1)?;
            for (d, t) in [(before.0, t1 - step), (after.0, t1)] {
                if d > out.max_m {
                    out.max_m = d;
                    out.at_s = seg.t0_s + t;
                }
            }
            // Intervals to certify: (t0, t1, both ends' samples, halvings).
            let mut open = vec![(t1 - step, t1, before, after, 0)];
            while let Some((t0, t1, s0, s1, depth)) = open.pop() {
                let rho = qd * (t1 - t0);
                let bound = [&s0.1, &s1.1]
                    .iter()
                    .filter_map(|p| jacobian_bound(p, model.l, rho))
                    .reduce(f64::min)
                    .map(|kb| 0.5 * (s0.0 + s1.0 + kb * rho));
                // Halving helps only while both samples are below the target.
                let settled = depth == REFINEMENTS || s0.0.max(s1.0) > target_m;
                match bound {
                    Some(b) if b <= target_m || settled => out.bound_m = out.bound_m.max(b),
                    _ if settled => out.bound_m = f64::INFINITY,
                    _ => {
                        let tm = 0.5 * (t0 + t1);
                        let mid = sample(tm)?;
                        if mid.0 > out.max_m {
                            out.max_m = mid.0;
                            out.at_s = seg.t0_s + tm;
                        }
                        open.push((t0, tm, s0, mid, depth + 1));
                        open.push((tm, t1, mid, s1, depth + 1));
                    }
                }
            }
            before = after;
        }
    }
    out.bound_m = out.bound_m.max(out.max_m);
    Ok(out)
}

/// Motor torques at segment-local time `t`.
pub fn segment_torque(
    model: &Model<f64>,
    seg: &Segment,
    index: usize,
    t: f64,
) -> Result<Vector3<f64>, StatsError> {
    let m = seg.quintic().eval(t);
    dynamics::torque(model, &m.q, &m.qd, &m.qdd).map_err(|source| StatsError {
        segment: index + 1,
        time_s: seg.t0_s + t,
        source,
    })
}

/// Folds one segment's (t, |x|) maximum into a running per-joint maximum.
fn fold_max(q: &mut Quantity, j: usize, t_abs: f64, value: f64) {
    if value > q.max[j] {
        q.max[j] = value;
        q.argmax_s[j] = t_abs;
    }
}

/// Statistics of a (validated) plan.
pub fn plan_stats(plan: &Plan) -> Result<PlanStats, StatsError> {
    let model = plan.robot.model::<f64>();
    let mut out = PlanStats {
        total_time_s: plan.segments.iter().map(|s| s.duration_s).sum(),
        intervals_s: plan.segments.iter().map(|s| s.duration_s).collect(),
        velocity: Quantity::default(),
        acceleration: Quantity::default(),
        jerk: Quantity::default(),
        torque: Quantity::default(),
        segments: Vec::with_capacity(plan.segments.len()),
        path_deviation: recorded_deviation(plan)?,
    };
    let mut integrals = [[0.0f64; 3]; 4];
    for (i, seg) in plan.segments.iter().enumerate() {
        let h = seg.duration_s;
        let mut s = SegmentStats {
            index: i + 1,
            t0_s: seg.t0_s,
            duration_s: h,
            max_velocity: [0.0; 3],
            max_acceleration: [0.0; 3],
            max_jerk: [0.0; 3],
            max_torque: [0.0; 3],
        };
        for j in 0..3 {
            let v = derivative(&seg.coeffs[j]);
            let a = derivative(&v);
            let jk = derivative(&a);
            for (d, (poly, quantity, seg_max)) in [
                (&v, &mut out.velocity, &mut s.max_velocity),
                (&a, &mut out.acceleration, &mut s.max_acceleration),
                (&jk, &mut out.jerk, &mut s.max_jerk),
            ]
            .into_iter()
            .enumerate()
            {
                let (t, value) = argmax_abs_on_interval(poly, 0.0, h);
                seg_max[j] = value;
                fold_max(quantity, j, seg.t0_s + t, value);
                integrals[d][j] += integral_abs_on_interval(poly, 0.0, h);
            }
        }
        let torque = segment_torque_stats(&model, seg, i)?;
        s.max_torque = torque.max;
        for (j, integral) in integrals[3].iter_mut().enumerate() {
            *integral += torque.integral[j];
            fold_max(
                &mut out.torque,
                j,
                seg.t0_s + torque.argmax[j],
                torque.max[j],
            );
        }
        out.segments.push(s);
    }
    let total = out.total_time_s;
    for (q, integral) in [
        &mut out.velocity,
        &mut out.acceleration,
        &mut out.jerk,
        &mut out.torque,
    ]
    .into_iter()
    .zip(integrals)
    {
        q.mean = integral.map(|x| x / total);
    }
    Ok(out)
}

struct TorqueSegment {
    max: [f64; 3],
    argmax: [f64; 3],
    integral: [f64; 3],
}

/// Grid, golden-section refinement of each joint's grid maximum, Simpson integral.
fn segment_torque_stats(
    model: &Model<f64>,
    seg: &Segment,
    index: usize,
) -> Result<TorqueSegment, StatsError> {
    let n = TORQUE_INTERVALS;
    let h = seg.duration_s;
    let dt = h / n as f64;
    let mut out = TorqueSegment {
        max: [0.0; 3],
        argmax: [0.0; 3],
        integral: [0.0; 3],
    };
    for k in 0..=n {
        let t = dt * k as f64;
        let tau = segment_torque(model, seg, index, t)?;
        let w = if k == 0 || k == n {
            1.0
        } else if k % 2 == 1 {
            4.0
        } else {
            2.0
        };
        for j in 0..3 {
            let a = tau[j].abs();
            out.integral[j] += w * a * dt / 3.0;
            if a > out.max[j] {
                out.max[j] = a;
                out.argmax[j] = t;
            }
        }
    }
    for j in 0..3 {
        let lo = (out.argmax[j] - dt).max(0.0);
        let hi = (out.argmax[j] + dt).min(h);
        let f = |t: f64| segment_torque(model, seg, index, t).map(|tau| tau[j].abs());
        let (t, value) = golden_max(f, lo, hi)?;
        if value > out.max[j] {
            out.max[j] = value;
            out.argmax[j] = t;
        }
    }
    Ok(out)
}

/// Golden-section search for a maximum of a unimodal f on [lo, hi].
fn golden_max<E>(f: impl Fn(f64) -> Result<f64, E>, lo: f64, hi: f64) -> Result<(f64, f64), E> {
    let r = 0.5 * (5f64.sqrt() - 1.0);
    let (mut a, mut b) = (lo, hi);
    let mut c = b - r * (b - a);
    let mut d = a + r * (b - a);
    let (mut fc, mut fd) = (f(c)?, f(d)?);
    for _ in 0..40 {
        if fc > fd {
            b = d;
            d = c;
            fd = fc;
            c = b - r * (b - a);
            fc = f(c)?;
        } else {
            a = c;
            c = d;
            fc = fd;
            d = a + r * (b - a);
            fd = f(d)?;
        }
    }
    Ok(if fc > fd { (c, fc) } else { (d, fd) })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The certificate's ‖∂r/∂q‖ bound holds at joints anywhere within the
    /// path length from the pose it is read at (a straight path there is
    /// one such path), across the workspace.
    #[test]
    fn the_jacobian_bound_holds_within_the_path_length() {
        let model = triquint_shared::Robot::default().model::<f64>();
        let mut state: u64 = 7;
        let mut next = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (state >> 11) as f64 / (1u64 << 53) as f64
        };
        let mut tight: f64 = 0.0;
        for _ in 0..200 {
            let r = Vector3::new(0.2 * next() - 0.1, 0.2 * next() - 0.1, 0.54 + 0.14 * next());
            let pose = Pose::from_cartesian(&model, r).unwrap();
            for rho in [1e-5, 1e-4, 1e-3] {
                let k = jacobian_bound(&pose, model.l, rho).unwrap();
                let spectral = |g: Matrix3<f64>| g.svd(false, false).singular_values.max();
                assert!(spectral(pose.platform_jacobian()) <= k);
                for _ in 0..20 {
                    let dir = Vector3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize();
                    let q = pose.q + dir * rho * next();
                    let at = Pose::from_joints(&model, q).unwrap();
                    let norm = at
                        .platform_jacobian()
                        .svd(false, false)
                        .singular_values
                        .max();
                    assert!(norm <= k, "rho {rho}: {norm} over {k}");
                    if rho == 1e-5 {
                        tight = tight.max(norm / k);
                    }
                }
            }
        }
        // Over a short path the bound is close to the largest value.
        assert!(tight > 0.5, "{tight}");
        // A path too long for the struts' geometry gets no bound.
        let pose = Pose::from_cartesian(&model, Vector3::new(0.0, 0.0, 0.6)).unwrap();
        assert_eq!(jacobian_bound(&pose, model.l, 1.0), None);
    }
}
