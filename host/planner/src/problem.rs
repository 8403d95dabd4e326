//! The planning problem for fixed knots and its exact evaluation.
//!
//! A [`Problem`] is the knots, the limits, the robot's dynamics and the time
//! budget; a [`Solution`] is intervals h and knot derivatives x with their
//! exact figures. The evaluation is exact in continuous time: the jerk,
//! acceleration and velocity of a segment are polynomials in time, so their
//! extrema are found in closed form; torque is sampled. A slider's
//! position is a quintic too: its extrema between knots are exact, and
//! keep it inside its travel (the knots are inside: the job checked them).
//! It also reports where the extrema are, which the programs cut at.
//!
//! Limits other than jerk enter with one elastic variable σ (relative
//! violation), priced by a large weight, so every program is feasible and
//! an infeasible job is recognised by σ > 0 at the optimum.

// Index loops over joints and segments mirror the maths.
#![allow(clippy::needless_range_loop)]

use nalgebra::Vector3;
use triquint_shared::kinematics::Pose;
use triquint_shared::quintic::eval_poly;
use triquint_shared::{Limits, Model, Travel, dynamics};

use std::sync::Arc;

use crate::extrema::{argmax_abs_on_interval, derivative, eval, roots_in};
use crate::lp::{Lp, LpFailure};
use crate::run_state::RunState;
use crate::spline::Knots;

/// Which limited quantity a constraint or a violation concerns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub(crate) enum Limited {
    Velocity,
    Acceleration,
    Jerk,
    Torque,
    /// A slider's position, between its travel's ends.
    Travel,
}

/// Torque samples per segment while searching (the final solve uses more).
const TORQUE_SAMPLES: usize = 48;
/// Fraction of a limit above which a local extremum gets a constraint.
const CUT_THRESHOLD: f64 = 0.5;
/// Fraction of a slider's travel span from either end within which a
/// position extremum between knots gets a constraint.
const TRAVEL_CUT: f64 = 1e-3;
/// Fraction of the travel span the programs keep a position extremum inside
/// the travel by: the cutting planes meet a bound to 1e-9 relative, and a
/// plan must not leave the travel by that much.
pub(crate) const TRAVEL_MARGIN: f64 = 1e-7;
/// Normalised distance from a knot within which a position extremum gets no
/// constraint: the position there is the knot's, which no program moves.
const KNOT_U: f64 = 1e-6;

/// One planning problem: knots, limits, dynamics and the time budget.
#[derive(Clone, Debug)]
pub(crate) struct Problem {
    pub(crate) knots: Knots,
    pub(crate) limits: Limits,
    pub(crate) model: Model<f64>,
    pub(crate) total_time: f64,
    pub(crate) h_min: f64,
    /// Longest interval (the wire's segment limit).
    pub(crate) h_max: f64,
    /// The sliders' travel, when the problem has one. Like jerk, it is part
    /// of the relaxation: a shape's positions do not change with its time
    /// scale.
    pub(crate) travel: Option<Travel>,
    /// Cancellation and progress, shared by every copy of the problem.
    pub(crate) run: Arc<RunState>,
    /// Price of one unit of relative limit violation, in m/s³.
    pub(crate) weight: f64,
    /// Torque samples per segment where local maxima get constraints.
    pub(crate) torque_samples: usize,
    /// Jerk only: velocity, acceleration and torque are neither constrained
    /// nor evaluated (the relaxation solved first, see [`Problem::relaxed`]).
    pub(crate) jerk_only: bool,
    /// The factor that takes this problem's max jerk to the job's, for the
    /// observer's best so far: 1 for the job's own problem, (t/T)³ for its
    /// shape searched at another total time t; None for a coarser path's
    /// search, whose jerk is not the job's at any scale.
    pub(crate) shown_jerk: Option<f64>,
}

/// A candidate plan: intervals, knot derivatives, and its exact figures.
#[derive(Clone, Debug)]
pub(crate) struct Solution {
    pub(crate) h: Vec<f64>,
    pub(crate) x: [Vec<f64>; 3],
    /// Exact continuous-time max |jerk| over all joints (m/s³).
    pub(crate) jerk: f64,
    /// Largest relative violation of the velocity, acceleration, torque and
    /// travel limits (0 if none); travel's relative to its span.
    pub(crate) violation: f64,
    /// The quantity with the largest violation, or the closest to its limit.
    pub(crate) binding: Limited,
    pub(crate) lp_solves: u64,
}

impl Solution {
    /// (h, x) with its exact figures `fig`, no LP solves counted yet.
    pub(crate) fn with_figures(h: Vec<f64>, x: [Vec<f64>; 3], fig: &Evaluation) -> Solution {
        Solution {
            h,
            x,
            jerk: fig.jerk,
            violation: fig.violation,
            binding: fig.binding,
            lp_solves: 0,
        }
    }

    pub(crate) fn merit(&self, weight: f64) -> f64 {
        self.jerk + weight * self.violation
    }
}

/// (segment, normalised time) of one side of a jerk condition.
pub(crate) type KnotSide = (usize, f64);

#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Cut {
    pub(crate) q: Limited,
    /// Joint (or, for torque, motor axis).
    pub(crate) j: usize,
    pub(crate) k: usize,
    pub(crate) u: f64,
    /// The sign of the value at the extremum, whose side alone the
    /// program bounds (the other side's row starts at least 1 +
    /// [`CUT_THRESHOLD`] of the limit from binding; an extremum that
    /// reaches it is cut on its own side); 0 bounds both (travel).
    pub(crate) side: f64,
}

/// Exact figures of a point, and where the extrema are.
pub(crate) struct Evaluation {
    pub(crate) jerk: f64,
    pub(crate) violation: f64,
    pub(crate) binding: Limited,
    pub(crate) cuts: Vec<Cut>,
    /// The largest relative closeness to a limit so far (for `binding`).
    closest: f64,
}

impl Evaluation {
    fn new() -> Evaluation {
        Evaluation {
            jerk: 0.0,
            violation: 0.0,
            binding: Limited::Jerk,
            cuts: Vec::new(),
            closest: f64::NEG_INFINITY,
        }
    }

    /// Adds a segment's figures (its cuts go in separately); segments in
    /// order give the same figures whatever else was evaluated.
    fn absorb(&mut self, seg: &SegmentFigures) {
        self.jerk = self.jerk.max(seg.jerk);
        for &(q, rel) in seg.notes() {
            if rel > self.closest {
                self.closest = rel;
                self.binding = q;
            }
            self.violation = self.violation.max(rel);
        }
    }

    fn finish(mut self) -> Evaluation {
        self.violation = self.violation.max(0.0);
        self
    }
}

/// One segment's figures in an [`Evaluation`]: its largest jerk, and each
/// limit's relative excess (negative when inside) in the order found.
struct SegmentFigures {
    jerk: f64,
    /// Per joint travel, velocity and acceleration, then torque per axis.
    notes: [(Limited, f64); 12],
    len: usize,
}

impl SegmentFigures {
    fn note(&mut self, q: Limited, rel: f64) {
        self.notes[self.len] = (q, rel);
        self.len += 1;
    }

    fn notes(&self) -> &[(Limited, f64)] {
        &self.notes[..self.len]
    }
}

impl Problem {
    pub(crate) fn nv(&self) -> usize {
        self.knots.vars()
    }

    pub(crate) fn nseg(&self) -> usize {
        self.knots.segments()
    }

    /// Solves one of this problem's programs, unless the search is cancelled.
    pub(crate) fn solve(&self, lp: &Lp) -> Result<Vec<f64>, LpFailure> {
        if !self.run.proceed() {
            return Err(LpFailure::Cancelled);
        }
        lp.solve()
    }

    /// The limit of a quantity bounded in magnitude; travel is bounded by
    /// its two ends instead ([`Problem::travel_of`]) and has none.
    pub(crate) fn limit(&self, q: Limited) -> f64 {
        match q {
            Limited::Velocity => self.limits.velocity,
            Limited::Acceleration => self.limits.acceleration,
            Limited::Jerk => self.limits.jerk,
            Limited::Torque => self.limits.torque,
            Limited::Travel => f64::INFINITY,
        }
    }

    /// Joint j's travel (min, max, span), when the problem has one.
    pub(crate) fn travel_of(&self, j: usize) -> Option<(f64, f64, f64)> {
        self.travel
            .as_ref()
            .map(|t| (t.min[j], t.max[j], t.max[j] - t.min[j]))
    }

    /// Joint j's position extrema on segment k that come within
    /// [`TRAVEL_CUT`] of its travel's ends, as (t, position): none when the
    /// segment's Bernstein coefficients (whose hull holds the quintic)
    /// keep away from them.
    fn near_travel(&self, c: &[f64; 6], vel: &[f64], j: usize, hk: f64) -> Vec<(f64, f64)> {
        let Some((lo, hi, span)) = self.travel_of(j) else {
            return Vec::new();
        };
        let (lo, hi) = (lo + TRAVEL_CUT * span, hi - TRAVEL_CUT * span);
        if bernstein(c, hk).iter().all(|b| (lo..=hi).contains(b)) {
            return Vec::new();
        }
        roots_in(vel, 0.0, hk)
            .into_iter()
            .map(|t| (t, eval(c, t)))
            .filter(|&(_, p)| p > hi || p < lo)
            .collect()
    }

    /// The first segment and joint whose position leaves the travel, with
    /// its farthest position and the end it passes: (k, j, position, end).
    pub(crate) fn travel_breach(
        &self,
        h: &[f64],
        x: &[Vec<f64>; 3],
    ) -> Option<(usize, usize, f64, f64)> {
        (0..self.nseg()).find_map(|k| {
            (0..3).find_map(|j| {
                let (lo, hi, _) = self.travel_of(j)?;
                let c = self.knots.coefficients(&x[j], j, k, h[k]);
                let far = self
                    .near_travel(&c, &derivative(&c), j, h[k])
                    .into_iter()
                    .map(|(_, p)| p)
                    .max_by(|a, b| (a - hi).max(lo - a).total_cmp(&(b - hi).max(lo - b)))?;
                if far > hi {
                    Some((k, j, far, hi))
                } else if far < lo {
                    Some((k, j, far, lo))
                } else {
                    None
                }
            })
        })
    }

    /// Exact figures of (h, x) and the cut points at its local extrema.
    pub(crate) fn evaluation(
        &self,
        h: &[f64],
        x: &[Vec<f64>; 3],
        torque_samples: usize,
    ) -> Evaluation {
        let mut fig = Evaluation::new();
        for k in 0..self.nseg() {
            let seg = self.segment_figures(h, x, k, torque_samples, &mut fig.cuts);
            fig.absorb(&seg);
        }
        fig.finish()
    }

    /// [`Problem::evaluation`] of a point that [`feasible`] accepts, else
    /// the first segment found to break a limit. Segment `first` (where the
    /// last point broke one) is checked first: a bisection's infeasible
    /// points then cost one segment, not all of them.
    pub(crate) fn feasible_evaluation(
        &self,
        h: &[f64],
        x: &[Vec<f64>; 3],
        first: usize,
    ) -> Result<Evaluation, usize> {
        let breaks = |s: &SegmentFigures| {
            s.jerk > self.limits.jerk * (1.0 + 1e-9) || s.notes().iter().any(|n| n.1 > 1e-9)
        };
        let first = first.min(self.nseg().saturating_sub(1));
        let mut early_cuts = Vec::new();
        let early = self.segment_figures(h, x, first, self.torque_samples, &mut early_cuts);
        if breaks(&early) {
            return Err(first);
        }
        // The figures and cuts go in in segment order, as the evaluation's do.
        let mut fig = Evaluation::new();
        for k in 0..self.nseg() {
            if k == first {
                fig.cuts.append(&mut early_cuts);
                fig.absorb(&early);
                continue;
            }
            let seg = self.segment_figures(h, x, k, self.torque_samples, &mut fig.cuts);
            if breaks(&seg) {
                return Err(k);
            }
            fig.absorb(&seg);
        }
        Ok(fig.finish())
    }

    /// Segment k's figures in the evaluation; its cuts are appended to `cuts`.
    fn segment_figures(
        &self,
        h: &[f64],
        x: &[Vec<f64>; 3],
        k: usize,
        torque_samples: usize,
        cuts: &mut Vec<Cut>,
    ) -> SegmentFigures {
        let mut fig = SegmentFigures {
            jerk: 0.0,
            notes: [(Limited::Jerk, 0.0); 12],
            len: 0,
        };
        let hk = h[k];
        for j in 0..3 {
            let c = self.knots.coefficients(&x[j], j, k, hk);
            let vel = derivative(&c);
            let acc = derivative(&vel);
            let jerk = derivative(&acc);
            fig.jerk = fig.jerk.max(argmax_abs_on_interval(&jerk, 0.0, hk).1);
            // Travel only counts when left: a position inside it is no
            // closer to binding than the others (and changes nothing).
            let near = self.near_travel(&c, &vel, j, hk);
            if let Some((lo, hi, span)) = self.travel_of(j)
                && !near.is_empty()
            {
                let mut worst = f64::NEG_INFINITY;
                for &(t, p) in &near {
                    let u = t / hk;
                    if u > KNOT_U && u < 1.0 - KNOT_U {
                        cuts.push(Cut {
                            q: Limited::Travel,
                            j,
                            k,
                            u,
                            side: 0.0,
                        });
                    }
                    worst = worst.max((p - hi).max(lo - p) / span);
                }
                if worst > 0.0 {
                    fig.note(Limited::Travel, worst);
                }
            }
            if self.jerk_only {
                continue;
            }
            for (q, poly, rate) in [
                (Limited::Velocity, &vel, &acc),
                (Limited::Acceleration, &acc, &jerk),
            ] {
                let lim = self.limit(q);
                let mut best: f64 = 0.0;
                let ts = roots_in(rate, 0.0, hk);
                for t in ts.into_iter().chain([0.0, hk]) {
                    let signed = eval(poly, t);
                    let v = signed.abs();
                    best = best.max(v);
                    if v >= CUT_THRESHOLD * lim {
                        cuts.push(Cut {
                            q,
                            j,
                            k,
                            u: t / hk,
                            side: signed.signum(),
                        });
                    }
                }
                fig.note(q, best / lim - 1.0);
            }
        }
        if self.jerk_only {
            return fig;
        }
        // Torque on a grid; cuts at each axis's local maxima of |τ|.
        // Samples from the power coefficients: one Horner pass per joint.
        let coeffs = [0, 1, 2].map(|j| self.knots.coefficients(&x[j], j, k, hk));
        let taus: Vec<Vector3<f64>> = (0..=torque_samples)
            .map(|i| {
                let t = hk * i as f64 / torque_samples as f64;
                let m = coeffs.map(|c| eval_poly(&c, t));
                let v = |r: usize| Vector3::new(m[0][r], m[1][r], m[2][r]);
                dynamics::torque(&self.model, &v(0), &v(1), &v(2))
                    .unwrap_or(Vector3::repeat(f64::INFINITY))
            })
            .collect();
        let lim = self.limits.torque;
        for axis in 0..3 {
            let a = |i: usize| taus[i][axis].abs();
            let mut best: f64 = 0.0;
            for i in 0..=torque_samples {
                best = best.max(a(i));
                let left = i == 0 || a(i) >= a(i - 1);
                let right = i == torque_samples || a(i) >= a(i + 1);
                if left && right && a(i) >= CUT_THRESHOLD * lim {
                    let u = i as f64 / torque_samples as f64;
                    cuts.push(Cut {
                        q: Limited::Torque,
                        j: axis,
                        k,
                        u,
                        side: taus[i][axis].signum(),
                    });
                }
            }
            fig.note(Limited::Torque, best / lim - 1.0);
        }
        fig
    }

    /// (segment, u) pairs whose jerks must match: C3 at interior knots, zero at the ends.
    pub(crate) fn jerk_conditions(&self) -> Vec<(KnotSide, Option<KnotSide>)> {
        let nseg = self.nseg();
        let mut out = vec![((0, 0.0), None), ((nseg - 1, 1.0), None)];
        out.extend((1..nseg).map(|k| ((k - 1, 1.0), Some((k, 0.0)))));
        out
    }

    /// Projects each joint's x onto the C3 / end-jerk equalities exactly
    /// (least change), with the conditions in knot order so that the
    /// normal matrix is banded ([`banded`](crate::banded)).
    pub(crate) fn project(&self, h: &[f64], x: &mut [Vec<f64>; 3]) {
        let mut conds = self.jerk_conditions();
        // The knot each condition sits at: the ends, or the knot between its two sides.
        let knot = |c: &(KnotSide, Option<KnotSide>)| match c {
            ((k, u), None) => k + usize::from(*u > 0.5),
            (_, Some((k, _))) => *k,
        };
        conds.sort_by_key(knot);
        // Jerk conditions of joint j at xj: residuals, and the (x-independent) rows.
        let condition = |j: usize, xj: &[f64], c: &(KnotSide, Option<KnotSide>)| {
            let mut value = 0.0;
            let mut row: Vec<(usize, f64)> = Vec::with_capacity(8);
            for (scale, side) in [(1.0, Some(c.0)), (-1.0, c.1)] {
                let Some((k, u)) = side else { continue };
                let f = self.knots.functional(xj, j, k, u, 3, h[k]);
                value += scale * f.value;
                for &(v, a) in f.dx() {
                    match row.iter_mut().find(|e| e.0 == v) {
                        Some(e) => e.1 += scale * a,
                        None => row.push((v, scale * a)),
                    }
                }
            }
            (value, row)
        };
        for (j, xj) in x.iter_mut().enumerate() {
            let (mut r, rows): (Vec<f64>, Vec<_>) =
                conds.iter().map(|c| condition(j, xj, c)).unzip();
            let Some(e) = crate::banded::Rows::new(rows) else {
                continue;
            };
            // Refined: the residual is recomputed from the corrected x.
            for _ in 0..3 {
                let before = r.iter().fold(0.0, |m: f64, v| m.max(v.abs()));
                e.subtract_correction(&r, xj);
                r = conds.iter().map(|c| condition(j, xj, c).0).collect();
                if r.iter().fold(0.0, |m: f64, v| m.max(v.abs())) >= 0.5 * before {
                    break;
                }
            }
        }
    }

    pub(crate) fn unpack(&self, sol: &[f64]) -> [Vec<f64>; 3] {
        let nv = self.nv();
        [0, 1, 2].map(|j| sol[j * nv..(j + 1) * nv].to_vec())
    }

    /// The jerk-only relaxation of this problem. Its optimum is a lower
    /// bound; when that optimum meets every other limit it is the optimum.
    pub(crate) fn relaxed(&self) -> Problem {
        Problem {
            jerk_only: true,
            ..self.clone()
        }
    }

    /// This problem at another total time, its jerk shown to the observer
    /// at this one's time scale (a fixed shape's jerk scales as T⁻³).
    pub(crate) fn retimed(&self, total_time: f64) -> Problem {
        Problem {
            total_time,
            shown_jerk: self
                .shown_jerk
                .map(|f| f * (total_time / self.total_time).powi(3)),
            ..self.clone()
        }
    }

    /// Exact figures of (h, x) under this problem's limits.
    pub(crate) fn evaluate(&self, h: &[f64], x: &[Vec<f64>; 3]) -> Solution {
        let f = self.evaluation(h, x, self.torque_samples);
        Solution::with_figures(h.to_vec(), x.clone(), &f)
    }

    /// A solution of the relaxation as a solution of this problem, when it
    /// meets every limit here (then it is this problem's optimum too).
    pub(crate) fn accept_relaxed(&self, r: &Solution) -> Option<Solution> {
        let full = self.evaluate(&r.h, &r.x);
        (full.violation == 0.0).then_some(Solution {
            lp_solves: r.lp_solves,
            ..full
        })
    }

    /// Zero knot derivatives: the start of the first inner solve.
    pub(crate) fn zero_x(&self) -> [Vec<f64>; 3] {
        [0, 1, 2].map(|_| vec![0.0; self.nv()])
    }
}

/// The knots, limits and weight of a problem with the robot's model.
pub(crate) fn problem(
    knots: Knots,
    limits: &Limits,
    model: Model<f64>,
    total_time: f64,
) -> Problem {
    Problem {
        h_min: 1e-3,
        h_max: f64::INFINITY,
        travel: None,
        run: Arc::new(RunState::new(None)),
        torque_samples: TORQUE_SAMPLES,
        jerk_only: false,
        shown_jerk: Some(1.0),
        weight: 1e3 * limits.jerk.max(1.0),
        knots,
        limits: limits.clone(),
        model,
        total_time,
    }
}

/// Knots from joint positions, checked reachable.
pub(crate) fn knots_from(
    points: &[Vector3<f64>],
    model: &Model<f64>,
) -> Result<Knots, (usize, String)> {
    let mut q = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let pose = Pose::from_cartesian(model, *p).map_err(|e| (i, e.to_string()))?;
        q.push([pose.q.x, pose.q.y, pose.q.z]);
    }
    Ok(Knots { q })
}

/// Bernstein coefficients of the quintic with power coefficients `c` on
/// [0, h]: their hull holds its values there.
fn bernstein(c: &[f64; 6], h: f64) -> [f64; 6] {
    // a_i = c_i hⁱ; b_k = Σ_{i≤k} C(k, i) / C(5, i) a_i.
    const BINOM: [[f64; 6]; 6] = [
        [1.0, 0.0, 0.0, 0.0, 0.0, 0.0],
        [1.0, 1.0, 0.0, 0.0, 0.0, 0.0],
        [1.0, 2.0, 1.0, 0.0, 0.0, 0.0],
        [1.0, 3.0, 3.0, 1.0, 0.0, 0.0],
        [1.0, 4.0, 6.0, 4.0, 1.0, 0.0],
        [1.0, 5.0, 10.0, 10.0, 5.0, 1.0],
    ];
    let mut a = *c;
    let mut hp = 1.0;
    for ai in a.iter_mut() {
        *ai *= hp;
        hp *= h;
    }
    core::array::from_fn(|k| (0..=k).map(|i| BINOM[k][i] / BINOM[5][i] * a[i]).sum())
}

/// Strict acceptance of a final plan: no limit exceeded at all.
pub(crate) fn meets_every_limit(p: &Problem, s: &Solution) -> bool {
    s.violation == 0.0 && s.jerk <= p.limits.jerk
}

/// A solution is feasible when no limit is violated beyond rounding.
pub(crate) fn feasible(p: &Problem, s: &Solution) -> bool {
    s.violation <= 1e-9 && s.jerk <= p.limits.jerk * (1.0 + 1e-9)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search_tests::{example_problem, uneven_intervals};

    /// Knot derivatives that are not C3: a deterministic pattern.
    fn rough_x(p: &Problem) -> [Vec<f64>; 3] {
        [0, 1, 2].map(|j| {
            (0..p.knots.vars())
                .map(|i| 0.01 * (((i * 7 + j * 3) % 5) as f64 - 2.0))
                .collect()
        })
    }

    #[test]
    fn the_exact_maximum_bounds_a_dense_sampling_and_is_reached_by_it() {
        let mut p = example_problem("paper-case2.toml");
        let h = uneven_intervals(&p);
        let mut x = rough_x(&p);
        p.project(&h, &mut x);
        let s = p.evaluate(&h, &x);
        let mut sampled: f64 = 0.0;
        for k in 0..p.knots.segments() {
            for j in 0..3 {
                let c = p.knots.coefficients(&x[j], j, k, h[k]);
                let jerk = derivative(&derivative(&derivative(&c)));
                for i in 0..=2000 {
                    sampled = sampled.max(eval(&jerk, h[k] * i as f64 / 2000.0).abs());
                }
            }
        }
        assert!(s.jerk >= sampled, "{} < sampled {sampled}", s.jerk);
        assert!(
            s.jerk <= sampled * (1.0 + 1e-5),
            "{} ≫ sampled {sampled}",
            s.jerk
        );
        // The end jerks are part of the problem's equalities: the ends rest.
        p.limits.velocity = 1e-6;
        let slow = p.evaluate(&h, &x);
        assert!(slow.violation > 0.0 && slow.binding == Limited::Velocity);
    }

    /// The Bernstein hull holds the quintic, and its ends are the quintic's.
    #[test]
    fn the_bernstein_hull_holds_the_segment() {
        let c = [0.2, -0.3, 1.1, -2.0, 0.7, 0.4];
        let h = 1.7;
        let b = bernstein(&c, h);
        let (lo, hi) = b
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, u), &x| (l.min(x), u.max(x)));
        for i in 0..=1000 {
            let v = eval(&c, h * i as f64 / 1000.0);
            assert!(
                v >= lo - 1e-12 && v <= hi + 1e-12,
                "{v} outside [{lo}, {hi}]"
            );
        }
        assert!((b[0] - eval(&c, 0.0)).abs() < 1e-12);
        assert!((b[5] - eval(&c, h)).abs() < 1e-12);
    }

    #[test]
    fn projection_meets_c3_and_rest_at_the_ends() {
        let p = example_problem("paper-case1.toml");
        let h = uneven_intervals(&p);
        let mut x = rough_x(&p);
        let residual = |x: &[Vec<f64>; 3]| {
            let mut worst: f64 = 0.0;
            for j in 0..3 {
                for ((ka, ua), b) in p.jerk_conditions() {
                    let a = p.knots.functional(&x[j], j, ka, ua, 3, h[ka]).value;
                    let b = b.map_or(0.0, |(kb, ub)| {
                        p.knots.functional(&x[j], j, kb, ub, 3, h[kb]).value
                    });
                    worst = worst.max((a - b).abs());
                }
            }
            worst
        };
        assert!(residual(&x) > 1e-3, "the test's x is C3 already");
        p.project(&h, &mut x);
        assert!(residual(&x) < 1e-9, "{}", residual(&x));
    }

    #[test]
    fn the_relaxation_evaluates_jerk_alone() {
        let mut p = example_problem("paper-case2.toml");
        p.limits.velocity = 1e-6;
        p.limits.torque = 1e-6;
        let h = uneven_intervals(&p);
        let mut x = rough_x(&p);
        p.project(&h, &mut x);
        let full = p.evaluate(&h, &x);
        let relaxed = p.relaxed().evaluate(&h, &x);
        assert!(full.violation > 1.0);
        assert_eq!(relaxed.violation, 0.0);
        assert_eq!(relaxed.binding, Limited::Jerk);
        assert_eq!(relaxed.jerk, full.jerk);
        assert!(p.accept_relaxed(&relaxed).is_none());
        assert!(!feasible(&p, &full));
    }
}
