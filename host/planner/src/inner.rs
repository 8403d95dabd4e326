//! The inner problem: the exact min-max-jerk knot derivatives at fixed
//! intervals, by one of the [`Method`]s.
//!
//! Cutting planes: the program ([`crate::program`]) is solved, its point
//! evaluated exactly, and cuts are added at the new extrema until the
//! program's bound equals the exact continuous-time maximum. Torque cuts are
//! re-linearised at each new point until they hold.

use crate::problem::{Cut, Limited, Problem, Solution, meets_every_limit};
use crate::program::add_new_cuts;

/// Relative tolerance of the cutting-plane loop.
const TOL: f64 = 1e-9;
/// Cutting-plane rounds of a full inner solve.
pub(crate) const ROUNDS: usize = 25;
/// Accuracy of the inner solves. Tighter asks for more than the interior
/// point method delivers on these degenerate problems (most solves then end
/// "almost solved", less accurate than this).
const INNER_TOL: f64 = 1e-9;
/// Relative margin over the jerk limit past which a program's optimum
/// proves a point infeasible, well above the solves' accuracy.
const CERTAIN: f64 = 1e-7;

/// How an inner solve is done. Each gives the exact optimum when it
/// succeeds; they differ in cost, and in which optimal knot derivatives
/// they pick where the optimum is not unique.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Method {
    /// Cutting planes by interior-point solves only.
    CuttingPlanes,
    /// On the jerk-only relaxation, each joint's exact optimum without an
    /// interior-point solve ([`crate::jerk_only`]) when it certifies;
    /// otherwise (and on the full problem) cutting planes.
    Direct,
    /// Through the relaxation: its interior-point optimum when that meets
    /// every limit (then it is exact and the cutting planes are skipped),
    /// else cutting planes from its knot derivatives.
    ViaRelaxation,
    /// For a final plan: the relaxation's direct solve when it meets every
    /// limit, else [`Method::ViaRelaxation`]. Only at the end: the search
    /// and the descent start better from the interior-point solve's central
    /// knot derivatives.
    Final,
    /// For a min-time plan at its rounded intervals: the relaxation's
    /// direct solve when it meets every limit, else cutting planes from
    /// `x0` (the min-time point's knot derivatives, whose extrema are where
    /// the rounds end; through the relaxation when a solve there fails),
    /// ending at the first point that meets every limit.
    /// Its objective, the total time, is fixed by the intervals here, so
    /// a jerk lowered further below its limit buys nothing.
    FirstFeasible,
}

/// What the cutting-plane rounds run to.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Goal {
    /// The exact optimum (or the last round).
    Optimum,
    /// The first point that meets every limit (or the optimum).
    Feasible,
}

impl Problem {
    /// The inner optimum at intervals `h` by `method`, with at most
    /// `rounds` cutting-plane rounds. `x0` is where torque is first
    /// linearised (zeros will do). None when a solve fails or is cancelled.
    pub(crate) fn inner(
        &self,
        h: &[f64],
        x0: &[Vec<f64>; 3],
        method: Method,
        rounds: usize,
    ) -> Option<Solution> {
        match method {
            Method::CuttingPlanes => self.cutting_planes(h, x0, rounds, Goal::Optimum),
            Method::Direct => self.direct(h, x0, rounds, Goal::Optimum),
            Method::ViaRelaxation => self.via_relaxation(h, x0, rounds, Goal::Optimum),
            Method::Final => self.final_solve(h, x0, rounds, Goal::Optimum),
            Method::FirstFeasible => self.final_solve(h, x0, rounds, Goal::Feasible),
        }
    }

    /// [`Method::Direct`].
    fn direct(&self, h: &[f64], x0: &[Vec<f64>; 3], rounds: usize, goal: Goal) -> Option<Solution> {
        if self.jerk_only
            && self.run.cancelled().is_none()
            && let Some(x) = self.jerk_only_direct(h, x0)
        {
            let fig = self.evaluation(h, &x, self.torque_samples);
            // The direct solve knows jerk alone: when its optimum leaves
            // the travel, the cutting planes start from it.
            if fig.violation > 0.0 {
                return self.cutting_planes(h, &x, rounds, goal);
            }
            return Some(Solution::with_figures(h.to_vec(), x, &fig));
        }
        self.cutting_planes(h, x0, rounds, goal)
    }

    /// [`Method::CuttingPlanes`].
    fn cutting_planes(
        &self,
        h: &[f64],
        x0: &[Vec<f64>; 3],
        max_rounds: usize,
        goal: Goal,
    ) -> Option<Solution> {
        let mut x = x0.clone();
        let first = self.evaluation(h, &x, self.torque_samples);
        let mut jerk = first.jerk;
        let mut cuts = first.cuts;
        let mut solves = 0;
        for _ in 0..max_rounds {
            let mut lp = self.build(h, &x, &cuts, None, jerk);
            lp.tolerance = INNER_TOL;
            let sol = self.solve(&lp).ok()?;
            solves += 1;
            let s_lp = sol[3 * self.nv()];
            let sigma_lp = sol[3 * self.nv() + 1];
            let prev = x.clone();
            x = self.unpack(&sol);
            self.project(h, &mut x);
            let fig = self.evaluation(h, &x, self.torque_samples);
            jerk = fig.jerk;
            let moved = x
                .iter()
                .zip(&prev)
                .flat_map(|(a, b)| a.iter().zip(b))
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            let scale = x.iter().flatten().map(|v| v.abs()).fold(1e-3, f64::max);
            let exact = fig.jerk <= s_lp * (1.0 + TOL) + 1e-12
                && fig.violation <= sigma_lp + TOL
                && (fig.binding != Limited::Torque || moved <= 1e-9 * scale);
            let before = cuts.len();
            add_new_cuts(&mut cuts, &fig.cuts);
            // Without a new cut the next LP is the same one, unless torque
            // cuts are re-linearised at the new point: stop, the figures are exact.
            let relinearise = moved > 1e-9 * scale && cuts.iter().any(|c| c.q == Limited::Torque);
            let stuck = cuts.len() == before && !relinearise;
            let point = Solution {
                lp_solves: solves,
                ..Solution::with_figures(h.to_vec(), x, &fig)
            };
            let enough = goal == Goal::Feasible
                && (meets_every_limit(self, &point)
                    || self.beyond_every_limit(s_lp, sigma_lp, &cuts));
            if exact || stuck || enough || solves == max_rounds as u64 {
                return Some(point);
            }
            x = point.x;
        }
        None
    }

    /// Whether a program's optimum (jerk bound `s_lp`, violation
    /// `sigma_lp`) proves that no point at its intervals meets every limit:
    /// without torque cuts (linearised, so not a relaxation) the program
    /// only relaxes the problem, and a point meeting every limit would cost
    /// it at most the jerk limit.
    fn beyond_every_limit(&self, s_lp: f64, sigma_lp: f64, cuts: &[Cut]) -> bool {
        !cuts.iter().any(|c| c.q == Limited::Torque)
            && s_lp + self.weight * sigma_lp > self.limits.jerk * (1.0 + CERTAIN)
    }

    /// [`Method::ViaRelaxation`].
    fn via_relaxation(
        &self,
        h: &[f64],
        x0: &[Vec<f64>; 3],
        max_rounds: usize,
        goal: Goal,
    ) -> Option<Solution> {
        // The relaxation's probe keeps the interior-point solve: its knot
        // derivatives (the analytic centre of the non-binding joints') start
        // the full problem's cutting planes, and start them better than the
        // direct solve's, each joint at its own optimum (docs/planner-speed.md).
        if !self.jerk_only
            && let Some(r) = self.relaxed().cutting_planes(h, x0, ROUNDS, Goal::Optimum)
        {
            if let Some(sol) = self.accept_relaxed(&r) {
                return Some(sol);
            }
            return self.direct(h, &r.x, max_rounds, goal).map(|s| Solution {
                lp_solves: s.lp_solves + r.lp_solves,
                ..s
            });
        }
        self.direct(h, x0, max_rounds, goal)
    }

    /// [`Method::Final`] and [`Method::FirstFeasible`].
    fn final_solve(
        &self,
        h: &[f64],
        x0: &[Vec<f64>; 3],
        max_rounds: usize,
        goal: Goal,
    ) -> Option<Solution> {
        if !self.jerk_only
            && self.run.cancelled().is_none()
            && let Some(x) = self.relaxed().jerk_only_direct(h, x0)
        {
            let full = self.evaluate(h, &x);
            if full.violation == 0.0 {
                return Some(full);
            }
        }
        // A min-time point a few microseconds away has its extrema where
        // the rounds end: its own cuts start them better than the
        // relaxation's point does (which is left for a failed solve).
        if goal == Goal::Feasible
            && let Some(s) = self.cutting_planes(h, x0, max_rounds, goal)
        {
            return Some(s);
        }
        self.via_relaxation(h, x0, max_rounds, goal)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search_tests::{example_problem, uneven_intervals};

    /// Every method reaches the same exact optimum, where only jerk binds
    /// and where velocity binds (then the relaxation's answer is refused).
    #[test]
    fn every_method_reaches_the_same_optimum() {
        for binds in [false, true] {
            let mut p = example_problem("paper-case1.toml");
            let h = uneven_intervals(&p);
            let relaxed = p.relaxed();
            let free = relaxed
                .inner(&h, &p.zero_x(), Method::Direct, ROUNDS)
                .unwrap();
            if binds {
                // 0.9 of the relaxation's optimum's peak velocity.
                let mut probe = p.clone();
                probe.limits.velocity = 1e-9;
                let peak = 1e-9 * (1.0 + probe.evaluate(&h, &free.x).violation);
                p.limits.velocity = 0.9 * peak;
            }
            assert_eq!(p.accept_relaxed(&free).is_none(), binds);
            let merit = |s: &Solution| s.merit(p.weight);
            let solve = |m| p.inner(&h, &p.zero_x(), m, ROUNDS).unwrap();
            let planes = solve(Method::CuttingPlanes);
            for m in [Method::Direct, Method::ViaRelaxation, Method::Final] {
                let s = solve(m);
                assert!(
                    (merit(&s) - merit(&planes)).abs() <= 1e-7 * merit(&planes),
                    "{m:?}: {} against {}",
                    merit(&s),
                    merit(&planes)
                );
                assert!(
                    s.jerk >= free.jerk * (1.0 - 1e-9),
                    "{m:?} below the relaxation"
                );
            }
        }
    }

    /// Case I's problem and its min-time point (before the rounding).
    fn case1_min_time() -> (Problem, Solution) {
        let p = example_problem("paper-case1.toml");
        let (s, _) = crate::min_time::min_time(&p, &crate::options::Options::default(), None)
            .ok()
            .unwrap();
        (p, s)
    }

    /// At Case I's min-time point lengthened by a few microseconds and
    /// rounded to whole ones, as the rounding does, acceleration and jerk
    /// both bind and the final solve's rounds chase the moving extrema;
    /// the first point that meets every limit ends them sooner, and is no
    /// better than the optimum they run to (within the gap the chase leaves).
    #[test]
    fn the_first_feasible_point_ends_the_rounds_sooner() {
        let (p, s) = case1_min_time();
        let mut f = p.clone();
        f.torque_samples = crate::rounding::FINAL_TORQUE_SAMPLES;
        for k in 1..=40 {
            let alpha = 1.0 + k as f64 * 1e-6;
            let h: Vec<f64> =
                s.h.iter()
                    .map(|x| (x * alpha * 1e6).round() * 1e-6)
                    .collect();
            let x0 = crate::time_scaling::scaled_x(&s.x, alpha);
            let optimum = f.inner(&h, &x0, Method::Final, ROUNDS).unwrap();
            if !meets_every_limit(&f, &optimum) || optimum.lp_solves <= 2 {
                continue;
            }
            let first = f.inner(&h, &x0, Method::FirstFeasible, ROUNDS).unwrap();
            assert!(meets_every_limit(&f, &first));
            assert!(
                first.lp_solves < optimum.lp_solves,
                "{} against {}",
                first.lp_solves,
                optimum.lp_solves
            );
            // The optimum's rounds end at their last point, which wanders
            // within the gap the chase leaves (a few 1e-7 of the jerk).
            assert!(
                first.jerk >= optimum.jerk * (1.0 - 1e-6),
                "{} against {}",
                first.jerk,
                optimum.jerk
            );
            return;
        }
        panic!("no lengthening where the rounds run on");
    }

    /// Shorter than Case I's min-time point by a little, no point meets
    /// every limit: the first round's program proves it, so the rounds
    /// that look for a feasible point end there, where the optimum's run on.
    #[test]
    fn a_program_that_proves_the_intervals_infeasible_ends_the_rounds() {
        let (p, s) = case1_min_time();
        let h: Vec<f64> = s.h.iter().map(|x| x * (1.0 - 1e-3)).collect();
        let x0 = crate::time_scaling::scaled_x(&s.x, 1.0 - 1e-3);
        let optimum = p.inner(&h, &x0, Method::Final, ROUNDS).unwrap();
        let first = p.inner(&h, &x0, Method::FirstFeasible, ROUNDS).unwrap();
        assert!(!meets_every_limit(&p, &optimum));
        assert!(!meets_every_limit(&p, &first));
        assert!(
            first.lp_solves < optimum.lp_solves,
            "{} against {}",
            first.lp_solves,
            optimum.lp_solves
        );
    }

    #[test]
    fn a_cancelled_run_solves_nothing() {
        let p = example_problem("paper-case1.toml");
        p.run.cancel();
        let h = uneven_intervals(&p);
        assert!(
            p.inner(&h, &p.zero_x(), Method::CuttingPlanes, ROUNDS)
                .is_none()
        );
        assert!(p.inner(&h, &p.zero_x(), Method::Final, ROUNDS).is_none());
    }
}
