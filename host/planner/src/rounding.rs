//! Rounding to whole microseconds (what the drives run): intervals rounded
//! within the time budget, re-solved exactly at the rounded intervals, and
//! repaired until every limit holds.

use crate::inner::{Method, ROUNDS};
use crate::problem::{Problem, Solution, meets_every_limit};
use crate::time_scaling::{scaled_x, within_bounds};

/// Torque samples per segment in the final solve (the search uses fewer).
pub(crate) const FINAL_TORQUE_SAMPLES: usize = 400;
/// Rounding repairs before giving up (each lengthens the plan a little more).
const REPAIRS: usize = 24;
/// Bisection steps back towards the shortest repaired time.
const BISECTIONS: usize = 8;
/// How far inside the limits other than jerk a rounded min-max-jerk plan is
/// re-solved when it misses one by the solves' accuracy (1e-9 relative).
const ROUNDING_MARGIN: f64 = 1e-8;

/// Rounds intervals to whole microseconds without exceeding the total time.
pub(crate) fn round_to_microseconds(h: &[f64], total_time: f64) -> Vec<f64> {
    let mut us: Vec<i64> = h
        .iter()
        .map(|x| (x * 1e6).round().max(1.0) as i64)
        .collect();
    let budget = (total_time * 1e6 + 1e-3).floor() as i64;
    while us.iter().sum::<i64>() > budget {
        if let Some((i, _)) = us.iter().enumerate().max_by_key(|(_, v)| **v) {
            us[i] -= 1;
        }
    }
    // Per-interval rounding must not lose time the optimum spends: the total
    // is the rounded sum, topped up where rounding took the most.
    let target = ((h.iter().sum::<f64>() * 1e6).round() as i64).min(budget);
    while us.iter().sum::<i64>() < target {
        let residue = |i: usize| h[i] * 1e6 - us[i] as f64;
        if let Some(i) = (0..us.len()).max_by(|&a, &b| residue(a).total_cmp(&residue(b))) {
            us[i] += 1;
        }
    }
    us.into_iter().map(|v| v as f64 * 1e-6).collect()
}

/// `p` with the final solve's torque samples, at total time `total`.
pub(crate) fn fine(p: &Problem, total: f64) -> Problem {
    let mut f = p.clone();
    f.torque_samples = FINAL_TORQUE_SAMPLES;
    f.total_time = total;
    f
}

/// Min-max-jerk: the solution's intervals stretched to the whole budget (more
/// time never raises the jerk; none past the longest interval) and rounded
/// to whole µs within it, re-solved exactly; None when that breaks a limit.
pub(crate) fn round_within(p: &Problem, s: &Solution, total_time: f64) -> Option<Solution> {
    let total: f64 = s.h.iter().sum();
    let stretch = total_time / total;
    let mut h: Vec<f64> = s.h.iter().map(|x| x * stretch).collect();
    // Not past the longest interval (the rest take the time instead).
    within_bounds(&mut h, p.h_min, p.h_max);
    let h = round_to_microseconds(&h, total_time);
    let f = fine(p, h.iter().sum());
    let x0 = scaled_x(&s.x, stretch);
    let Some(exact) = f.inner(&h, &x0, Method::ViaRelaxation, ROUNDS) else {
        // At the tiny jerks of a very slow plan the re-solve can end short
        // (InsufficientProgress); the rounded intervals moved each by at
        // most half a microsecond, so the solution's own knot derivatives,
        // brought onto C3 there, are all but optimal.
        let mut x = x0;
        f.project(&h, &mut x);
        let near = f.evaluate(&h, &x);
        return meets_every_limit(&f, &near).then_some(near);
    };
    if meets_every_limit(&f, &exact) {
        return Some(exact);
    }
    // A limit other than jerk that binds at the optimum is met only to the
    // solves' accuracy, and a plan over it by that much would fall back to
    // the shortest one (tests/regression/lissajous-24-fast.toml): re-solved
    // with those limits a hair inside.
    let inside = with_margin(&f, ROUNDING_MARGIN);
    let exact = inside.inner(&h, &exact.x, Method::ViaRelaxation, ROUNDS)?;
    let exact = f.evaluate(&exact.h, &exact.x);
    meets_every_limit(&f, &exact).then_some(exact)
}

/// `p` with its velocity, acceleration and torque limits `margin` (relative) lower.
fn with_margin(p: &Problem, margin: f64) -> Problem {
    let mut inside = p.clone();
    let l = &mut inside.limits;
    for v in [&mut l.velocity, &mut l.acceleration, &mut l.torque] {
        *v *= 1.0 - margin;
    }
    inside
}

/// Min-time: the solution's intervals lengthened by a factor α and rounded
/// to whole µs, re-solved exactly. Rounding moves each interval by up to
/// ½ µs, and on long chains of short segments the optimum is sensitive to
/// that (a few per cent of jerk for 1e-5 relative); so α grows until every
/// limit holds, then is bisected back towards the smallest that holds.
pub(crate) fn lengthen_until_feasible(p: &Problem, s: &Solution) -> Option<Solution> {
    let at = |alpha: f64| -> Option<Solution> {
        let h: Vec<f64> =
            s.h.iter()
                .map(|x| ((x * alpha * 1e6).round() * 1e-6).max(1e-6))
                .collect();
        let f = fine(p, h.iter().sum());
        // Limits other than jerk that bind are met only to the solves'
        // accuracy: re-solved a hair inside them (as in `round_within`).
        let inside = with_margin(&f, ROUNDING_MARGIN);
        inside
            .inner(&h, &scaled_x(&s.x, alpha), Method::FirstFeasible, ROUNDS)
            .map(|r| Solution {
                lp_solves: r.lp_solves,
                ..f.evaluate(&r.h, &r.x)
            })
    };
    let ok = |x: &Solution| meets_every_limit(p, x);
    let mut lo = 1.0;
    let mut alpha = 1.0 + 2e-6;
    let mut excess: f64 = 0.0;
    let mut found = None;
    for _ in 0..REPAIRS {
        let exact = at(alpha)?;
        if ok(&exact) {
            found = Some((alpha, exact));
            break;
        }
        lo = alpha;
        // Time scaling by r lowers jerk by r³ and v, a by r, r²; torque
        // less. A re-solve that proved its intervals infeasible early
        // stops at a point whose violation says little; its jerk does.
        let need = if exact.jerk > p.limits.jerk || exact.violation == 0.0 {
            (exact.jerk / p.limits.jerk).cbrt()
        } else {
            (1.0 + exact.violation).sqrt()
        };
        excess = (need - 1.0).max(2.0 * excess).max(1e-6);
        alpha *= 1.0 + excess;
    }
    let (mut hi, mut best) = found?;
    for _ in 0..BISECTIONS {
        if hi - lo <= 2e-6 * hi {
            break;
        }
        let mid = 0.5 * (lo + hi);
        match at(mid) {
            Some(x) if ok(&x) => {
                hi = mid;
                best = x;
            }
            _ => lo = mid,
        }
    }
    Some(best)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search_tests::{example_problem, uneven_intervals};

    fn whole_microseconds(h: &[f64]) -> bool {
        h.iter().all(|x| (x * 1e6 - (x * 1e6).round()).abs() < 1e-6)
    }

    #[test]
    fn a_rounded_min_time_plan_meets_every_limit_in_whole_microseconds() {
        let mut p = example_problem("paper-case2.toml");
        p.limits.jerk = 1.0;
        let h = uneven_intervals(&p);
        let s = p
            .inner(&h, &p.zero_x(), Method::ViaRelaxation, ROUNDS)
            .unwrap();
        // Jerk exactly at its limit: rounding alone would break it.
        let s = crate::time_scaling::shortest_scaling(&p, &s).unwrap();
        let r = lengthen_until_feasible(&p, &s).unwrap();
        assert!(whole_microseconds(&r.h));
        assert!(meets_every_limit(&p, &r));
        let (t0, t1) = (s.h.iter().sum::<f64>(), r.h.iter().sum::<f64>());
        assert!(
            t1 >= t0 - 1e-6 * s.h.len() as f64 && t1 <= t0 * 1.001,
            "{t0} → {t1}"
        );
    }

    #[test]
    fn a_rounded_min_max_jerk_plan_fills_the_budget() {
        let mut p = example_problem("paper-case1.toml");
        // Every limit far away: the test is about the budget.
        p.limits.velocity *= 1e3;
        p.limits.acceleration *= 1e3;
        p.limits.jerk *= 1e3;
        p.limits.torque *= 1e3;
        let h: Vec<f64> = uneven_intervals(&p).iter().map(|x| x * 0.9).collect();
        let s = p
            .inner(&h, &p.zero_x(), Method::ViaRelaxation, ROUNDS)
            .unwrap();
        let r = round_within(&p, &s, p.total_time).unwrap();
        assert!(whole_microseconds(&r.h));
        assert!((r.h.iter().sum::<f64>() - p.total_time).abs() < 1e-9);
        // More time never raises the jerk.
        assert!(r.jerk < s.jerk);
    }

    #[test]
    fn rounding_keeps_the_whole_budget_and_never_exceeds_it() {
        // 96 intervals that sum to 30 s but each round down by 0.4 µs.
        let h: Vec<f64> = (0..96)
            .map(|i| {
                if i < 95 {
                    0.3125004
                } else {
                    30.0 - 95.0 * 0.3125004
                }
            })
            .collect();
        let r = round_to_microseconds(&h, 30.0);
        let total: i64 = r.iter().map(|x| (x * 1e6).round() as i64).sum();
        assert_eq!(total, 30_000_000);
        for (a, b) in r.iter().zip(&h) {
            assert!((a - b).abs() <= 1.000_001e-6, "{a} vs {b}");
        }
        // Never above the budget, even when the optimum overshoots it slightly.
        let over: Vec<f64> = h.iter().map(|x| x * (1.0 + 1e-7)).collect();
        let r = round_to_microseconds(&over, 30.0);
        let total: i64 = r.iter().map(|x| (x * 1e6).round() as i64).sum();
        assert_eq!(total, 30_000_000);
    }
}
