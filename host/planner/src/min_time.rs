//! Minimum time: the shortest total time with a plan meeting every limit,
//! from the jerk-only relaxation's shapes (a lower bound, then time-scaled
//! until every limit holds) and the descent on Σh.

use crate::options::Options;
use crate::problem::{Problem, Solution, feasible};
use crate::search::{REFERENCE_S_PER_SEGMENT, SearchResult, global_from, relaxed_shapes};
use crate::time_descent::descend_time;
use crate::time_scaling::{scale, shortest_scaling};

/// Why min-time found no plan: the binding limit and the shortest time tried.
#[derive(Debug, Clone)]
pub(crate) struct MinTimeFailure {
    /// The best plan at the longest time tried, when the search got one.
    pub(crate) best: Option<Box<Solution>>,
}

/// Relative distance from the relaxation's shortest time within which a
/// time-scaled shape is taken to meet it (the scaling is bisected to 1e-9).
const LOWER_BOUND_MET: f64 = 1e-8;

/// Shortest total time with a plan meeting every limit, and a plan there.
/// It does not depend on the job's total-time limit, so a job's verdict
/// and its shortest time agree whatever bound is asked.
///
/// Jerk alone gives a lower bound: the jerk-only optimum's shape does not
/// depend on T (jerk scales as T⁻³), so its global optimum at any T, scaled
/// to the jerk limit, is the shortest time when nothing else binds (its
/// search ends at the first refined agreement, so the bound is as good as
/// the optimum that search finds; a search refined only as a shape's,
/// [`SearchResult::loose`], bounds nothing). Each
/// refined shape of that relaxation is time-scaled until velocity,
/// acceleration and torque hold too, then shortened by the descent on Σh
/// ([`descend_time`], every iterate feasible); the shortest wins.
/// Only when no shape meets the limits at any time scale does a walk-up
/// with the local search (which may reshape it) look for a first plan.
///
/// `relaxed` is the relaxation's search result when the caller has it (at
/// any total time: only its shapes are used).
pub(crate) fn min_time(
    template: &Problem,
    opts: &Options,
    relaxed: Option<SearchResult>,
) -> Result<(Solution, SearchResult), MinTimeFailure> {
    let at = |t: f64| template.retimed(t);
    // A reference time of 0.5 s per segment: in theory any would do (but
    // for h_min and h_max); the search's absolute tolerances make it matter
    // in practice (docs/planner-speed.md).
    let t_ref = REFERENCE_S_PER_SEGMENT * template.knots.segments() as f64;
    // Only the shapes `relaxed_shapes` gives: a search that ran further
    // would make the verdict's shortest time depend on the time asked.
    let probe = match relaxed.filter(|r| r.as_shapes) {
        Some(r) => r,
        // The relaxation's travel rows too (`global_from` searches on when
        // its best breaks them).
        None => {
            let reference = at(t_ref);
            global_from(&reference.relaxed(), opts, relaxed_shapes(&reference, opts))
                .ok_or(MinTimeFailure { best: None })?
        }
    };
    let s = &probe.best;
    let total: f64 = s.h.iter().sum();
    let t_low = total * (s.jerk / template.limits.jerk).cbrt();
    // Each refined shape of the relaxation, time-scaled until it meets every
    // limit; the shortest is shortened by the descent on Σh (every iterate
    // feasible).
    let total_of = |s: &Solution| s.h.iter().sum::<f64>();
    let shortest_start = probe
        .shapes
        .iter()
        .filter_map(|shape| shortest_scaling(template, &template.evaluate(&shape.h, &shape.x)))
        .min_by(|a, b| total_of(a).total_cmp(&total_of(b)));
    // One descent, from the shape that starts shortest: descending from
    // every shape costs more and ends at the same plan (docs/planner-speed.md).
    if let Some(start) = shortest_start {
        // It meets every limit at the relaxation's own shortest time, a
        // lower bound of this problem's: no descent can shorten it (so a
        // move where only jerk binds skips the descent's solves).
        if !probe.loose && total_of(&start) <= t_low * (1.0 + LOWER_BOUND_MET) {
            return Ok((start, probe));
        }
        let best = descend_time(template, &start);
        return Ok((best, probe));
    }
    let mut spent = 0;
    // No shape of the relaxation meets the limits at any time scale (torque
    // that slowing down does not lower): walk up from the lower bound with
    // the local search, which may reshape it.
    let mut last = None;
    let mut found = None;
    let mut t = t_low;
    for _ in 0..40 {
        let p = at(t);
        if let Some(guess) = scale(&p, s, t) {
            let sol = p.local_search_until(&guess, TRIAL_STEPS, 1e-9, &|sol| feasible(&p, sol));
            spent += sol.lp_solves;
            if feasible(&p, &sol) {
                found = Some(sol);
                break;
            }
            last = Some(sol);
        }
        if template.run.cancelled().is_some() {
            break;
        }
        t *= 1.1;
    }
    let Some(found) = found else {
        return Err(MinTimeFailure {
            best: last.map(Box::new),
        });
    };
    let mut best = descend_time(template, &found);
    // The descent's count starts from the walk-up trial's, already in `spent`.
    best.lp_solves = spent + best.lp_solves - found.lp_solves;
    Ok((best, probe))
}

/// Trust-region steps of one walk-up trial: a trial that has not found a
/// feasible point by then counts as infeasible.
const TRIAL_STEPS: usize = 20;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search_tests::example_problem;

    /// Jerk alone bounds the shortest time from below; the answer meets
    /// every limit and sits between that bound and the first feasible
    /// scaling of the relaxation's best shape.
    #[test]
    fn the_shortest_time_is_feasible_and_above_the_jerk_bound() {
        let mut p = example_problem("paper-case2.toml");
        p.limits.jerk = 1.0;
        let opts = Options {
            starts: 2,
            ..Options::default()
        };
        let (best, probe) = min_time(&p, &opts, None).unwrap();
        let s = &probe.best;
        let t_low = s.h.iter().sum::<f64>() * (s.jerk / p.limits.jerk).cbrt();
        let t: f64 = best.h.iter().sum();
        assert!(feasible(&p, &best));
        assert!(t >= t_low * (1.0 - 1e-8), "{t} below the bound {t_low}");
        // No longer than the best shape's scaling, when there is one.
        if let Some(first) = shortest_scaling(&p, &p.evaluate(&s.h, &s.x)) {
            assert!(t <= first.h.iter().sum::<f64>() * (1.0 + 1e-12));
        }
    }
}
