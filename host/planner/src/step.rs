//! The trust-region step: a sequential linear program over (x, h). Each
//! step solves the program linearised in h at the current point (x is exact
//! there) and is judged on the exact inner optimum at the new intervals. The
//! minimum-time descent takes the same steps with another objective
//! ([`Problem::time_step`]).

use crate::inner::Method;
use crate::lp::{Lp, LpFailure, Marks};
use crate::problem::{Cut, Evaluation, Problem, Solution};
use crate::program::add_new_cuts;
use crate::run_state::held_solves;
use crate::workers::{Beside, on_spare_core};

/// Cutting-plane rounds of a trust-region step's program, and when judging
/// the step (its figures are exact whatever the count; more rounds only
/// improve x).
const STEP_ROUNDS: usize = 6;
/// Relative promise of a trust-region step below which a rejection whose
/// promise did not fall with the region counts as the model's error floor.
const FLOOR_GAIN: f64 = 1e-4;

/// A step of the minimum-time descent: new intervals, knot derivatives,
/// and the LPs it took.
pub(crate) struct TimeStep {
    /// The new point with its exact figures.
    pub(crate) point: Solution,
    pub(crate) solves: u64,
    /// The last round's program and solution, for the second-order
    /// correction ([`Problem::second_order_corrected`]).
    pub(crate) program: StepPoint,
}

/// The cutting-plane rounds of one step program ([`Problem::step_rounds`]).
struct StepRounds {
    /// The last solved round.
    last: Option<StepPoint>,
    solves: u64,
    /// The failure that ended the rounds, if one did.
    failed: Option<LpFailure>,
}

/// A trust-region trial ([`Problem::trial`]).
struct Trial {
    rounds: StepRounds,
    /// The merit its step program promises to gain (with a point).
    gain: Option<f64>,
    cand: Option<Solution>,
}

/// A promised gain below this share of the merit is the step LP's noise.
const NOISE_GAIN: f64 = 1e-9;

/// A solved step program: the program, its solution, its intervals, its
/// knot derivatives on C3 there, and their evaluation.
pub(crate) struct StepPoint {
    pub(crate) lp: Lp,
    /// The program's rows before the trust region's.
    pub(crate) marks: Marks,
    /// How many of the rounds' cuts (the first) it holds.
    pub(crate) cuts: usize,
    pub(crate) sol: Vec<f64>,
    pub(crate) h: Vec<f64>,
    pub(crate) x: [Vec<f64>; 3],
    pub(crate) fig: Evaluation,
}

impl Problem {
    /// Trust-region SLP over (x, h) from `start` (an inner solution), with
    /// Σh ≤ total_time: each step solves the problem linearised in h at the
    /// current point (x is exact there) and is judged on the exact inner
    /// optimum at the new intervals. Stops when a step gains less than
    /// `rel_tol` of the merit (three times running), when the model's
    /// promise falls to the LP's accuracy, or when the region collapses.
    pub(crate) fn local_search(&self, start: &Solution, max_iter: usize, rel_tol: f64) -> Solution {
        self.local_search_until(start, max_iter, rel_tol, &|_| false)
    }

    /// [`Problem::local_search`] that also stops at the first point where `done` holds.
    pub(crate) fn local_search_until(
        &self,
        start: &Solution,
        max_iter: usize,
        rel_tol: f64,
        done: &dyn Fn(&Solution) -> bool,
    ) -> Solution {
        let nv = self.nv();
        let nseg = self.nseg();
        let mut cur = start.clone();
        let mut delta = 0.25;
        let mut solves = 0;
        let mut stalled = 0;
        let mut rejected_small = 0;
        // Rejections since the last accepted step whose promise did not
        // fall with the region (see below), and the last rejected promise.
        let mut at_floor = 0;
        let mut last_rejected_gain = f64::INFINITY;
        // A trial at the current point with the region a rejection leaves,
        // started beside the last one on a spare core: the same trial the
        // loop would solve next, so the search is the same either way (it
        // is abandoned when the last one is accepted).
        let mut ahead: Option<(f64, Beside<(Trial, u64)>)> = None;
        for _ in 0..max_iter {
            if done(&cur) {
                break;
            }
            let trial = match ahead.take() {
                Some((d, beside)) if d == delta => match beside.wait() {
                    Some((t, held)) => {
                        self.run.count_solves(held);
                        t
                    }
                    None => self.trial(&cur, delta),
                },
                _ => {
                    let smaller = delta * 0.25;
                    let (p, at) = (self.clone(), cur.clone());
                    ahead = on_spare_core(move || held_solves(|| p.trial(&at, smaller)))
                        .map(|beside| (smaller, beside));
                    self.trial(&cur, delta)
                }
            };
            solves += trial.rounds.solves;
            let (Some(StepPoint { sol, .. }), Some(gain)) = (trial.rounds.last, trial.gain) else {
                delta *= 0.25;
                if delta < 1e-7 {
                    break;
                }
                continue;
            };
            let merit = cur.merit(self.weight);
            // Below the step LP's accuracy a predicted gain is noise.
            if gain <= NOISE_GAIN * merit {
                break;
            }
            let Some(cand) = trial.cand else {
                delta *= 0.25;
                if delta < 1e-7 {
                    break;
                }
                continue;
            };
            solves += cand.lp_solves;
            let actual = merit - cand.merit(self.weight);
            let rho = actual / gain;
            let at_edge = (0..nseg).any(|k| sol[3 * nv + k].abs() >= 0.99 * delta * cur.h[k]);
            if rho > 0.1 {
                stalled = if actual < rel_tol * merit {
                    stalled + 1
                } else {
                    0
                };
                cur = cand;
                ahead = None;
                at_floor = 0;
                last_rejected_gain = f64::INFINITY;
                if rho > 0.5 && at_edge {
                    delta = (delta * 2.0).min(0.5);
                } else if rho < 0.25 {
                    delta *= 0.5;
                }
            } else {
                delta *= 0.25;
                // Rejected although the model promised little: at the noise floor.
                rejected_small += usize::from(gain < 1e-6 * merit);
                // A linear model's promise falls with the region (about
                // fourfold here); a small one that does not is the model's
                // own error at this point (x moves freely while h is
                // linearised, and the solves' accuracy), not a gain a
                // smaller step would deliver: two of them end the search
                // rather than shrinking the region to its floor.
                at_floor +=
                    usize::from(gain < FLOOR_GAIN * merit && gain > 0.5 * last_rejected_gain);
                last_rejected_gain = gain;
            }
            if stalled >= 3 || rejected_small >= 2 || at_floor >= 2 || delta < 1e-7 {
                break;
            }
        }
        cur.lp_solves = start.lp_solves + solves;
        cur
    }

    /// One trust-region trial from `cur` with region `delta`: the step
    /// program's rounds and, unless the predicted gain is noise, the exact
    /// inner optimum at its point (the step is judged on it, not on the
    /// LP's x projected back onto C3: that evaluation understates the gain
    /// and keeps steps tiny). Depends on `cur` and `delta` alone.
    fn trial(&self, cur: &Solution, delta: f64) -> Trial {
        // Where a limit other than jerk binds, a step with only the cuts
        // at the current point's extrema promises what holds only there:
        // steps are rejected, the region collapses and the search crawls
        // (docs/planner-speed.md), so the step program has its own rounds.
        let mut cuts = self.evaluation(&cur.h, &cur.x, self.torque_samples).cuts;
        let rounds = self.step_rounds(cur, delta, &mut cuts, STEP_ROUNDS, |_| {}, |_| false);
        let nd = 3 * self.nv() + self.nseg();
        let merit = cur.merit(self.weight);
        let gain = rounds
            .last
            .as_ref()
            .map(|last| merit - (last.sol[nd] + self.weight * last.sol[nd + 1]));
        let cand = rounds
            .last
            .as_ref()
            .filter(|_| gain.is_some_and(|g| g > NOISE_GAIN * merit))
            .and_then(|last| self.inner(&last.h, &last.x, Method::ViaRelaxation, STEP_ROUNDS));
        Trial { rounds, gain, cand }
    }

    /// The step program at `cur` (h moving by at most Δ·h_k), shaped by
    /// `shape`, in cutting-plane rounds as in the inner loop from the cuts
    /// `cuts`: each round's point is checked exactly and its new extrema
    /// cut (appended to `cuts`), so the step does not promise what is only
    /// true at the old extrema. With jerk alone there are no cuts: one
    /// round. Ends at the first round that adds no cut or whose new
    /// intervals are `enough`, at `max_rounds`, or at a failed solve.
    fn step_rounds(
        &self,
        cur: &Solution,
        delta: f64,
        cuts: &mut Vec<Cut>,
        max_rounds: usize,
        shape: impl Fn(&mut Lp),
        enough: impl Fn(&[f64]) -> bool,
    ) -> StepRounds {
        let mut out = StepRounds {
            last: None,
            solves: 0,
            failed: None,
        };
        // Every round's program is the one at `cur` with more cuts: the
        // rows before the cuts' are built once, and each cut's once.
        let mut program = self.program_at(&cur.h, &cur.x, Some(delta), cur.jerk);
        for _ in 0..max_rounds {
            let added = program.cuts();
            program.add_cuts(self, &cuts[added..]);
            let (marks, held) = (program.marks(), program.cuts());
            let mut lp = program.clone().finish(self);
            // A step only needs to be good, not exact: it is judged exactly
            // (so no iterative refinement of the KKT solves either).
            lp.tolerance = 1e-8;
            lp.refine = false;
            shape(&mut lp);
            out.solves += 1;
            let sol = match self.solve(&lp) {
                Ok(sol) => sol,
                Err(failure) => {
                    out.failed = Some(failure);
                    break;
                }
            };
            let (h, x) = self.step_point(&cur.h, &sol);
            let before = cuts.len();
            let fig = self.evaluation(&h, &x, self.torque_samples);
            add_new_cuts(cuts, &fig.cuts);
            let settled = cuts.len() == before || enough(&h);
            out.last = Some(StepPoint {
                lp,
                marks,
                cuts: held,
                sol,
                h,
                x,
                fig,
            });
            if settled {
                break;
            }
        }
        out
    }

    /// The point of a step program's solution `sol` from intervals `h`: the
    /// new intervals (at least h_min) and the knot derivatives projected
    /// onto C3 there.
    pub(crate) fn step_point(&self, h: &[f64], sol: &[f64]) -> (Vec<f64>, [Vec<f64>; 3]) {
        let dh0 = 3 * self.nv();
        let h: Vec<f64> = h
            .iter()
            .enumerate()
            .map(|(k, hk)| (hk + sol[dh0 + k]).max(self.h_min))
            .collect();
        let mut x = self.unpack(sol);
        self.project(&h, &mut x);
        (h, x)
    }

    /// One step of the minimum-time descent from
    /// `cur`: the LP linearised in h at `cur` (h moving by at most Δ·h_k),
    /// minimising Σh with the jerk capped at its limit and every limit
    /// elastic; returns the new intervals, the LP's knot derivatives
    /// projected onto C3 there. Its program starts from `cuts` and runs at
    /// most `max_rounds` rounds; the cuts they find are appended to `cuts`.
    /// A round that promises at most `floor` of the time ends them: a later
    /// round only adds rows, so (while the violation σ stays at zero) it
    /// promises no more.
    pub(crate) fn time_step(
        &self,
        cur: &Solution,
        delta: f64,
        cuts: &mut Vec<Cut>,
        max_rounds: usize,
        floor: f64,
    ) -> Result<TimeStep, LpFailure> {
        let nv = self.nv();
        let nseg = self.nseg();
        let (dh0, s_col) = (3 * nv, 3 * nv + nseg);
        let sigma = s_col + 1;
        let t: f64 = cur.h.iter().sum();
        let jerk = self.limits.jerk;
        let rounds = self.step_rounds(
            cur,
            delta,
            cuts,
            max_rounds,
            |lp| {
                // Relative time against relative violation: making up a
                // violation ν by time-scaling costs about ν/2 of the time, so
                // 1e3 keeps σ at 0 whenever the linearisation allows it.
                lp.cost[s_col] = 0.0;
                lp.cost[sigma] = 1e3;
                for k in 0..nseg {
                    lp.cost[dh0 + k] = 1.0 / t;
                }
                lp.at_most(&[(s_col, 1.0), (sigma, -jerk)], jerk);
            },
            |h| t - h.iter().sum::<f64>() <= floor * t,
        );
        if let Some(failure) = rounds.failed {
            return Err(failure);
        }
        let last = rounds.last.ok_or(LpFailure::Cancelled)?;
        Ok(TimeStep {
            point: Solution::with_figures(last.h.clone(), last.x.clone(), &last.fig),
            solves: rounds.solves,
            program: last,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    use crate::inner::ROUNDS;
    use crate::run_state::RunState;
    use crate::search_tests::{example_problem, uneven_intervals};
    use crate::workers::parallel;

    #[test]
    fn the_search_never_worsens_and_keeps_the_budget() {
        for p in [
            example_problem("paper-case1.toml").relaxed(),
            example_problem("paper-case2.toml"),
        ] {
            let h = uneven_intervals(&p);
            let start = p.inner(&h, &p.zero_x(), Method::Direct, ROUNDS).unwrap();
            let end = p.local_search(&start, 30, 1e-6);
            let total: f64 = end.h.iter().sum();
            assert!(end.merit(p.weight) < start.merit(p.weight) * (1.0 - 1e-3));
            assert!(total <= p.total_time * (1.0 + 1e-9), "{total}");
            assert!(end.h.iter().all(|&x| x >= p.h_min && x <= p.h_max));
            assert!(end.lp_solves > start.lp_solves);
            // Its figures are the exact ones at its point.
            let again = p.evaluate(&end.h, &end.x);
            assert_eq!((again.jerk, again.violation), (end.jerk, end.violation));
        }
    }

    #[test]
    fn a_trial_solved_ahead_changes_neither_the_search_nor_its_count() {
        let p = example_problem("paper-case1.toml").relaxed();
        let h = uneven_intervals(&p);
        let start = p.inner(&h, &p.zero_x(), Method::Direct, ROUNDS).unwrap();
        // Alone on two threads the search has a spare core; on one it has none.
        let search = |threads: usize| {
            let q = Problem {
                run: Arc::new(RunState::new(None)),
                ..p.clone()
            };
            let end = parallel(&[()], threads, |_| q.local_search(&start, 30, 1e-6));
            (end[0].clone(), q.run.progress().lp_solves)
        };
        let (alone, counted_alone) = search(1);
        let (beside, counted_beside) = search(2);
        assert_eq!(
            (&alone.h, &alone.x, alone.lp_solves),
            (&beside.h, &beside.x, beside.lp_solves)
        );
        // The run counts the solves the search used, not those thrown away.
        assert_eq!(counted_alone, alone.lp_solves - start.lp_solves);
        assert_eq!(counted_beside, counted_alone);
    }

    #[test]
    fn a_time_step_shortens_within_the_region() {
        let p = example_problem("paper-case2.toml");
        let h = uneven_intervals(&p);
        let cur = p
            .inner(&h, &p.zero_x(), Method::ViaRelaxation, ROUNDS)
            .unwrap();
        let delta = 0.05;
        let mut cuts = p.evaluation(&cur.h, &cur.x, p.torque_samples).cuts;
        let step = p
            .time_step(&cur, delta, &mut cuts, STEP_ROUNDS, 0.0)
            .unwrap();
        let before: f64 = cur.h.iter().sum();
        let after: f64 = step.point.h.iter().sum();
        assert!(after < before, "{after} ≥ {before}");
        for (a, b) in step.point.h.iter().zip(&cur.h) {
            assert!((a - b).abs() <= delta * b * (1.0 + 1e-6) + 1e-12);
        }
        // Its rounds ran on; asked for a little more than its first round
        // promises, that round ends them.
        assert!(step.solves > 1);
        let own = p.evaluation(&cur.h, &cur.x, p.torque_samples).cuts;
        let first = p.time_step(&cur, delta, &mut own.clone(), 1, 0.0).unwrap();
        let floor = (before - first.point.h.iter().sum::<f64>()) / before * 1.01;
        let short = p
            .time_step(&cur, delta, &mut own.clone(), STEP_ROUNDS, floor)
            .unwrap();
        assert_eq!(short.solves, 1);
        assert_eq!(short.point.h, first.point.h);
    }
}
