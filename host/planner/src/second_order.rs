//! Fletcher's second-order correction of a minimum-time descent step.
//!
//! A step's program is linear in the change of h, so at the step's point
//! its rows are off by their linearisation error, which grows as the square
//! of the step: the jerk comes out above its limit and time-scaling takes
//! back much of what a wide step promised (docs/planner-speed.md). Solved
//! again with each row's error at that point taken off its right-hand
//! side, the program holds to second order there, and its point needs
//! little scaling.

use crate::lp::LpFailure;
use crate::problem::{Cut, Problem, Solution};
use crate::step::StepPoint;

impl Problem {
    /// `step`'s program (at `cur`, region `delta`, holding the first of
    /// `cuts`, those its rounds were given and found) solved again with each
    /// of its rows' linearisation error at the step's point (the rows
    /// rebuilt exactly at the step's intervals, with the same cuts) off its
    /// right-hand side; the new point with its exact figures. None when
    /// the rows at the step's point do not match the program's (nothing
    /// was solved).
    pub(crate) fn second_order_corrected(
        &self,
        cur: &Solution,
        delta: f64,
        step: &StepPoint,
        cuts: &[Cut],
    ) -> Option<Result<Solution, LpFailure>> {
        let nseg = self.nseg();
        let dh0 = 3 * self.nv();
        // The rows at the step's intervals and the LP's own knot
        // derivatives (not yet on C3 there), where h no longer moves.
        let x = self.unpack(&step.sol);
        let mut program = self.program_at(&step.h, &x, Some(delta), cur.jerk);
        program.add_cuts(self, &cuts[..step.cuts]);
        if program.marks() != step.marks {
            // A cut's torque has no gradient at the step's point.
            return None;
        }
        let exact = program.finish(self);
        let mut at_step = step.sol.clone();
        at_step[dh0..dh0 + nseg].fill(0.0);
        let actual = exact.residuals(&at_step, step.marks);
        let model = step.lp.residuals(&step.sol, step.marks);
        let error: Vec<f64> = actual.iter().zip(&model).map(|(a, m)| a - m).collect();
        let mut lp = step.lp.clone();
        lp.shift_rhs(step.marks, &error);
        Some(self.solve(&lp).map(|sol| {
            let (h, x) = self.step_point(&cur.h, &sol);
            let fig = self.evaluation(&h, &x, self.torque_samples);
            Solution::with_figures(h, x, &fig)
        }))
    }
}

#[cfg(test)]
mod tests {
    use crate::inner::{Method, ROUNDS};
    use crate::problem::Solution;
    use crate::search_tests::{example_problem, uneven_intervals};
    use crate::time_scaling::shortest_scaling;

    /// On wide descent steps from a Case II point where velocity and jerk
    /// bind, time-scaling takes back a good part of what the plain step
    /// promised; the corrected step keeps at least half of that part.
    #[test]
    fn a_corrected_wide_step_loses_less_to_time_scaling() {
        let mut p = example_problem("paper-case2.toml");
        let h = uneven_intervals(&p);
        let s = p
            .inner(&h, &p.zero_x(), Method::ViaRelaxation, ROUNDS)
            .unwrap();
        let cur = shortest_scaling(&p, &s).unwrap();
        let t_cur: f64 = cur.h.iter().sum();
        p.total_time = t_cur;
        for delta in [0.1, 0.2] {
            let mut cuts = p.evaluation(&cur.h, &cur.x, p.torque_samples).cuts;
            let step = p.time_step(&cur, delta, &mut cuts, 3, 0.0).unwrap();
            let promised = t_cur - step.point.h.iter().sum::<f64>();
            // The share of the promise a point keeps once time-scaled.
            let kept = |point: &Solution| {
                let scaled = shortest_scaling(&p, point).unwrap();
                (t_cur - scaled.h.iter().sum::<f64>()) / promised
            };
            let plain = kept(&step.point);
            let corrected = kept(
                &p.second_order_corrected(&cur, delta, &step.program, &cuts)
                    .unwrap()
                    .unwrap(),
            );
            eprintln!(
                "Δ {delta}: of the promise, plain keeps {plain:.3}, corrected {corrected:.3}"
            );
            assert!(plain < 0.8, "Δ {delta}: {plain}");
            assert!(
                corrected > plain + 0.5 * (1.0 - plain),
                "Δ {delta}: {corrected} against {plain}"
            );
        }
    }
}
