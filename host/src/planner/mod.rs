//! The planner: Cartesian via-points → globally min-max-jerk C3 piecewise
//! quintic joint trajectory under velocity, acceleration, jerk, torque and
//! total-time limits, with every limit verified in continuous time.
//!
//! - [`spline`]: Hermite form of the C3 quintic spline (unknowns: knot v, a).
//! - [`lp`]: the linear/second-order-cone program and its solver (Clarabel).
//! - [`local`]: exact inner problem for fixed intervals; local search over intervals.
//! - [`search`]: deterministic multistart, µs rounding, min-time.
//! - [`verify`]: independent checks of a plan file.
//! - [`evolution`]: differential evolution, an independent global check of the search.

pub mod evolution;
pub mod local;
pub mod lp;
pub mod search;
pub mod spline;
pub mod verify;

use std::time::Instant;

use nalgebra::Vector3;
use triquint_shared::plan::{Objective, PLAN_FORMAT, Plan, Segment, SolverStats};

use crate::exit::{CliError, CliResult};
use crate::job::Job;
use local::{Problem, Quantity, Solution, knots_from, problem};
use search::{SearchOptions, global, min_time, round_to_microseconds};

/// Torque samples per segment in the final solve (the search uses fewer).
const FINAL_TORQUE_SAMPLES: usize = 400;

/// Knots of a path: the via-points, with straight-line points added between
/// them when there are fewer than five (a C3 quintic spline at rest at both
/// ends needs n ≥ 4 knots, and one more leaves the jerk a free variable).
pub fn knot_points(points: &[Vector3<f64>]) -> Vec<Vector3<f64>> {
    let n = points.len();
    if !(2..5).contains(&n) {
        return points.to_vec();
    }
    let pieces = 4usize.div_ceil(n - 1);
    let mut out = Vec::new();
    for w in points.windows(2) {
        for i in 0..pieces {
            out.push(w[0] + (w[1] - w[0]) * (i as f64 / pieces as f64));
        }
    }
    out.push(points[n - 1]);
    out
}

/// The planning problem of a job at its total-time limit.
pub fn job_problem(job: &Job) -> CliResult<Problem> {
    let model = job.robot.model::<f64>();
    let pts = knot_points(&job.points_m());
    let knots = knots_from(&pts, &model).map_err(|(i, e)| {
        CliError::bad_input(format!(
            "knot {} on the straight line between via-points is outside the workspace: {e}",
            i + 1
        ))
    })?;
    Ok(problem(knots, &job.limits, model, job.limits.total_time))
}

fn infeasible_limit(q: Quantity, job: &Job) -> String {
    let l = &job.limits;
    let (value, unit) = match q {
        Quantity::Velocity => (l.velocity, "m/s"),
        Quantity::Acceleration => (l.acceleration, "m/s²"),
        Quantity::Jerk => (l.jerk, "m/s³"),
        Quantity::Torque => (l.torque, "N·m"),
    };
    format!("{} limit {value} {unit}", q.name())
}

/// Plans a job. Errors: bad input (2) or infeasible (3), each one line.
pub fn plan(job: &Job, opts: &SearchOptions) -> CliResult<Plan> {
    let clock = Instant::now();
    let p = job_problem(job)?;
    let (sol, starts, mut lp_solves) = match job.objective {
        Objective::MinMaxJerk => {
            let r = global(&p, opts)
                .ok_or_else(|| CliError::infeasible("the solver found no plan for these knots"))?;
            let mut best = r.best;
            let mut lp_solves = r.lp_solves;
            if !search::feasible(&p, &best) {
                // Restoration: the shortest feasible plan, stretched to the
                // time budget, then optimised locally there.
                let shortest = min_time(&p, job.limits.total_time * 8.0, opts).ok();
                let restored = shortest.as_ref().and_then(|(s, _)| {
                    let t: f64 = s.h.iter().sum();
                    (t <= job.limits.total_time)
                        .then(|| search::stretch(&p, s, job.limits.total_time))?
                });
                match restored {
                    Some(sol) if search::feasible(&p, &sol) => {
                        lp_solves += sol.lp_solves;
                        best = sol;
                    }
                    _ => {
                        let binding = if best.violation > 1e-9 {
                            best.binding
                        } else {
                            Quantity::Jerk
                        };
                        let hint = match &shortest {
                            Some((s, _)) => format!(
                                "; the shortest total time that meets every limit is {:.6} s",
                                s.h.iter().sum::<f64>()
                            ),
                            None => String::new(),
                        };
                        return Err(CliError::infeasible(format!(
                            "no plan within total_time {} s meets the {} (best max jerk {:.6} m/s³, limit violation {:.3} %){hint}",
                            job.limits.total_time,
                            infeasible_limit(binding, job),
                            best.jerk,
                            best.violation * 100.0
                        )));
                    }
                }
            }
            (best, r.starts, lp_solves)
        }
        Objective::MinTime => {
            let (best, probe) = min_time(&p, job.limits.total_time, opts).map_err(|f| {
                CliError::infeasible(format!(
                    "no total time up to {:.3} s meets the {}",
                    f.tried_up_to,
                    infeasible_limit(f.binding, job)
                ))
            })?;
            // Leave room for rounding to whole microseconds (jerk ∝ T⁻³).
            let t = best.h.iter().sum::<f64>() * (1.0 + 1e-6) + 1e-6 * best.h.len() as f64;
            let bisection = best.lp_solves;
            let best = search::stretch(&p, &best, t)
                .filter(|s| search::feasible(&p, s))
                .unwrap_or(best);
            if t > job.limits.total_time * (1.0 + 1e-9) {
                return Err(CliError::infeasible(format!(
                    "total_time {} s is too short: the shortest total time that meets every limit is {t:.6} s",
                    job.limits.total_time
                )));
            }
            let lp_solves = probe.lp_solves + bisection + best.lp_solves;
            (best, probe.starts, lp_solves)
        }
    };
    let total: f64 = sol.h.iter().sum();
    let h = match job.objective {
        // Use the whole time budget (more time never raises the jerk), in whole µs.
        Objective::MinMaxJerk => {
            let stretch = job.limits.total_time / total;
            let h: Vec<f64> = sol.h.iter().map(|x| x * stretch).collect();
            round_to_microseconds(&h, job.limits.total_time)
        }
        // Never shorter than the shortest feasible time: round every interval up.
        Objective::MinTime => sol
            .h
            .iter()
            .map(|x| (x * 1e6 - 1e-6).ceil() * 1e-6)
            .collect(),
    };
    let mut fine = p.clone();
    fine.torque_samples = FINAL_TORQUE_SAMPLES;
    fine.total_time = h.iter().sum();
    let exact = fine
        .inner_via_relaxation(&h, &sol.x)
        .ok_or_else(|| CliError::infeasible("the solver failed on the rounded intervals"))?;
    lp_solves += exact.lp_solves;
    if !search::feasible(&fine, &exact) {
        let binding = if exact.violation > 1e-9 {
            exact.binding
        } else {
            Quantity::Jerk
        };
        return Err(CliError::infeasible(format!(
            "after rounding the intervals to whole microseconds the {} is exceeded (max jerk {:.9} m/s³, violation {:.3e})",
            infeasible_limit(binding, job),
            exact.jerk,
            exact.violation
        )));
    }
    let mut plan = assemble(job, &fine, &exact);
    plan.max_abs = verify::max_abs(&plan, FINAL_TORQUE_SAMPLES)
        .map_err(|e| CliError::infeasible(format!("plan leaves the workspace: {e}")))?;
    plan.solver = SolverStats {
        seconds: clock.elapsed().as_secs_f64(),
        starts: starts as u64,
        lp_solves,
    };
    Ok(plan)
}

fn assemble(job: &Job, p: &Problem, s: &Solution) -> Plan {
    let mut t0 = 0.0;
    let segments = (0..p.knots.segments())
        .map(|k| {
            let seg = Segment {
                t0_s: t0,
                duration_s: s.h[k],
                coeffs: [0, 1, 2].map(|j| p.knots.coefficients(&s.x[j], j, k, s.h[k])),
            };
            t0 += s.h[k];
            seg
        })
        .collect();
    Plan {
        format: PLAN_FORMAT.to_string(),
        objective: job.objective,
        robot: job.robot.clone(),
        limits: job.limits.clone(),
        via_points_m: job.points_m().iter().map(|p| [p.x, p.y, p.z]).collect(),
        knots_m: p.knots.q.clone(),
        intervals_s: s.h.clone(),
        total_time_s: s.h.iter().sum(),
        segments,
        max_abs: Default::default(),
        solver: Default::default(),
    }
}
