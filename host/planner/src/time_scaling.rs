//! Time-scaling a solution's shape: the same intervals and knot
//! derivatives stretched by a factor α (velocities ÷ α, accelerations ÷ α²,
//! jerk ÷ α³), evaluated as it is or re-solved at the new intervals.

use crate::inner::{Method, ROUNDS};
use crate::problem::{Cut, Problem, Solution, feasible};

/// Knot derivatives of a shape time-scaled by α: velocities ÷ α, accelerations ÷ α².
pub(crate) fn scaled_x(x: &[Vec<f64>; 3], alpha: f64) -> [Vec<f64>; 3] {
    x.clone().map(|v| {
        let n = v.len() / 2;
        v.iter()
            .enumerate()
            .map(|(i, x)| {
                if i < n {
                    x / alpha
                } else {
                    x / (alpha * alpha)
                }
            })
            .collect()
    })
}

/// `s`'s shape time-scaled (and evaluated, not re-solved) to the shortest
/// total time at which it meets every limit. Velocity, acceleration and
/// jerk fall as α⁻¹, α⁻², α⁻³ with the time scale α, and torque's inertial
/// part as α⁻², so the feasible scalings are (in practice) a half-line:
/// bracketed, then bisected to a relative 1e-9.
pub(crate) fn shortest_scaling(p: &Problem, s: &Solution) -> Option<Solution> {
    shortest_scaling_cuts(p, s).map(|(sol, _)| sol)
}

/// [`shortest_scaling`], with the cuts of the scaled solution's evaluation
/// when it evaluated it (not when it is `s` itself).
pub(crate) fn shortest_scaling_cuts(
    p: &Problem,
    s: &Solution,
) -> Option<(Solution, Option<Vec<Cut>>)> {
    // The segment that broke a limit at the last scaling tried: the next
    // infeasible one most likely breaks there too.
    let mut broken = 0;
    let mut at = |alpha: f64| {
        let h: Vec<f64> = s.h.iter().map(|x| x * alpha).collect();
        let x = scaled_x(&s.x, alpha);
        match p.feasible_evaluation(&h, &x, broken) {
            Ok(f) => Some((Solution::with_figures(h, x, &f), Some(f.cuts))),
            Err(k) => {
                broken = k;
                None
            }
        }
    };
    let (mut lo, mut hi, mut best) = if feasible(p, s) {
        // No shape meets the jerk limit faster than (J / J_max)^(1/3).
        let lo = (s.jerk / p.limits.jerk).cbrt().min(1.0);
        (lo * (1.0 - 1e-12), 1.0, (s.clone(), None))
    } else {
        let mut alpha = 1.0;
        let mut found = None;
        for _ in 0..30 {
            alpha *= 1.0 + (0.5 * s.violation).clamp(1e-4, 0.5);
            if let Some(sol) = at(alpha) {
                found = Some(sol);
                break;
            }
        }
        (1.0, alpha, found?)
    };
    while hi - lo > 1e-9 * hi {
        let mid = 0.5 * (lo + hi);
        match at(mid) {
            Some(sol) => {
                hi = mid;
                best = sol;
            }
            None => lo = mid,
        }
    }
    let (best, cuts) = best;
    Some((
        Solution {
            lp_solves: s.lp_solves,
            ..best
        },
        cuts,
    ))
}

/// A solution's intervals and knot derivatives time-scaled to total time
/// `t` (intervals × α, velocities ÷ α, accelerations ÷ α²): the same
/// shape, not re-solved.
pub(crate) fn scaled_shape(s: &Solution, t: f64) -> (Vec<f64>, [Vec<f64>; 3]) {
    let alpha = t / s.h.iter().sum::<f64>();
    let h: Vec<f64> = s.h.iter().map(|x| x * alpha).collect();
    (h, scaled_x(&s.x, alpha))
}

/// A solution's shape time-scaled to total time `t` ([`scaled_shape`]) and
/// re-solved exactly at the scaled intervals.
pub(crate) fn scale(p: &Problem, s: &Solution, t: f64) -> Option<Solution> {
    let (h, x) = scaled_shape(s, t);
    let mut p = p.clone();
    p.total_time = t;
    p.inner(&h, &x, Method::ViaRelaxation, ROUNDS)
}

/// A solution's shape time-scaled to total time `t` (its intervals kept
/// within the problem's bounds), re-solved and locally optimised there.
pub(crate) fn stretch(p: &Problem, s: &Solution, t: f64) -> Option<Solution> {
    let mut guess = scale(p, s, t)?;
    let mut p = p.clone();
    p.total_time = t;
    let mut h = guess.h.clone();
    if within_bounds(&mut h, p.h_min, p.h_max) {
        // Scaled past the longest interval: the search's trust region would
        // keep it there, so it starts from the shape brought within.
        guess = p.inner(&h, &guess.x, Method::ViaRelaxation, ROUNDS)?;
    }
    Some(p.local_search(&guess, 200, 1e-9))
}

/// Brings intervals that sum to T into [lo, hi] keeping the sum: those
/// outside are clamped and the rest scaled to make up the difference, until
/// none is outside. The search's trust region only keeps a move within the
/// bounds, so a start must begin there. Intervals already within are
/// untouched; true when any was not.
pub(crate) fn within_bounds(h: &mut [f64], lo: f64, hi: f64) -> bool {
    let total: f64 = h.iter().sum();
    let mut moved = false;
    for _ in 0..h.len() {
        if h.iter().all(|x| (lo..=hi).contains(x)) {
            return moved;
        }
        moved = true;
        h.iter_mut().for_each(|x| *x = x.clamp(lo, hi));
        let held: f64 = h.iter().filter(|&&x| x == lo || x == hi).sum();
        let free: f64 = h.iter().filter(|&&x| x != lo && x != hi).sum();
        if free <= 0.0 {
            return moved;
        }
        let f = (total - held) / free;
        h.iter_mut()
            .filter(|x| **x != lo && **x != hi)
            .for_each(|x| *x *= f);
    }
    moved
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inner::Method;
    use crate::search_tests::{example_problem, uneven_intervals};

    #[test]
    fn jerk_scales_as_the_cube_of_the_time_scale() {
        let p = example_problem("paper-case1.toml").relaxed();
        let h = uneven_intervals(&p);
        let s = p.inner(&h, &p.zero_x(), Method::Direct, ROUNDS).unwrap();
        for alpha in [0.5, 1.7] {
            let hs: Vec<f64> = s.h.iter().map(|x| x * alpha).collect();
            let scaled = p.evaluate(&hs, &scaled_x(&s.x, alpha));
            let want = s.jerk / alpha.powi(3);
            assert!((scaled.jerk - want).abs() <= 1e-9 * want, "α {alpha}");
        }
    }

    #[test]
    fn the_shortest_scaling_is_feasible_and_a_hair_shorter_is_not() {
        let mut p = example_problem("paper-case2.toml");
        p.limits.jerk = 1.0;
        let h = uneven_intervals(&p);
        let s = p
            .inner(&h, &p.zero_x(), Method::ViaRelaxation, ROUNDS)
            .unwrap();
        let best = shortest_scaling(&p, &s).expect("a scaling meets the limits");
        assert!(feasible(&p, &best));
        let alpha = best.h.iter().sum::<f64>() / s.h.iter().sum::<f64>();
        let shorter = alpha * (1.0 - 1e-6);
        let hs: Vec<f64> = s.h.iter().map(|x| x * shorter).collect();
        assert!(!feasible(&p, &p.evaluate(&hs, &scaled_x(&s.x, shorter))));
    }

    #[test]
    fn within_bounds_keeps_the_sum_and_leaves_a_start_within_alone() {
        let mut h = vec![96.0, 59.0, 40.0, 10.0, 0.0005];
        let total: f64 = h.iter().sum();
        assert!(within_bounds(&mut h, 1e-3, 60.0));
        assert!((h.iter().sum::<f64>() - total).abs() < 1e-9 * total);
        assert!(h.iter().all(|x| (1e-3..=60.0).contains(x)), "{h:?}");
        let mut inside = vec![0.5, 0.25, 1.25];
        assert!(!within_bounds(&mut inside, 1e-3, 60.0));
        assert_eq!(inside, vec![0.5, 0.25, 1.25]);
    }
}
