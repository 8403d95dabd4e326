//! Minimum time by a feasible trust-region SLP on Σh.
//!
//! Every iterate meets every limit. A step solves the LP linearised in h
//! ([`Problem::time_step`]); its point, whose limits are right only to first
//! order in the change of h, is then time-scaled to the shortest total time
//! at which it meets every limit exactly
//! ([`shortest_scaling`](crate::time_scaling::shortest_scaling)). The scaling
//! absorbs the second-order error that stalls a plain SLP on Σh
//! (docs/planner-speed.md), and the step is accepted on that exact time.
//! The cuts a step's rounds find start the next step's program (but those
//! beside one of its point's own): the extrema move little from step to
//! step, so fewer rounds place them.

use crate::problem::{Cut, Problem, Solution};
use crate::program::{add_new_cuts, near_any};
use crate::time_scaling::shortest_scaling_cuts;

/// Normalised time within which a cut the last step's rounds found is
/// left out beside another of the same limit, joint, segment and side.
const CARRIED_APART: f64 = 1e-3;
/// Steps at most.
const MAX_STEPS: usize = 80;
/// A step promising less than this share of the time ends the descent.
const PROMISE_FLOOR: f64 = 1e-6;
/// Cutting-plane rounds of a descent step's program. Each step starts
/// from the cuts the step before found, so three rounds place them as well
/// as six from the current point's cuts alone did (docs/planner-speed.md).
const DESCENT_ROUNDS: usize = 3;
/// Share of a step's promise lost to time-scaling above which the step is
/// corrected to second order ([`Problem::second_order_corrected`]).
const SCALING_LOSS: f64 = 0.05;
/// Consecutive steps gaining less than this (relative) end the descent.
const STALL_GAIN: f64 = 1e-7;

/// From a feasible solution of `template`, the shortest feasible plan the
/// descent reaches (`start` itself when no step gains).
pub(crate) fn descend_time(template: &Problem, start: &Solution) -> Solution {
    let mut cur = start.clone();
    let mut delta: f64 = 0.05;
    let mut solves = 0;
    let mut stalled = 0;
    // The cuts the last step's rounds found, at extrema of points near the
    // next step's: they start its program beside the current point's own.
    let mut carried: Vec<Cut> = Vec::new();
    // The cuts at the current point's extrema, once its evaluation is known.
    let mut cur_cuts: Option<Vec<Cut>> = None;
    for _ in 0..MAX_STEPS {
        let t_cur: f64 = cur.h.iter().sum();
        let mut p = template.clone();
        p.total_time = t_cur;
        let own =
            cur_cuts.get_or_insert_with(|| p.evaluation(&cur.h, &cur.x, p.torque_samples).cuts);
        let mut cuts = own.clone();
        // Near one of the point's own cuts a carried one adds a nearly
        // parallel row: the own cut holds it.
        let apart: Vec<Cut> = carried
            .iter()
            .filter(|c| !near_any(own, c, CARRIED_APART))
            .copied()
            .collect();
        add_new_cuts(&mut cuts, &apart);
        let initial = cuts.len();
        let step = p.time_step(&cur, delta, &mut cuts, DESCENT_ROUNDS, PROMISE_FLOOR);
        carried = cuts[initial..].to_vec();
        let Ok(step) = step else {
            delta *= 0.25;
            if delta < 1e-7 {
                break;
            }
            continue;
        };
        solves += step.solves;
        // Its exact figures: the step's last round evaluated it.
        let exact = &step.point;
        let promised = t_cur - exact.h.iter().sum::<f64>();
        // A promised gain near the plan's microsecond rounding is not
        // worth the steps: such a tail of steps gains almost nothing
        // together (docs/planner-speed.md).
        if promised <= PROMISE_FLOOR * t_cur {
            break;
        }
        let gain = |c: &Option<(Solution, Option<Vec<Cut>>)>| {
            c.as_ref()
                .map_or(f64::NEG_INFINITY, |c| t_cur - c.0.h.iter().sum::<f64>())
        };
        let mut cand = shortest_scaling_cuts(&p, exact);
        let mut actual = gain(&cand);
        // Time-scaling took back much of the promise: the second-order
        // error of a wide step, which the corrected program mostly avoids.
        if actual < (1.0 - SCALING_LOSS) * promised {
            let corrected = p.second_order_corrected(&cur, delta, &step.program, &cuts);
            solves += u64::from(corrected.is_some());
            if let Some(Ok(corrected)) = corrected {
                let other = shortest_scaling_cuts(&p, &corrected);
                if gain(&other) > actual {
                    actual = gain(&other);
                    cand = other;
                }
            }
        }
        let rho = actual / promised;
        if let (Some((c, c_cuts)), true) = (cand, rho > 0.1) {
            stalled = if actual < STALL_GAIN * t_cur {
                stalled + 1
            } else {
                0
            };
            cur = c;
            cur_cuts = c_cuts;
            // A step that gains about what it promised keeps its region: a
            // wider one promises little more (the linearisation's gain sits
            // at small steps) and overshoots on the curvature.
            if rho < 0.25 {
                delta *= 0.5;
            }
        } else {
            delta *= 0.25;
        }
        if stalled >= 3 || delta < 1e-7 {
            break;
        }
    }
    cur.lp_solves = start.lp_solves + solves;
    cur
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inner::{Method, ROUNDS};
    use crate::problem::feasible;
    use crate::search_tests::{example_problem, uneven_intervals};
    use crate::time_scaling::shortest_scaling;

    #[test]
    fn the_descent_shortens_and_every_iterate_is_feasible() {
        let mut p = example_problem("paper-case2.toml");
        p.limits.jerk = 1.0;
        let h = uneven_intervals(&p);
        let s = p
            .inner(&h, &p.zero_x(), Method::ViaRelaxation, ROUNDS)
            .unwrap();
        let start = shortest_scaling(&p, &s).unwrap();
        let end = descend_time(&p, &start);
        let (t0, t1) = (start.h.iter().sum::<f64>(), end.h.iter().sum::<f64>());
        assert!(t1 < t0 * (1.0 - 1e-3), "{t1} against {t0}");
        assert!(feasible(&p, &end));
        assert!(end.lp_solves > start.lp_solves);
    }
}
