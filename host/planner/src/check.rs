//! Independent verification of a plan: interpolation, C3 continuity, rest
//! at both ends, and every limit in continuous time — velocity,
//! acceleration and jerk exactly, by Sturm sequences ([`crate::sturm`], a
//! method the search does not use); torque on a fine grid; the sliders'
//! travel from the exact position extremes; a recorded deviation bound by
//! its certificate; and every figure the plan
//! records (`max_abs`) against its recomputation, so no reader of the plan
//! trusts a summary that does not match the segments.

// Index loops over joints and segments mirror the maths.
#![allow(clippy::needless_range_loop)]

use nalgebra::Vector3;
use triquint_shared::dynamics;
use triquint_shared::plan::figures::kinematics;
use triquint_shared::plan::{MaxAbs, Plan};
use triquint_shared::quintic::eval_poly;

use crate::load::{LoadError, unshaped, validate_plan};
use crate::shaper::{Impulses, convolve, knot_deviation};
use crate::stats::{StatsError, path_deviation_within};
use crate::sturm;

/// Torque samples per segment in checks and in the reported maxima.
pub const TORQUE_CHECK_SAMPLES: usize = 400;
/// Tolerance of positions and continuity (m, m/s, m/s², m/s³).
pub const CONTINUITY_TOL: f64 = 1e-9;
/// Relative tolerance of the exact limits; torque (sampled) gets 0.1 %.
pub const LIMIT_TOL: f64 = 1e-9;
pub const TORQUE_TOL: f64 = 1e-3;

/// One line of a check: what, the measured value, the bound, and whether it holds.
#[derive(Clone, Debug, PartialEq)]
pub struct CheckRow {
    pub what: String,
    pub value: f64,
    pub bound: f64,
    pub ok: bool,
}

/// Exact continuous-time maxima of |v|, |a|, |jerk|; |τ| on a grid. Err
/// where the dynamics fail (the plan leaves the workspace).
pub(crate) fn max_abs(plan: &Plan, torque_samples: usize) -> Result<MaxAbs, StatsError> {
    let mut m = MaxAbs::default();
    let model = plan.robot.model::<f64>();
    for (k, seg) in plan.segments.iter().enumerate() {
        for j in 0..3 {
            let vel = crate::extrema::derivative(&seg.coeffs[j]);
            let acc = crate::extrema::derivative(&vel);
            let jerk = crate::extrema::derivative(&acc);
            let h = seg.duration_s;
            m.velocity[j] = m.velocity[j].max(sturm::max_abs(&vel, 0.0, h).1);
            m.acceleration[j] = m.acceleration[j].max(sturm::max_abs(&acc, 0.0, h).1);
            m.jerk[j] = m.jerk[j].max(sturm::max_abs(&jerk, 0.0, h).1);
        }
        for i in 0..=torque_samples {
            let t = seg.duration_s * i as f64 / torque_samples as f64;
            let s = [0, 1, 2].map(|j| eval_poly(&seg.coeffs[j], t));
            let v = |r: usize| Vector3::new(s[0][r], s[1][r], s[2][r]);
            let tau =
                dynamics::torque(&model, &v(0), &v(1), &v(2)).map_err(|source| StatsError {
                    segment: k + 1,
                    time_s: seg.t0_s + t,
                    source,
                })?;
            for j in 0..3 {
                m.torque[j] = m.torque[j].max(tau[j].abs());
            }
        }
    }
    Ok(m)
}

/// Checks a plan: Err when it is not a usable plan ([`validate_plan`]);
/// else every check with its figure (any row not `ok` is a violation).
///
/// ```
/// use triquint_planner::{Job, Options, check, plan};
/// let job = Job::builder().points_mm([[0.0, 0.0, 600.0], [20.0, 0.0, 600.0]]).build()?;
/// let mut p = plan(&job, &Options::default())?;
/// assert!(check(&p)?.iter().all(|r| r.ok));
/// p.limits.jerk = 0.5 * p.max_abs.jerk.iter().fold(0.0, |a, &b| f64::max(a, b));
/// assert!(check(&p)?.iter().any(|r| !r.ok && r.what.starts_with("max |jerk")));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn check(plan: &Plan) -> Result<Vec<CheckRow>, LoadError> {
    validate_plan(plan)?;
    let mut rows = Vec::new();
    let mut row = |what: &str, value: f64, bound: f64| {
        rows.push(CheckRow {
            what: what.to_string(),
            value,
            bound,
            ok: value <= bound,
        })
    };

    // Timing: whole microseconds, consistent offsets and total.
    let mut t = 0.0;
    let (mut timing, mut micro): (f64, f64) = (0.0, 0.0);
    for (seg, h) in plan.segments.iter().zip(&plan.intervals_s) {
        timing = timing
            .max((seg.t0_s - t).abs())
            .max((seg.duration_s - h).abs());
        micro = micro.max((h * 1e6 - (h * 1e6).round()).abs() * 1e-6);
        t += h;
    }
    timing = timing.max((plan.total_time_s - t).abs());
    row("segment times consistent (s)", timing, 1e-9);
    row("intervals whole µs (s)", micro, 1e-9);
    row(
        "total time ≤ limit (s)",
        t,
        plan.limits.total_time * (1.0 + LIMIT_TOL),
    );

    // Interpolation of the knots, and via-points among the knots (in order).
    let mut interp: f64 = 0.0;
    for (k, seg) in plan.segments.iter().enumerate() {
        for j in 0..3 {
            let start = eval_poly(&seg.coeffs[j], 0.0)[0];
            let end = eval_poly(&seg.coeffs[j], seg.duration_s)[0];
            interp = interp
                .max((start - plan.knots_m[k][j]).abs())
                .max((end - plan.knots_m[k + 1][j]).abs());
        }
    }
    row("knot interpolation error (m)", interp, CONTINUITY_TOL);
    // C3 at interior knots and rest (v = a = jerk = 0) at both ends.
    let mut c3: f64 = 0.0;
    for k in 1..plan.segments.len() {
        let (a, b) = (&plan.segments[k - 1], &plan.segments[k]);
        for j in 0..3 {
            let end = eval_poly(&a.coeffs[j], a.duration_s);
            let start = eval_poly(&b.coeffs[j], 0.0);
            for r in 0..4 {
                c3 = c3.max((end[r] - start[r]).abs());
            }
        }
    }
    row("C3 residual at interior knots", c3, CONTINUITY_TOL);
    let (first, last) = (&plan.segments[0], &plan.segments[plan.segments.len() - 1]);
    let mut rest: f64 = 0.0;
    for j in 0..3 {
        let s = eval_poly(&first.coeffs[j], 0.0);
        let e = eval_poly(&last.coeffs[j], last.duration_s);
        for r in 1..4 {
            rest = rest.max(s[r].abs()).max(e[r].abs());
        }
    }
    row("end velocity/acceleration/jerk", rest, CONTINUITY_TOL);

    let m = max_abs(plan, TORQUE_CHECK_SAMPLES).map_err(|e| LoadError::Invalid(e.to_string()))?;
    let l = &plan.limits;
    for (name, vals, lim, tol) in [
        ("velocity (m/s)", m.velocity, l.velocity, LIMIT_TOL),
        (
            "acceleration (m/s²)",
            m.acceleration,
            l.acceleration,
            LIMIT_TOL,
        ),
        ("jerk (m/s³)", m.jerk, l.jerk, LIMIT_TOL),
        ("torque (N·m)", m.torque, l.torque, TORQUE_TOL),
    ] {
        for (j, v) in vals.iter().enumerate() {
            row(
                &format!("max |{name}| joint {}", j + 1),
                *v,
                lim * (1.0 + tol),
            );
        }
    }
    // The limits within the machine's ceilings (exactly: both are inputs).
    for ((name, lim), (_, ceiling)) in l.named().into_iter().zip(plan.ceilings.named()) {
        row(&format!("limit {name} − ceiling"), lim - ceiling, 0.0);
    }
    // Travel: the exact lowest and highest position of every slider.
    let k = kinematics(&plan.segments);
    let travel = &plan.travel;
    for j in 0..3 {
        row(
            &format!("travel min − lowest position slider {} (m)", j + 1),
            travel.min[j] - k.position_min[j],
            CONTINUITY_TOL,
        );
        row(
            &format!("highest position − travel max slider {} (m)", j + 1),
            k.position_max[j] - travel.max[j],
            CONTINUITY_TOL,
        );
    }
    // Every recorded figure against its recomputation: exact ones to 1e-9
    // relative, torque (sampled on the same grid the planner records) to
    // its tolerance. A NaN difference fails the row.
    for (name, rec, val, tol) in [
        (
            "velocity (m/s)",
            plan.max_abs.velocity,
            m.velocity,
            LIMIT_TOL,
        ),
        (
            "acceleration (m/s²)",
            plan.max_abs.acceleration,
            m.acceleration,
            LIMIT_TOL,
        ),
        ("jerk (m/s³)", plan.max_abs.jerk, m.jerk, LIMIT_TOL),
        ("torque (N·m)", plan.max_abs.torque, m.torque, TORQUE_TOL),
    ] {
        let diff = rec
            .iter()
            .zip(&val)
            .map(|(a, b)| (a - b).abs())
            .fold(
                0.0,
                |acc: f64, d| if d.is_nan() { f64::NAN } else { acc.max(d) },
            );
        row(
            &format!("reported max {name} matches"),
            if diff.is_nan() { f64::INFINITY } else { diff },
            tol * val.iter().fold(1.0, |a: f64, b| a.max(*b)),
        );
    }
    if let Some((convolution, deviation, bound)) = shaping_figures(plan)? {
        row(
            "shaped = unshaped ∗ shaper (m)",
            convolution,
            CONTINUITY_TOL,
        );
        row("via-point deviation of shaping (m)", deviation, bound);
    }
    if let Some(limit) = plan.max_deviation_m {
        rows.push(deviation_row(plan, limit)?);
    }
    Ok(rows)
}

/// The check of a bound `limit_m` (m) on the platform's distance from the
/// straight segments between the via-points: the certified bound
/// ([`PathDeviation`](crate::stats::PathDeviation): samples, and a bound
/// on ‖∂r/∂q‖ over each interval between them) against it. [`check`] does
/// it for the bound a plan records (format 6); this one proves any other.
///
/// ```
/// use triquint_planner::{Job, KnotPlacement, Objective, Options, check_deviation, plan};
/// let job = Job::builder()
///     .objective(Objective::MinTime)
///     .knots(KnotPlacement::Free)
///     .max_deviation_mm(0.5)
///     .points_mm([[-60.0, 40.0, 560.0], [60.0, -40.0, 640.0]])
///     .build()?;
/// let p = plan(&job, &Options::default())?;
/// assert!(check_deviation(&p, 0.5e-3)?.ok);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn check_deviation(plan: &Plan, limit_m: f64) -> Result<CheckRow, LoadError> {
    validate_plan(plan)?;
    deviation_row(plan, limit_m)
}

/// [`check_deviation`] of a validated plan.
fn deviation_row(plan: &Plan, limit_m: f64) -> Result<CheckRow, LoadError> {
    let d = path_deviation_within(plan, limit_m).map_err(|e| LoadError::Invalid(e.to_string()))?;
    Ok(CheckRow {
        what: "path deviation, certified (m)".to_string(),
        value: d.bound_m,
        bound: limit_m,
        ok: d.bound_m <= limit_m,
    })
}

/// A shaped plan's figures: how far its segments are from the unshaped
/// plan convolved again (m over each segment: Σₖ |Δcₖ| hᵏ, infinite if the
/// segments differ in number or time), and the largest joint distance at a
/// via-point's time plus the shaper's mean delay from the via-point, with
/// its bound, the unshaped plan's top speed times the shaper's duration
/// (each copy is within that of the via-point). `None` for a plan that is
/// not shaped; the unshaped plan is itself checked.
fn shaping_figures(plan: &Plan) -> Result<Option<(f64, f64, f64)>, LoadError> {
    let (Some(record), Some(base)) = (&plan.shaping, unshaped(plan)) else {
        return Ok(None);
    };
    let nested = |e: &dyn std::fmt::Display| LoadError::Invalid(format!("shaping.unshaped: {e}"));
    if let Some(bad) = check(&base)
        .map_err(|e| nested(&e))?
        .into_iter()
        .find(|r| !r.ok)
    {
        return Err(nested(&format!(
            "{} is {}, bound {}",
            bad.what, bad.value, bad.bound
        )));
    }
    let impulses =
        Impulses::for_spec(&record.shaper).map_err(|e| LoadError::Invalid(e.to_string()))?;
    let again = convolve(&base.segments, &impulses).map_err(|e| nested(&e))?;
    let mut convolution: f64 = 0.0;
    if again.len() != plan.segments.len() {
        convolution = f64::INFINITY;
    }
    for (a, b) in again.iter().zip(&plan.segments) {
        if (a.t0_s - b.t0_s).abs() > 1e-9 || (a.duration_s - b.duration_s).abs() > 1e-9 {
            convolution = f64::INFINITY;
        }
        for j in 0..3 {
            let d: f64 = (0..6)
                .map(|k| (a.coeffs[j][k] - b.coeffs[j][k]).abs() * b.duration_s.powi(k as i32))
                .sum();
            convolution = if d.is_nan() {
                f64::INFINITY
            } else {
                convolution.max(d)
            };
        }
    }
    // The via-points' knots and their times in the unshaped plan.
    let model = base.robot.model::<f64>();
    let mut times = Vec::new();
    let mut knots = Vec::new();
    let mut next = 0;
    for p in &base.via_points_m {
        let q = triquint_shared::kinematics::Pose::from_cartesian(&model, Vector3::from(*p))
            .map_err(|e| nested(&e))?
            .q;
        let found = (next..base.knots_m.len())
            .find(|&k| (0..3).all(|j| (base.knots_m[k][j] - q[j]).abs() <= CONTINUITY_TOL));
        let Some(k) = found else {
            return Err(nested(&"a via-point is not a knot"));
        };
        times.push(base.intervals_s[..k].iter().sum::<f64>());
        knots.push(base.knots_m[k]);
        next = k + 1;
    }
    let deviation = knot_deviation(&knots, &times, &plan.segments, &impulses)
        .into_iter()
        .fold(0.0, f64::max);
    let speed = base
        .max_abs
        .velocity
        .iter()
        .fold(0.0, |a: f64, b| a.max(*b));
    Ok(Some((
        convolution,
        deviation,
        speed * impulses.duration_s() * (1.0 + LIMIT_TOL) + CONTINUITY_TOL,
    )))
}
