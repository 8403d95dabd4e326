//! [`plan`]: a job → a plan in whole microseconds that meets every limit,
//! or the reason there is none.

use std::sync::Arc;
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::time::Duration;

use nalgebra::Vector3;
use triquint_shared::Travel;
use triquint_shared::plan::figures::kinematics;
use triquint_shared::plan::{
    Objective, PLAN_FORMAT, PLAN_FORMAT_BOUNDED, PLAN_FORMAT_FREE_KNOTS, Plan, Segment, SolverStats,
};

use crate::check::max_abs;
use crate::error::{Limit, PlanError, PointKind};
use crate::free_knots::{FreeShape, free_knots, toward_straight};
use crate::inner::{Method, ROUNDS};
use crate::jerk_knots::jerk_knots;
use crate::job::{Job, KnotPlacement, MAX_SEGMENT_S, MIN_SEGMENT_S};
use crate::min_time::{MinTimeFailure, min_time};
use crate::options::{Control, Observer, Options, Stage};
use crate::problem::{
    Limited, Problem, Solution, feasible, knots_from, meets_every_limit, problem,
};
use crate::rounding::{FINAL_TORQUE_SAMPLES, fine, lengthen_until_feasible, round_within};
use crate::run_state::RunState;
use crate::search::{SearchResult, global_from, relaxed_global};
use crate::stats::{PathDeviation, path_deviation_within};
use crate::streaming::{shortfall, streams};
use crate::time_scaling::{scaled_shape, stretch};

/// How often [`plan_with`] calls its observer.
const OBSERVER_PERIOD: Duration = Duration::from_millis(25);

/// Plans a job on the calling thread (and `opts.threads` workers).
///
/// ```
/// use triquint_planner::{Job, Options, plan};
/// let job = Job::builder()
///     .points_mm([[0.0, 0.0, 600.0], [20.0, 0.0, 600.0], [20.0, 20.0, 610.0]])
///     .total_time(2.0)
///     .build()?;
/// let p = plan(&job, &Options::default())?;
/// assert!(p.total_time_s <= 2.0);
/// # Ok::<(), triquint_planner::PlanError>(())
/// ```
pub fn plan(job: &Job, opts: &Options) -> Result<Plan, PlanError> {
    let state = Arc::new(RunState::new(opts.time_budget));
    run(job, opts, &state)
}

/// [`plan`] with an observer, called on this thread at least every 50 ms
/// while the search runs on another; it may cancel.
///
/// ```
/// use triquint_planner::{CancelReason, Control, Job, Options, PlanError, Progress, plan_with};
/// let job = Job::builder()
///     .points_mm([[0.0, 0.0, 600.0], [20.0, 0.0, 600.0], [20.0, 20.0, 610.0]])
///     .build()?;
/// let mut calls = 0;
/// let r = plan_with(&job, &Options::default(), &mut |_: &Progress| {
///     calls += 1;
///     Control::Cancel
/// });
/// // Either it finished before the first call, or the first call stopped it.
/// assert!(r.is_ok() || r == Err(PlanError::Cancelled { reason: CancelReason::Observer }));
/// # Ok::<(), PlanError>(())
/// ```
pub fn plan_with(
    job: &Job,
    opts: &Options,
    observer: &mut dyn Observer,
) -> Result<Plan, PlanError> {
    let state = Arc::new(RunState::new(opts.time_budget));
    observed(&state, observer, || run(job, opts, &state))
        .unwrap_or_else(|| Err(PlanError::Solver("the search thread panicked".into())))
}

/// Runs `work` on another thread while this one calls `observer` (which
/// may cancel `state`); None when `work` panicked. The sender moves into
/// the thread, so a panic there disconnects the channel and ends the
/// observer's loop rather than leaving it waiting for a message that will
/// never come.
fn observed<R: Send>(
    state: &RunState,
    observer: &mut dyn Observer,
    work: impl FnOnce() -> R + Send,
) -> Option<R> {
    let (done, finished) = channel();
    std::thread::scope(|s| {
        let worker = s.spawn(move || {
            let r = work();
            let _ = done.send(());
            r
        });
        while let Err(RecvTimeoutError::Timeout) = finished.recv_timeout(OBSERVER_PERIOD) {
            if observer.progress(&state.progress()) == Control::Cancel {
                state.cancel();
            }
        }
        worker.join().ok()
    })
}

fn run(job: &Job, opts: &Options, state: &Arc<RunState>) -> Result<Plan, PlanError> {
    let fixed = job_problem(job, state)?;
    // The travel joins the problem when the plan without it leaves it, as
    // the limits other than jerk join the relaxation when its optimum breaks
    // one: without it the problem is a relaxation, whose optimum is the
    // problem's own when it stays inside (and then the plan is the one the
    // travel never touched).
    let (mut plan, starts) = match planned(job, &fixed, opts, state)? {
        (plan, _) if leaves_travel(&plan, job.travel()).is_some() => {
            let bounded = Problem {
                travel: Some(job.travel().clone()),
                ..fixed.clone()
            };
            planned(job, &bounded, opts, state)?
        }
        done => done,
    };
    if let Some(e) = leaves_travel(&plan, job.travel()) {
        return Err(e);
    }
    // The guard that nothing written has a segment the wire cannot carry.
    if let Some((k, h)) = plan
        .intervals_s
        .iter()
        .enumerate()
        .find(|(_, h)| **h > MAX_SEGMENT_S)
    {
        return Err(PlanError::Solver(format!(
            "segment {k} lasts {h} s, more than the {MAX_SEGMENT_S} s a segment may"
        )));
    }
    streams(&plan)?;
    if let Some(limit) = job.max_deviation_m() {
        // Recorded, so that `check` proves it without being told.
        plan.format = PLAN_FORMAT_BOUNDED.to_string();
        plan.max_deviation_m = Some(limit);
    }
    plan.max_abs = max_abs(&plan, FINAL_TORQUE_SAMPLES)
        .map_err(|e| PlanError::Solver(format!("the plan leaves the workspace: {e}")))?;
    let progress = state.progress();
    plan.solver = SolverStats {
        seconds: progress.elapsed.as_secs_f64(),
        starts: starts as u64,
        lp_solves: progress.lp_solves,
    };
    match job.shaper() {
        Some(spec) => crate::shaping::job_shaped(
            job,
            &plan,
            spec,
            &mut |j: &Job| run(j, opts, state),
            &mut |s: f64| retimed(job, &fixed, &plan, s),
        ),
        None => Ok(plan),
    }
}

/// The plan of `fixed` (the job's problem at its fixed knots, or the
/// knots the planner chooses when the job asks for that) and its search
/// starts, without its recorded figures.
fn planned(
    job: &Job,
    fixed: &Problem,
    opts: &Options,
    state: &Arc<RunState>,
) -> Result<(Plan, usize), PlanError> {
    let mut added = None;
    let (p, free, r) = match job.knot_placement() {
        KnotPlacement::Free if job.objective() == Objective::MinMaxJerk => {
            let f = solve(job, fixed, opts);
            let better = f.as_ref().ok().and_then(|(s, starts)| {
                let (q, sol, knots) = jerk_knots(fixed, s, job.limits().total_time)?;
                (sol.jerk < s.jerk).then_some((q, sol, knots, *starts))
            });
            match better {
                Some((q, sol, knots, starts)) => {
                    added = Some(knots);
                    (q, true, Ok((sol, starts)))
                }
                None => (fixed.clone(), false, f),
            }
        }
        KnotPlacement::Free => match solve_free(job, fixed, opts)? {
            Some((p, r, false)) => (p, true, r),
            // Torque bound the free shape, which is only time-scaled for
            // it: the fixed knots, reshaped by the search, may do better.
            Some((p, r, true)) => {
                let f = solve(job, fixed, opts);
                let total = |r: &Result<(Solution, usize), PlanError>| match r {
                    Ok((s, _)) => s.h.iter().sum::<f64>(),
                    Err(_) => f64::INFINITY,
                };
                if r.is_ok() && total(&r) <= total(&f) {
                    (p, true, r)
                } else {
                    (fixed.clone(), false, f)
                }
            }
            None => (fixed.clone(), false, solve(job, fixed, opts)),
        },
        KnotPlacement::Fixed => (fixed.clone(), false, solve(job, fixed, opts)),
    };
    if let Some(reason) = state.cancelled() {
        return Err(PlanError::Cancelled { reason });
    }
    let (sol, starts) = r?;
    let mut plan = assemble(job, &p, &sol);
    if free {
        plan.format = PLAN_FORMAT_FREE_KNOTS.to_string();
        plan.free_knots = added.unwrap_or_else(|| (1..p.knots.len() - 1).collect());
    }
    if free && job.knot_segments().is_some() {
        // A segment count the job asks for is kept, or refused: falling
        // back to other knots would not be what it asked.
        streams(&plan)?;
    }
    // Min-max-jerk's added knots are not moved toward the straight
    // segment: over the bound, the fixed knots' plan is the one to try.
    let over_bound = |plan: &Plan| -> Result<bool, PlanError> {
        Ok(match job.max_deviation_m() {
            Some(limit) if job.objective() == Objective::MinMaxJerk => {
                path_deviation_within(plan, limit)
                    .map_err(|e| PlanError::Solver(format!("the plan leaves the workspace: {e}")))?
                    .bound_m
                    > limit
            }
            _ => false,
        })
    };
    if free && (!passes_check(&plan)? || shortfall(&plan).is_some() || over_bound(&plan)?) {
        // Nothing the planner writes fails the check or the streaming
        // rule: the fixed knots then (fewer, longer segments).
        let (sol, _) = solve(job, fixed, opts)?;
        let plan = assemble(job, fixed, &sol);
        return within_deviation(job, fixed, opts, plan, None).map(|p| (p, starts));
    }
    // The bound moves a point-to-point move's free knots toward the
    // straight segment; min-max-jerk's falls back to the fixed knots.
    let free = (free && job.objective() == Objective::MinTime).then_some(&p);
    within_deviation(job, fixed, opts, plan, free).map(|p| (p, starts))
}

/// `plan` when the job sets no bound on the Cartesian deviation or its
/// certificate proves it; else a free-knot plan (`free`: its problem)
/// with its knots moved toward the straight segment and re-planned by the
/// min-time search until the certificate holds, or else the fixed knots' plan if that holds; or the verdict with
/// the closest plan's figures.
fn within_deviation(
    job: &Job,
    fixed: &Problem,
    opts: &Options,
    plan: Plan,
    free: Option<&Problem>,
) -> Result<Plan, PlanError> {
    let Some(limit) = job.max_deviation_m() else {
        return Ok(plan);
    };
    let certify = |plan: &Plan| {
        path_deviation_within(plan, limit)
            .map_err(|e| PlanError::Solver(format!("the plan leaves the workspace: {e}")))
    };
    let first = certify(&plan)?;
    if first.bound_m <= limit {
        return Ok(plan);
    }
    let mut closest = first.clone();
    let mut closer = |d: PathDeviation| {
        if d.bound_m < closest.bound_m {
            closest = d;
        }
    };
    if let Some(p) = free {
        let [a, b] = [0, 1].map(|i| job.points_m()[i]);
        // The deviation falls about linearly in λ: aim below the bound,
        // then closer to the straight segment, then onto it.
        let share = limit / first.max_m;
        let mut tried = Vec::new();
        let mut found = None;
        for lambda in [1.0 - 0.8 * share, 1.0 - 0.4 * share, 1.0] {
            let lambda = lambda.clamp(0.0, 1.0);
            if tried.contains(&lambda) {
                continue;
            }
            tried.push(lambda);
            let Some(q) = toward_straight(p, a, b, lambda) else {
                continue;
            };
            let Ok((s, _)) = solve(job, &q, opts) else {
                continue;
            };
            let mut moved = assemble(job, &q, &s);
            moved.format = PLAN_FORMAT_FREE_KNOTS.to_string();
            moved.free_knots = (1..q.knots.len() - 1).collect();
            if !passes_check(&moved)? {
                continue;
            }
            let d = certify(&moved)?;
            if d.bound_m <= limit {
                found = Some(moved);
                break;
            }
            closer(d);
        }
        // The fixed knots' plan when it holds and is no longer.
        let (sol, _) = solve(job, fixed, opts)?;
        let straight = assemble(job, fixed, &sol);
        let d = certify(&straight)?;
        return match found {
            Some(moved) if d.bound_m > limit || moved.total_time_s <= straight.total_time_s => {
                Ok(moved)
            }
            _ if d.bound_m <= limit => Ok(straight),
            _ => {
                closer(d);
                Err(deviation(limit, &closest))
            }
        };
    }
    Err(deviation(limit, &closest))
}

/// The verdict when no plan met the deviation bound `limit` (m): the
/// closest plan's figures.
fn deviation(limit: f64, closest: &PathDeviation) -> PlanError {
    PlanError::Deviation {
        limit_m: limit,
        bound_m: closest.bound_m,
        reached_m: closest.max_m,
        at_s: closest.at_s,
    }
}

/// A free-knot plan's check (its maxima recorded first, as the plan will).
fn passes_check(plan: &Plan) -> Result<bool, PlanError> {
    let mut plan = plan.clone();
    plan.max_abs = max_abs(&plan, FINAL_TORQUE_SAMPLES)
        .map_err(|e| PlanError::Solver(format!("the plan leaves the workspace: {e}")))?;
    Ok(crate::check::check(&plan).is_ok_and(|rows| rows.iter().all(|r| r.ok)))
}

/// The first segment in which a slider leaves the travel, from the exact
/// extremes of its quintics as `check` finds them (the knots are inside:
/// the job checked them). The solves keep the sliders inside; this is the
/// guard that nothing written leaves it.
fn leaves_travel(plan: &Plan, travel: &Travel) -> Option<PlanError> {
    plan.segments.iter().enumerate().find_map(|(segment, seg)| {
        let k = kinematics(std::slice::from_ref(seg));
        let o = travel
            .outside(&k.position_min)
            .or_else(|| travel.outside(&k.position_max))?;
        Some(PlanError::LeavesTravel {
            segment,
            axis: o.axis,
            joint_m: o.position_m,
            limit_m: o.limit_m,
        })
    })
}

/// `plan`, at the job's own knots, slowed by `s`: its intervals × s
/// rounded to whole microseconds and solved exactly there, as the planner
/// finishes any plan; None when it is not at the job's knots, exceeds the
/// total-time limit, breaks a limit (torque included), leaves the travel
/// or the job's deviation bound, or a solve fails.
fn retimed(job: &Job, fixed: &Problem, plan: &Plan, s: f64) -> Option<Plan> {
    if !plan.free_knots.is_empty()
        || plan.intervals_s.len() != fixed.nseg()
        || s.is_nan()
        || s < 1.0
    {
        return None;
    }
    let h: Vec<f64> = plan
        .intervals_s
        .iter()
        .map(|x| ((x * s * 1e6).round() * 1e-6).max(1e-6))
        .collect();
    let total: f64 = h.iter().sum();
    if total > job.limits().total_time {
        return None;
    }
    let f = fine(fixed, total);
    let sol = f.inner(&h, &fixed.zero_x(), Method::Final, ROUNDS)?;
    if !meets_every_limit(&f, &sol) {
        return None;
    }
    let mut slow = assemble(job, fixed, &sol);
    if leaves_travel(&slow, job.travel()).is_some() {
        return None;
    }
    if let Some(limit) = job.max_deviation_m() {
        if path_deviation_within(&slow, limit).ok()?.bound_m > limit {
            return None;
        }
        slow.format = PLAN_FORMAT_BOUNDED.to_string();
        slow.max_deviation_m = Some(limit);
    }
    slow.max_abs = max_abs(&slow, FINAL_TORQUE_SAMPLES).ok()?;
    slow.solver = plan.solver.clone();
    Some(slow)
}

/// The planning problem of a job at its total-time limit.
pub(crate) fn job_problem(job: &Job, state: &Arc<RunState>) -> Result<Problem, PlanError> {
    let model = job.robot().model::<f64>();
    let pts: Vec<Vector3<f64>> = job.knots_m().into_iter().map(Vector3::from).collect();
    let knots = knots_from(&pts, &model).map_err(|(i, reason)| PlanError::OutsideWorkspace {
        point: PointKind::Knot,
        index: i,
        position_m: pts[i].into(),
        reason,
    })?;
    let mut p = problem(knots, job.limits(), model, job.limits().total_time);
    p.run = state.clone();
    p.h_max = MAX_SEGMENT_S;
    p.h_min = MIN_SEGMENT_S;
    Ok(p)
}

/// The limit of a quantity bounded in magnitude (travel has its own error).
fn limit_of(q: Limited) -> Limit {
    match q {
        Limited::Velocity => Limit::Velocity,
        Limited::Acceleration => Limit::Acceleration,
        Limited::Jerk | Limited::Travel => Limit::Jerk,
        Limited::Torque => Limit::Torque,
    }
}

/// The infeasibility of `s`: its binding limit and how far it got. When the
/// travel binds, where the closest plan leaves it.
fn infeasible(p: &Problem, s: &Solution, shortest: Option<f64>) -> PlanError {
    let q = if s.violation > 1e-9 {
        s.binding
    } else {
        Limited::Jerk
    };
    if q == Limited::Travel
        && let Some((segment, axis, joint_m, limit_m)) = p.travel_breach(&s.h, &s.x)
    {
        return PlanError::LeavesTravel {
            segment,
            axis,
            joint_m,
            limit_m,
        };
    }
    let q = if q == Limited::Travel {
        Limited::Jerk
    } else {
        q
    };
    let limit_value = p.limit(q);
    let reached = match q {
        Limited::Jerk => s.jerk,
        _ => limit_value * (1.0 + s.violation),
    };
    PlanError::Infeasible {
        limit: limit_of(q),
        limit_value,
        reached,
        shortest_total_time: shortest,
    }
}

/// The shortest plan in whole microseconds that meets every limit:
/// min-time search, then rounding and repair.
fn shortest(
    p: &Problem,
    opts: &Options,
    relaxed: Option<SearchResult>,
) -> Result<(Solution, usize), MinTimeFailure> {
    p.run.set_stage(Stage::MinTime);
    let (best, probe) = min_time(p, opts, relaxed)?;
    p.run.set_stage(Stage::Finishing);
    let Some(rounded) = lengthen_until_feasible(p, &best) else {
        return Err(MinTimeFailure {
            best: Some(Box::new(best)),
        });
    };
    Ok((rounded, probe.starts))
}

fn solve(job: &Job, p: &Problem, opts: &Options) -> Result<(Solution, usize), PlanError> {
    let total_time = job.limits().total_time;
    match job.objective() {
        Objective::MinMaxJerk => {
            p.run.set_stage(Stage::Searching);
            let relaxed = relaxed_global(p, opts);
            // When the relaxation's optimum breaks a limit other than jerk,
            // the full search at this time only pays if a plan exists here:
            // the shortest time (which does not depend on this one) decides.
            let mut known_short = None;
            if let Some(r) = &relaxed
                && p.accept_relaxed(&r.best).is_none()
            {
                let short = shortest(p, opts, Some(r.clone()));
                match &short {
                    Ok((s, _)) if s.h.iter().sum::<f64>() > total_time * (1.0 + 1e-12) => {
                        return Err(too_short(p, s, total_time));
                    }
                    Err(f) => {
                        return Err(match &f.best {
                            Some(b) => infeasible(p, b, None),
                            None => infeasible(p, &p.evaluate(&r.best.h, &r.best.x), None),
                        });
                    }
                    Ok(_) => {}
                }
                known_short = Some(short);
            }
            let r = global_from(p, opts, relaxed).ok_or_else(|| solver_failure(p))?;
            let found = feasible(p, &r.best);
            if found {
                p.run.set_stage(Stage::Finishing);
                if let Some(s) = round_within(p, &r.best, total_time) {
                    return Ok((s, r.starts));
                }
            }
            // Restoration: the shortest feasible plan, stretched to the time
            // budget and optimised there; or, when rounding that fails, the
            // shortest plan itself.
            let short = known_short.unwrap_or_else(|| shortest(p, opts, None));
            let Ok((s, starts)) = short else {
                return Err(infeasible(p, &r.best, None));
            };
            let t_short: f64 = s.h.iter().sum();
            if t_short > total_time {
                return Err(infeasible(p, &r.best, Some(t_short)));
            }
            let stretched = stretch(p, &s, total_time)
                .filter(|x| feasible(p, x))
                .and_then(|x| round_within(p, &x, total_time));
            Ok((stretched.unwrap_or(s), starts))
        }
        Objective::MinTime => {
            let (s, starts) = shortest(p, opts, None).map_err(|f| match &f.best {
                Some(b) => infeasible(p, b, None),
                None => solver_failure(p),
            })?;
            if s.h.iter().sum::<f64>() > total_time * (1.0 + 1e-12) {
                return Err(too_short(p, &s, total_time));
            }
            Ok((s, starts))
        }
    }
}

/// A plan's solution and search starts, or the verdict.
type FreeResult = Result<(Solution, usize), PlanError>;

/// Min-time at free knots ([`free_knots`]): the problem there and its
/// shortest plan in whole microseconds (or the verdict against the job's
/// total time), and whether torque slowed it; None when no time-scaling
/// of the free-knot shape meets every limit, and the fixed knots are
/// planned instead. Err when the job's segment count cannot be had.
fn solve_free(
    job: &Job,
    fixed: &Problem,
    opts: &Options,
) -> Result<Option<(Problem, FreeResult, bool)>, PlanError> {
    fixed.run.set_stage(Stage::MinTime);
    let shape = free_knots(fixed, job.knot_segments()).map_err(|e| {
        PlanError::invalid(
            "knots.segments",
            format!(
                "{} segments: this move takes at most {} (segments of at least 5 ms)",
                job.knot_segments().unwrap_or_default(),
                e.most
            ),
        )
    })?;
    let (p, s, slowed) = match shape {
        None => return Ok(None),
        Some(FreeShape::Solved(p, s, slowed)) => (p, s, slowed),
        Some(FreeShape::Knots(p)) => {
            let r = solve(job, &p, opts);
            return Ok(Some((p, r, false)));
        }
    };
    let total_time = job.limits().total_time;
    let r = if s.h.iter().sum::<f64>() > total_time * (1.0 + 1e-12) {
        Err(too_short(&p, &s, total_time))
    } else {
        Ok((s, 0))
    };
    Ok(Some((p, r, slowed)))
}

/// The verdict when the shortest plan `s` is longer than `total_time`: the
/// limit it breaks when time-scaled to `total_time`, and its time. The
/// scaled plan is evaluated exactly, not re-solved: re-solving its knot
/// derivatives at the shorter time lowers the figure a little and costs the
/// verdict's most expensive solves (docs/planner-speed.md).
fn too_short(p: &Problem, s: &Solution, total_time: f64) -> PlanError {
    let t: f64 = s.h.iter().sum();
    let (h, x) = scaled_shape(s, total_time);
    let mut at = p.clone();
    at.total_time = total_time;
    let scaled = at.evaluate(&h, &x);
    if scaled.jerk.is_finite() && scaled.violation.is_finite() {
        infeasible(p, &scaled, Some(t))
    } else {
        PlanError::Infeasible {
            limit: Limit::TotalTime,
            limit_value: total_time,
            reached: t,
            shortest_total_time: Some(t),
        }
    }
}

fn solver_failure(p: &Problem) -> PlanError {
    PlanError::Solver(format!(
        "no solution of the inner problem for {} knots",
        p.knots.len()
    ))
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
        objective: job.objective(),
        robot: job.robot().clone(),
        limits: job.limits().clone(),
        travel: job.travel().clone(),
        ceilings: job.ceilings().clone(),
        via_points_m: job.points_m().to_vec(),
        knots_m: p.knots.q.clone(),
        free_knots: Vec::new(),
        max_deviation_m: None,
        intervals_s: s.h.clone(),
        total_time_s: s.h.iter().sum(),
        segments,
        max_abs: Default::default(),
        solver: Default::default(),
        shaping: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Progress;
    use crate::search_tests::example_problem;

    /// A search that panics ends the observed run with None (the CLI's
    /// clear error), where the observer once waited for it forever. Run
    /// on its own thread, so that such a hang fails the test rather than
    /// stalling the suite.
    #[test]
    fn a_panicking_search_ends_the_observed_run() {
        let (tx, rx) = channel();
        std::thread::spawn(move || {
            let state = RunState::new(None);
            let mut calls = 0;
            let mut observer = |_: &Progress| {
                calls += 1;
                Control::Continue
            };
            let r: Option<()> = observed(&state, &mut observer, || {
                std::thread::sleep(OBSERVER_PERIOD * 2);
                panic!("a search that breaks")
            });
            let _ = tx.send((r.is_none(), calls));
        });
        let (ended_as_none, calls) = rx
            .recv_timeout(Duration::from_secs(60))
            .expect("the observed run ended");
        assert!(ended_as_none);
        assert!(calls >= 1);
        let state = RunState::new(None);
        let ok = observed(&state, &mut |_: &Progress| Control::Continue, || 7);
        assert_eq!(ok, Some(7));
    }

    /// Where travel binds, the verdict is where the closest plan leaves it.
    #[test]
    fn a_travel_that_binds_is_solved_for_and_named_when_it_cannot_be_met() {
        let mut p = example_problem("paper-case1.toml");
        let h = vec![p.total_time / p.knots.segments() as f64; p.knots.segments()];
        let free = p.inner(&h, &p.zero_x(), Method::Final, ROUNDS).unwrap();
        // Every knot inside, the ends a hair beyond the lowest and highest knot.
        let end = |f: fn(f64, f64) -> f64, from: f64| {
            [0, 1, 2].map(|j| p.knots.q.iter().map(|q| q[j]).fold(from, f))
        };
        let (bottom, top) = (end(f64::min, f64::MAX), end(f64::max, f64::MIN));
        p.travel = Some(Travel {
            min: bottom.map(|b| b - 1e-6),
            max: top.map(|t| t + 1e-6),
        });
        let s = p.evaluate(&free.h, &free.x);
        assert!(s.violation > 0.0 && s.binding == Limited::Travel, "{s:?}");
        let Some((segment, axis, joint_m, limit_m)) = p.travel_breach(&s.h, &s.x) else {
            panic!("no breach");
        };
        assert!(
            (joint_m > limit_m && limit_m == top[axis] + 1e-6)
                || (joint_m < limit_m && limit_m == bottom[axis] - 1e-6),
            "{joint_m} {limit_m}"
        );
        assert_eq!(
            infeasible(&p, &s, None),
            PlanError::LeavesTravel {
                segment,
                axis,
                joint_m,
                limit_m,
            }
        );
        // The solve at the same intervals keeps every slider inside.
        let bound = p.inner(&h, &p.zero_x(), Method::Final, ROUNDS).unwrap();
        assert_eq!(bound.violation, 0.0);
        assert_eq!(p.travel_breach(&bound.h, &bound.x), None);
        assert!(bound.jerk > free.jerk);
    }

    #[test]
    fn an_infeasible_verdict_names_the_binding_limit_and_its_value() {
        let p = example_problem("paper-case1.toml");
        let h = vec![p.total_time / p.knots.segments() as f64; p.knots.segments()];
        let mut s = p.evaluate(&h, &p.zero_x());
        s.violation = 0.25;
        s.binding = Limited::Torque;
        let e = infeasible(&p, &s, Some(7.0));
        assert_eq!(
            e,
            PlanError::Infeasible {
                limit: Limit::Torque,
                limit_value: p.limits.torque,
                reached: p.limits.torque * 1.25,
                shortest_total_time: Some(7.0),
            }
        );
        // Within the solves' accuracy of every other limit, jerk binds.
        s.violation = 1e-12;
        match infeasible(&p, &s, None) {
            PlanError::Infeasible { limit, reached, .. } => {
                assert_eq!(limit, Limit::Jerk);
                assert_eq!(reached, s.jerk);
            }
            other => panic!("{other:?}"),
        }
    }
}
