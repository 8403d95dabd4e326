//! The planning problem for fixed knots, and its two solvers:
//!
//! - [`Problem::inner`]: intervals h fixed. Min-max jerk over the knot
//!   velocities/accelerations is a linear program; the jerk, acceleration and
//!   velocity of a segment are polynomials in time, so their extrema are known
//!   in closed form, and cutting planes are added at them until the LP's bound
//!   equals the exact continuous-time maximum. Torque limits are linearised
//!   in (q, q̇, q̈) at sampled local maxima and re-linearised until they hold.
//! - [`Problem::local_search`]: h free. A trust-region sequential linear
//!   program over (x, h): each step solves the LP linearised in h at the
//!   current point, and the step is accepted on the exact merit of the inner
//!   problem at the new intervals.
//!
//! Limits other than jerk enter with one elastic variable σ (relative
//! violation), priced by a large weight, so every LP is feasible and an
//! infeasible job is recognised by σ > 0 at the optimum.

// Index loops over joints and segments mirror the maths.
#![allow(clippy::needless_range_loop)]

use nalgebra::Vector3;
use triquint_shared::kinematics::Pose;
use triquint_shared::quintic::eval_poly;
use triquint_shared::{Limits, Model, dynamics};

use std::sync::Arc;

use crate::extrema::{argmax_abs_on_interval, derivative, eval, roots_in};
use crate::lp::{Lp, LpFailure};
use crate::spline::{Affine, Knots};
use crate::watch::Watch;

/// Which limited quantity a constraint or a violation concerns.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum Quantity {
    Velocity,
    Acceleration,
    Jerk,
    Torque,
}

/// Torque samples per segment while searching (the final solve uses more).
const TORQUE_SAMPLES: usize = 48;
/// Fraction of a limit above which a local extremum gets a constraint.
const CUT_THRESHOLD: f64 = 0.5;
/// Relative tolerance of the cutting-plane loop.
const TOL: f64 = 1e-9;
const MAX_INNER_ROUNDS: usize = 25;
/// Cutting-plane rounds of a trust-region step's program, and when judging
/// the step (its figures are exact whatever the count; more rounds only
/// improve x).
const STEP_ROUNDS: usize = 6;
/// Jerk (m/s³) below which a program's jerk rows are scaled to 1 (see
/// [`Problem::build`]). Not at 1: a point-to-point move's relaxation
/// (0.6 m/s³) then took 26 LPs instead of 19 to the same plan.
const SMALL_JERK: f64 = 0.1;
/// Accuracy of the inner solves. Tighter asks for more than the interior
/// point method delivers on these degenerate problems (most solves then end
/// "almost solved", less accurate than this).
const INNER_TOL: f64 = 1e-9;
/// Relative promise of a trust-region step below which a rejection whose
/// promise did not fall with the region counts as the model's error floor.
const FLOOR_GAIN: f64 = 1e-4;

/// One planning problem: knots, limits, dynamics and the time budget.
#[derive(Clone, Debug)]
pub struct Problem {
    pub knots: Knots,
    pub limits: Limits,
    pub model: Model<f64>,
    pub total_time: f64,
    pub h_min: f64,
    /// Longest interval (the wire's segment limit).
    pub h_max: f64,
    /// Cancellation and progress, shared by every copy of the problem.
    pub(crate) watch: Arc<Watch>,
    /// Price of one unit of relative limit violation, in m/s³.
    pub weight: f64,
    /// Torque samples per segment where local maxima get constraints.
    pub torque_samples: usize,
    /// Jerk only: velocity, acceleration and torque are neither constrained
    /// nor evaluated (the relaxation solved first, see [`Problem::relaxed`]).
    pub jerk_only: bool,
}

/// A candidate plan: intervals, knot derivatives, and its exact figures.
#[derive(Clone, Debug)]
pub struct Solution {
    pub h: Vec<f64>,
    pub x: [Vec<f64>; 3],
    /// Exact continuous-time max |jerk| over all joints (m/s³).
    pub jerk: f64,
    /// Largest relative violation of the velocity, acceleration and torque limits (0 if none).
    pub violation: f64,
    /// The quantity with the largest violation, or the closest to its limit.
    pub binding: Quantity,
    pub lp_solves: u64,
}

impl Solution {
    pub fn merit(&self, weight: f64) -> f64 {
        self.jerk + weight * self.violation
    }
}

/// A step of the minimum-time descent: new intervals, knot derivatives,
/// and the LPs it took.
pub(crate) struct TimeStep {
    pub h: Vec<f64>,
    pub x: [Vec<f64>; 3],
    pub solves: u64,
}

/// The cutting-plane rounds of one step program ([`Problem::step_rounds`]).
struct StepRounds {
    /// The last solved round.
    last: Option<StepPoint>,
    solves: u64,
    /// The failure that ended the rounds, if one did.
    failed: Option<LpFailure>,
}

/// A solved step program: its solution, its intervals, and its knot
/// derivatives on C3 there.
struct StepPoint {
    sol: Vec<f64>,
    h: Vec<f64>,
    x: [Vec<f64>; 3],
}

/// (segment, normalised time) of one side of a jerk condition.
type KnotSide = (usize, f64);

#[derive(Clone, Copy, Debug, PartialEq)]
struct Cut {
    q: Quantity,
    /// Joint (or, for torque, motor axis).
    j: usize,
    k: usize,
    u: f64,
}

/// Exact figures of a point, and where the extrema are.
struct Figures {
    jerk: f64,
    violation: f64,
    binding: Quantity,
    cuts: Vec<Cut>,
}

/// Terms of one LP row built from affine forms.
#[derive(Default)]
struct RowBuilder {
    terms: Vec<(usize, f64)>,
    /// Value of the row's affine expression with all LP variables at zero.
    constant: f64,
}

impl RowBuilder {
    /// Σ scale·row.
    fn combine(parts: &[(f64, &RowBuilder)]) -> RowBuilder {
        let mut out = RowBuilder::default();
        for &(scale, row) in parts {
            out.terms
                .extend(row.terms.iter().map(|&(c, v)| (c, scale * v)));
            out.constant += scale * row.constant;
        }
        out
    }

    /// The row plus coef·(variable col).
    fn plus(mut self, col: usize, coef: f64) -> RowBuilder {
        self.terms.push((col, coef));
        self
    }

    /// Adds scale·(an affine form of joint j on segment k), linearised at x0.
    fn add(&mut self, scale: f64, f: &Affine, x0: &[f64], x_off: usize, dh_col: Option<usize>) {
        let mut c = f.value;
        for &(v, a) in f.dx() {
            self.terms.push((x_off + v, scale * a));
            c -= a * x0[v];
        }
        if let Some(col) = dh_col {
            self.terms.push((col, scale * f.dh));
        }
        self.constant += scale * c;
    }
}

impl Problem {
    fn nv(&self) -> usize {
        self.knots.vars()
    }

    fn nseg(&self) -> usize {
        self.knots.segments()
    }

    /// Solves one of this problem's programs, unless the search is cancelled.
    fn solve(&self, lp: &Lp) -> Result<Vec<f64>, LpFailure> {
        if !self.watch.proceed() {
            return Err(LpFailure::Cancelled);
        }
        lp.solve()
    }

    pub(crate) fn limit(&self, q: Quantity) -> f64 {
        match q {
            Quantity::Velocity => self.limits.velocity,
            Quantity::Acceleration => self.limits.acceleration,
            Quantity::Jerk => self.limits.jerk,
            Quantity::Torque => self.limits.torque,
        }
    }

    /// Joint positions, velocities, accelerations at (segment k, u) as affine forms.
    fn motion_forms(&self, h: &[f64], x: &[Vec<f64>; 3], k: usize, u: f64) -> [[Affine; 3]; 3] {
        [0, 1, 2].map(|j| [0, 1, 2].map(|r| self.knots.functional(&x[j], j, k, u, r, h[k])))
    }

    /// Exact figures of (h, x) and the cut points at its local extrema.
    fn figures(&self, h: &[f64], x: &[Vec<f64>; 3], torque_samples: usize) -> Figures {
        let mut fig = Figures {
            jerk: 0.0,
            violation: 0.0,
            binding: Quantity::Jerk,
            cuts: Vec::new(),
        };
        let mut closest = f64::NEG_INFINITY;
        let mut note = |fig: &mut Figures, q: Quantity, value: f64| {
            let rel = value / self.limit(q) - 1.0;
            if rel > closest {
                closest = rel;
                fig.binding = q;
            }
            fig.violation = fig.violation.max(rel);
        };
        for k in 0..self.nseg() {
            let hk = h[k];
            for j in 0..3 {
                let c = self.knots.coefficients(&x[j], j, k, hk);
                let vel = derivative(&c);
                let acc = derivative(&vel);
                let jerk = derivative(&acc);
                fig.jerk = fig.jerk.max(argmax_abs_on_interval(&jerk, 0.0, hk).1);
                if self.jerk_only {
                    continue;
                }
                for (q, poly, rate) in [
                    (Quantity::Velocity, &vel, &acc),
                    (Quantity::Acceleration, &acc, &jerk),
                ] {
                    let lim = self.limit(q);
                    let mut best: f64 = 0.0;
                    let ts = roots_in(rate, 0.0, hk);
                    for t in ts.into_iter().chain([0.0, hk]) {
                        let v = eval(poly, t).abs();
                        best = best.max(v);
                        if v >= CUT_THRESHOLD * lim {
                            fig.cuts.push(Cut { q, j, k, u: t / hk });
                        }
                    }
                    note(&mut fig, q, best);
                }
            }
            if self.jerk_only {
                continue;
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
                        fig.cuts.push(Cut {
                            q: Quantity::Torque,
                            j: axis,
                            k,
                            u,
                        });
                    }
                }
                note(&mut fig, Quantity::Torque, best);
            }
        }
        fig.violation = fig.violation.max(0.0);
        fig
    }

    /// Builds the LP at (h, x) with these cuts; `trust` = Some(Δ) lets h move by
    /// at most Δ·h_k (linearised), None keeps h fixed. `jerk` is the size of
    /// the jerks about there (m/s³): below [`SMALL_JERK`] the jerk rows and
    /// the cost are divided by it. The solver's gap and residual tests are
    /// absolute below 1 (its relative measures have a floor of 1), so at a
    /// jerk of 1e-4 they were 1e-4 of it, and the trust-region steps stalled
    /// on that noise (the 200-point closed curve ended 1.5 % above its
    /// optimum).
    /// Scaling a row with its right-hand side, or a cone's rows together,
    /// keeps the feasible set; scaling the cost keeps the optimum.
    fn build(
        &self,
        h: &[f64],
        x: &[Vec<f64>; 3],
        cuts: &[Cut],
        trust: Option<f64>,
        jerk: f64,
    ) -> Lp {
        let k_j = if jerk < SMALL_JERK {
            1.0 / jerk.max(1e-12)
        } else {
            1.0
        };
        let nv = self.nv();
        let nseg = self.nseg();
        let dh0 = 3 * nv;
        let s_col = dh0 + if trust.is_some() { nseg } else { 0 };
        let sigma = s_col + 1;
        let lambda0 = sigma + 1;
        let mut lp = Lp::new(lambda0 + 6 * nseg);
        lp.cost[s_col] = k_j;
        lp.cost[sigma] = self.weight * k_j;
        let dh_col = |k: usize| trust.map(|_| dh0 + k);

        // C3 at interior knots and zero jerk at both ends.
        for j in 0..3 {
            for (a, b) in self.jerk_conditions() {
                let mut row = RowBuilder::default();
                for (scale, (k, u)) in [(1.0, a), (-1.0, b.unwrap_or((0, f64::NAN)))] {
                    if u.is_nan() {
                        continue;
                    }
                    let f = self.knots.functional(&x[j], j, k, u, 3, h[k]);
                    row.add(scale * k_j, &f, &x[j], j * nv, dh_col(k));
                }
                lp.equal(&row.terms, -row.constant);
            }
        }

        // |jerk| ≤ s on every whole segment, exactly: s ∓ J(u) is a quadratic
        // in u that must be ≥ 0 on [0, 1], which holds iff it equals
        // σ₀(u) + λ u(1 − u) with σ₀ a sum of squares (a 2×2 PSD matrix, i.e.
        // a 3-dimensional second-order cone) and λ ≥ 0 (Markov–Lukács).
        for j in 0..3 {
            for k in 0..nseg {
                let at = |u: f64| {
                    let mut row = RowBuilder::default();
                    let f = self.knots.functional(&x[j], j, k, u, 3, h[k]);
                    row.add(k_j, &f, &x[j], j * nv, dh_col(k));
                    row
                };
                let (j0, jm, j1) = (at(0.0), at(0.5), at(1.0));
                // Power coefficients of J(u) from its values at 0, ½, 1.
                let c0 = RowBuilder::combine(&[(1.0, &j0)]);
                let c1 = RowBuilder::combine(&[(-3.0, &j0), (4.0, &jm), (-1.0, &j1)]);
                let c2 = RowBuilder::combine(&[(2.0, &j0), (-4.0, &jm), (2.0, &j1)]);
                for (n, sign) in [1.0, -1.0].into_iter().enumerate() {
                    let lam = lambda0 + 6 * k + 2 * j + n;
                    lp.at_most(&[(lam, -1.0)], 0.0);
                    // p(u) = s − sign·J(u): p0 = s − sign c0, p1 = −sign c1, p2 = −sign c2.
                    let p0 = RowBuilder::combine(&[(-sign, &c0)]).plus(s_col, k_j);
                    let p1 = RowBuilder::combine(&[(-sign, &c1)]);
                    let p2 = RowBuilder::combine(&[(-sign, &c2)]);
                    let t = RowBuilder::combine(&[(1.0, &p0), (1.0, &p2)]).plus(lam, 1.0);
                    let a = RowBuilder::combine(&[(1.0, &p1)]).plus(lam, -1.0);
                    let b = RowBuilder::combine(&[(1.0, &p0), (-1.0, &p2)]).plus(lam, -1.0);
                    lp.second_order_cone([
                        (&t.terms, t.constant),
                        (&a.terms, a.constant),
                        (&b.terms, b.constant),
                    ]);
                }
            }
        }

        for cut in cuts {
            let mut row = RowBuilder::default();
            match cut.q {
                Quantity::Torque => {
                    let f = self.motion_forms(h, x, cut.k, cut.u);
                    let Some(grad) = self.torque_gradient(&f, cut.j) else {
                        continue;
                    };
                    for j in 0..3 {
                        for r in 0..3 {
                            row.add(grad.1[j][r], &f[j][r], &x[j], j * nv, dh_col(cut.k));
                        }
                    }
                    // Affine part: τ0 − Σ ∂τ·D0 + Σ ∂τ·D(x, δh).
                    let lin0: f64 = (0..3)
                        .flat_map(|j| (0..3).map(move |r| (j, r)))
                        .map(|(j, r)| grad.1[j][r] * f[j][r].value)
                        .sum();
                    row.constant += grad.0 - lin0;
                }
                q => {
                    let r = match q {
                        Quantity::Velocity => 1,
                        Quantity::Acceleration => 2,
                        _ => 3,
                    };
                    let f = self
                        .knots
                        .functional(&x[cut.j], cut.j, cut.k, cut.u, r, h[cut.k]);
                    row.add(1.0, &f, &x[cut.j], cut.j * nv, dh_col(cut.k));
                }
            }
            for sign in [1.0, -1.0] {
                let mut terms: Vec<(usize, f64)> =
                    row.terms.iter().map(|&(c, v)| (c, sign * v)).collect();
                if cut.q == Quantity::Jerk {
                    terms.iter_mut().for_each(|t| t.1 *= k_j);
                    terms.push((s_col, -k_j));
                    lp.at_most(&terms, -sign * row.constant * k_j);
                } else {
                    let lim = self.limit(cut.q);
                    terms.push((sigma, -lim));
                    lp.at_most(&terms, lim - sign * row.constant);
                }
            }
        }
        lp.at_most(&[(sigma, -1.0)], 0.0);

        if let Some(delta) = trust {
            let slack = self.total_time - h.iter().sum::<f64>();
            let all: Vec<(usize, f64)> = (0..nseg).map(|k| (dh0 + k, 1.0)).collect();
            lp.at_most(&all, slack.max(0.0));
            for (k, &hk) in h.iter().enumerate() {
                lp.at_most(
                    &[(dh0 + k, 1.0)],
                    (delta * hk).min(self.h_max - hk).max(0.0),
                );
                lp.at_most(
                    &[(dh0 + k, -1.0)],
                    (delta * hk).min(hk - self.h_min).max(0.0),
                );
            }
        }
        lp
    }

    /// (segment, u) pairs whose jerks must match: C3 at interior knots, zero at the ends.
    pub(crate) fn jerk_conditions(&self) -> Vec<(KnotSide, Option<KnotSide>)> {
        let nseg = self.nseg();
        let mut out = vec![((0, 0.0), None), ((nseg - 1, 1.0), None)];
        out.extend((1..nseg).map(|k| ((k - 1, 1.0), Some((k, 0.0)))));
        out
    }

    /// τ_axis and ∂τ_axis/∂(q_j, q̇_j, q̈_j) at a point.
    #[allow(clippy::type_complexity)]
    fn torque_gradient(&self, f: &[[Affine; 3]; 3], axis: usize) -> Option<(f64, [[f64; 3]; 3])> {
        let base = [0, 1, 2].map(|r| Vector3::new(f[0][r].value, f[1][r].value, f[2][r].value));
        let tau = |s: &[Vector3<f64>; 3]| {
            dynamics::torque(&self.model, &s[0], &s[1], &s[2])
                .ok()
                .map(|t| t[axis])
        };
        let t0 = tau(&base)?;
        let mut grad = [[0.0; 3]; 3];
        for (j, row) in grad.iter_mut().enumerate() {
            for (r, g) in row.iter_mut().enumerate() {
                // Torque is affine in q̈ and quadratic in q̇: central differences are exact there.
                let e = if r == 0 { 1e-6 } else { 1e-3 };
                let mut plus = base;
                plus[r][j] += e;
                let mut minus = base;
                minus[r][j] -= e;
                *g = (tau(&plus)? - tau(&minus)?) / (2.0 * e);
            }
        }
        Some((t0, grad))
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

    fn unpack(&self, sol: &[f64]) -> [Vec<f64>; 3] {
        let nv = self.nv();
        [0, 1, 2].map(|j| sol[j * nv..(j + 1) * nv].to_vec())
    }

    /// Exact min-max-jerk knot derivatives for fixed intervals (cutting planes).
    /// `x0` is where torque is first linearised (zeros will do).
    pub fn inner(&self, h: &[f64], x0: &[Vec<f64>; 3]) -> Option<Solution> {
        self.inner_rounds(h, x0, MAX_INNER_ROUNDS)
    }

    /// [`Problem::inner`] with at most `max_rounds` cutting-plane rounds.
    fn inner_rounds(&self, h: &[f64], x0: &[Vec<f64>; 3], max_rounds: usize) -> Option<Solution> {
        // Jerk only: each joint's exact optimum without an interior-point solve.
        if self.jerk_only
            && self.watch.cancelled().is_none()
            && let Some(x) = self.jerk_only_direct(h, x0)
        {
            let fig = self.figures(h, &x, self.torque_samples);
            return Some(Solution {
                h: h.to_vec(),
                x,
                jerk: fig.jerk,
                violation: fig.violation,
                binding: fig.binding,
                lp_solves: 0,
            });
        }
        self.inner_lp(h, x0, max_rounds)
    }

    /// [`Problem::inner_rounds`] by interior-point solves only.
    pub(crate) fn inner_lp(
        &self,
        h: &[f64],
        x0: &[Vec<f64>; 3],
        max_rounds: usize,
    ) -> Option<Solution> {
        let mut x = x0.clone();
        let first = self.figures(h, &x, self.torque_samples);
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
            let fig = self.figures(h, &x, self.torque_samples);
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
                && (fig.binding != Quantity::Torque || moved <= 1e-9 * scale);
            let before = cuts.len();
            add_new_cuts(&mut cuts, &fig.cuts);
            // Without a new cut the next LP is the same one, unless torque
            // cuts are re-linearised at the new point: stop, the figures are exact.
            let relinearise = moved > 1e-9 * scale && cuts.iter().any(|c| c.q == Quantity::Torque);
            let stuck = cuts.len() == before && !relinearise;
            if exact || stuck || solves == max_rounds as u64 {
                return Some(Solution {
                    h: h.to_vec(),
                    x,
                    jerk: fig.jerk,
                    violation: fig.violation,
                    binding: fig.binding,
                    lp_solves: solves,
                });
            }
        }
        None
    }

    /// Trust-region SLP over (x, h) from `start` (an inner solution), with
    /// Σh ≤ total_time: each step solves the problem linearised in h at the
    /// current point (x is exact there) and is judged on the exact inner
    /// optimum at the new intervals. Stops when a step gains less than
    /// `rel_tol` of the merit (three times running), when the model's
    /// promise falls to the LP's accuracy, or when the region collapses.
    pub fn local_search(&self, start: &Solution, max_iter: usize, rel_tol: f64) -> Solution {
        self.local_search_until(start, max_iter, rel_tol, &|_| false)
    }

    /// [`Problem::local_search`] that also stops at the first point where `done` holds.
    pub fn local_search_until(
        &self,
        start: &Solution,
        max_iter: usize,
        rel_tol: f64,
        done: &dyn Fn(&Solution) -> bool,
    ) -> Solution {
        let nv = self.nv();
        let nseg = self.nseg();
        let nd = 3 * nv + nseg;
        let mut cur = start.clone();
        let mut delta = 0.25;
        let mut solves = 0;
        let mut stalled = 0;
        let mut rejected_small = 0;
        // Rejections since the last accepted step whose promise did not
        // fall with the region (see below), and the last rejected promise.
        let mut at_floor = 0;
        let mut last_rejected_gain = f64::INFINITY;
        for _ in 0..max_iter {
            if done(&cur) {
                break;
            }
            // Where a limit other than jerk binds, a step with only the cuts
            // at the current point's extrema promised what held only there:
            // steps were rejected, the region fell to 1e-4 and the search
            // crawled (the 24-point closed curve at 5.75 s took 2 500 LPs to
            // 4.81297 m/s³, 1 546 to 4.81231 with the rounds).
            let rounds = self.step_rounds(&cur, delta, |_| {});
            solves += rounds.solves;
            let Some(StepPoint {
                sol,
                h: h_new,
                x: x_new,
            }) = rounds.last
            else {
                delta *= 0.25;
                if delta < 1e-7 {
                    break;
                }
                continue;
            };
            let merit = cur.merit(self.weight);
            let predicted = sol[nd] + self.weight * sol[nd + 1];
            let gain = merit - predicted;
            // Below the step LP's accuracy a predicted gain is noise.
            if gain <= 1e-9 * merit {
                break;
            }
            // The step is judged on the exact inner optimum at the new
            // intervals: x re-optimised, not the LP's x projected back onto C3
            // (that evaluation understates the gain and keeps steps tiny).
            let Some(cand) = self.inner_at(&h_new, &x_new, STEP_ROUNDS) else {
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
                // smaller step would deliver. On the 100-point curve each
                // search ended in ten such rejections, promising 1e-5 of
                // the merit down to a region of 1e-7.
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

    /// The step program at `cur` (h moving by at most Δ·h_k), shaped by
    /// `shape`, in cutting-plane rounds as in the inner loop: each round's
    /// point is checked exactly and its new extrema cut, so the step does
    /// not promise what is only true at the old extrema. With jerk alone
    /// there are no cuts: one round. Ends at the first round that adds no
    /// cut, at [`STEP_ROUNDS`], or at a failed solve.
    fn step_rounds(&self, cur: &Solution, delta: f64, shape: impl Fn(&mut Lp)) -> StepRounds {
        let mut cuts = self.figures(&cur.h, &cur.x, self.torque_samples).cuts;
        let mut out = StepRounds {
            last: None,
            solves: 0,
            failed: None,
        };
        for _ in 0..STEP_ROUNDS {
            let mut lp = self.build(&cur.h, &cur.x, &cuts, Some(delta), cur.jerk);
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
            add_new_cuts(&mut cuts, &self.figures(&h, &x, self.torque_samples).cuts);
            let settled = cuts.len() == before;
            out.last = Some(StepPoint { sol, h, x });
            if settled {
                break;
            }
        }
        out
    }

    /// The point of a step program's solution `sol` from intervals `h`: the
    /// new intervals (at least h_min) and the knot derivatives projected
    /// onto C3 there.
    fn step_point(&self, h: &[f64], sol: &[f64]) -> (Vec<f64>, [Vec<f64>; 3]) {
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

    /// One step of the minimum-time descent ([`crate::time_descent`]) from
    /// `cur`: the LP linearised in h at `cur` (h moving by at most Δ·h_k),
    /// minimising Σh with the jerk capped at its limit and every limit
    /// elastic; returns the new intervals, the LP's knot derivatives
    /// projected onto C3 there.
    pub(crate) fn time_step(&self, cur: &Solution, delta: f64) -> Result<TimeStep, LpFailure> {
        let nv = self.nv();
        let nseg = self.nseg();
        let (dh0, s_col) = (3 * nv, 3 * nv + nseg);
        let sigma = s_col + 1;
        let t: f64 = cur.h.iter().sum();
        let jerk = self.limits.jerk;
        let rounds = self.step_rounds(cur, delta, |lp| {
            // Relative time against relative violation: making up a
            // violation ν by time-scaling costs about ν/2 of the time, so
            // 1e3 keeps σ at 0 whenever the linearisation allows it.
            lp.cost[s_col] = 0.0;
            lp.cost[sigma] = 1e3;
            for k in 0..nseg {
                lp.cost[dh0 + k] = 1.0 / t;
            }
            lp.at_most(&[(s_col, 1.0), (sigma, -jerk)], jerk);
        });
        if let Some(failure) = rounds.failed {
            return Err(failure);
        }
        let StepPoint { h, x, .. } = rounds.last.ok_or(LpFailure::Cancelled)?;
        Ok(TimeStep {
            h,
            x,
            solves: rounds.solves,
        })
    }

    /// The jerk-only relaxation of this problem. Its optimum is a lower
    /// bound; when that optimum meets every other limit it is the optimum.
    pub fn relaxed(&self) -> Problem {
        Problem {
            jerk_only: true,
            ..self.clone()
        }
    }

    /// Exact figures of (h, x) under this problem's limits.
    pub fn evaluate(&self, h: &[f64], x: &[Vec<f64>; 3]) -> Solution {
        let f = self.figures(h, x, self.torque_samples);
        Solution {
            h: h.to_vec(),
            x: x.clone(),
            jerk: f.jerk,
            violation: f.violation,
            binding: f.binding,
            lp_solves: 0,
        }
    }

    /// A solution of the relaxation as a solution of this problem, when it
    /// meets every limit here (then it is this problem's optimum too).
    pub fn accept_relaxed(&self, r: &Solution) -> Option<Solution> {
        let full = self.evaluate(&r.h, &r.x);
        (full.violation == 0.0).then_some(Solution {
            lp_solves: r.lp_solves,
            ..full
        })
    }

    /// The inner optimum at fixed h, through the relaxation when its answer
    /// meets every limit (then it is exact, and the cutting planes are skipped).
    pub fn inner_via_relaxation(&self, h: &[f64], x0: &[Vec<f64>; 3]) -> Option<Solution> {
        self.inner_at(h, x0, MAX_INNER_ROUNDS)
    }

    /// [`Problem::inner_via_relaxation`] for a final plan: the relaxation's
    /// direct solve (each joint at its own exact min-max jerk, no
    /// interior-point solve) when it meets every limit. Only at the end:
    /// the search and the descent start better from the interior-point
    /// solve's central knot derivatives (see [`Problem::inner_at`]).
    pub(crate) fn inner_final(&self, h: &[f64], x0: &[Vec<f64>; 3]) -> Option<Solution> {
        if !self.jerk_only
            && self.watch.cancelled().is_none()
            && let Some(x) = self.relaxed().jerk_only_direct(h, x0)
        {
            let full = self.evaluate(h, &x);
            if full.violation == 0.0 {
                return Some(full);
            }
        }
        self.inner_via_relaxation(h, x0)
    }

    /// [`Problem::inner_via_relaxation`] with at most `max_rounds` cutting-plane rounds.
    fn inner_at(&self, h: &[f64], x0: &[Vec<f64>; 3], max_rounds: usize) -> Option<Solution> {
        // The relaxation's probe keeps the interior-point solve: its knot
        // derivatives (the analytic centre of the non-binding joints') start
        // the full problem's cutting planes, and the direct solve's
        // (each joint at its own optimum) made min-time 1.3× slower.
        if !self.jerk_only
            && let Some(r) = self.relaxed().inner_lp(h, x0, MAX_INNER_ROUNDS)
        {
            if let Some(sol) = self.accept_relaxed(&r) {
                return Some(sol);
            }
            return self.inner_rounds(h, &r.x, max_rounds).map(|s| Solution {
                lp_solves: s.lp_solves + r.lp_solves,
                ..s
            });
        }
        self.inner_rounds(h, x0, max_rounds)
    }

    /// Zero knot derivatives: the start of the first inner solve.
    pub fn zero_x(&self) -> [Vec<f64>; 3] {
        [0, 1, 2].map(|_| vec![0.0; self.nv()])
    }
}

/// Appends the cuts of `found` that `cuts` does not hold yet (same
/// quantity, joint, segment and normalised time).
fn add_new_cuts(cuts: &mut Vec<Cut>, found: &[Cut]) {
    for c in found {
        if !cuts
            .iter()
            .any(|d| d.q == c.q && d.j == c.j && d.k == c.k && (d.u - c.u).abs() < 1e-9)
        {
            cuts.push(*c);
        }
    }
}

/// The knots, limits and weight of a problem with the robot's model.
pub fn problem(knots: Knots, limits: &Limits, model: Model<f64>, total_time: f64) -> Problem {
    Problem {
        h_min: 1e-3,
        h_max: f64::INFINITY,
        watch: Arc::new(Watch::new(None)),
        torque_samples: TORQUE_SAMPLES,
        jerk_only: false,
        weight: 1e3 * limits.jerk.max(1.0),
        knots,
        limits: limits.clone(),
        model,
        total_time,
    }
}

/// Knots from joint positions, checked reachable.
pub fn knots_from(points: &[Vector3<f64>], model: &Model<f64>) -> Result<Knots, (usize, String)> {
    let mut q = Vec::with_capacity(points.len());
    for (i, p) in points.iter().enumerate() {
        let pose = Pose::from_cartesian(model, *p).map_err(|e| (i, e.to_string()))?;
        q.push([pose.q.x, pose.q.y, pose.q.z]);
    }
    Ok(Knots { q })
}
