//! The program of a problem at a point: the second-order-cone program whose
//! optimum is the min-max-jerk knot derivatives, with h fixed or, in a
//! trust region, linearised in h.
//!
//! Velocity, acceleration, torque and travel limits enter as cutting planes
//! at the evaluation's extrema ([`crate::problem`]); torque is linearised in
//! (q, q̇, q̈) there.

// Index loops over joints and segments mirror the maths.
#![allow(clippy::needless_range_loop)]

use nalgebra::Vector3;
use triquint_shared::dynamics;

use crate::lp::{Lp, Marks};
use crate::problem::{Cut, Limited, Problem, TRAVEL_MARGIN};
use crate::spline::Affine;

/// Jerk (m/s³) below which a program's jerk rows are scaled to 1 (see
/// [`Problem::build`]). Not at 1: the small relaxations of point-to-point
/// moves then took more solves to the same plan (docs/planner-speed.md).
const SMALL_JERK: f64 = 0.1;

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
    /// Joint positions, velocities, accelerations at (segment k, u) as affine forms.
    fn motion_forms(&self, h: &[f64], x: &[Vec<f64>; 3], k: usize, u: f64) -> [[Affine; 3]; 3] {
        [0, 1, 2].map(|j| [0, 1, 2].map(|r| self.knots.functional(&x[j], j, k, u, r, h[k])))
    }

    /// Builds the LP at (h, x) with these cuts; `trust` = Some(Δ) lets h move by
    /// at most Δ·h_k (linearised), None keeps h fixed. `jerk` is the size of
    /// the jerks about there (m/s³): below [`SMALL_JERK`] the jerk rows and
    /// the cost are divided by it. The solver's gap and residual tests are
    /// absolute below 1 (its relative measures have a floor of 1), so at a
    /// small jerk they are coarse relative to it, and the trust-region steps
    /// stall on that noise (docs/planner-speed.md).
    /// Scaling a row with its right-hand side, or a cone's rows together,
    /// keeps the feasible set; scaling the cost keeps the optimum.
    pub(crate) fn build(
        &self,
        h: &[f64],
        x: &[Vec<f64>; 3],
        cuts: &[Cut],
        trust: Option<f64>,
        jerk: f64,
    ) -> Lp {
        let mut program = self.program_at(h, x, trust, jerk);
        program.add_cuts(self, cuts);
        program.finish(self)
    }

    /// The program at (h, x) without its cuts ([`Problem::build`]), to
    /// which cuts are added ([`Program::add_cuts`]) before it is finished
    /// ([`Program::finish`]): the rows of a point's program in the order
    /// [`Problem::build`] gives them, so that programs at one point that
    /// differ only by cuts added last share the rest of the work.
    pub(crate) fn program_at<'a>(
        &self,
        h: &'a [f64],
        x: &'a [Vec<f64>; 3],
        trust: Option<f64>,
        jerk: f64,
    ) -> Program<'a> {
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

        Program {
            lp,
            h,
            x,
            trust,
            k_j,
            cuts: 0,
        }
    }
}

/// A program at a point under construction ([`Problem::program_at`]).
#[derive(Clone)]
pub(crate) struct Program<'a> {
    lp: Lp,
    h: &'a [f64],
    x: &'a [Vec<f64>; 3],
    trust: Option<f64>,
    /// The jerk rows' scale ([`Problem::build`]).
    k_j: f64,
    /// Cuts added so far.
    cuts: usize,
}

impl Program<'_> {
    /// Cuts added so far.
    pub(crate) fn cuts(&self) -> usize {
        self.cuts
    }

    /// Its rows so far (those [`Program::finish`] adds come after them).
    pub(crate) fn marks(&self) -> Marks {
        self.lp.marks()
    }

    /// Adds the rows of `cuts`.
    pub(crate) fn add_cuts(&mut self, p: &Problem, cuts: &[Cut]) {
        let (h, x, trust, k_j) = (self.h, self.x, self.trust, self.k_j);
        let lp = &mut self.lp;
        let nv = p.nv();
        let nseg = p.nseg();
        let dh0 = 3 * nv;
        let s_col = dh0 + if trust.is_some() { nseg } else { 0 };
        let sigma = s_col + 1;
        let dh_col = |k: usize| trust.map(|_| dh0 + k);
        self.cuts += cuts.len();
        for cut in cuts {
            let mut row = RowBuilder::default();
            match cut.q {
                Limited::Torque => {
                    let f = p.motion_forms(h, x, cut.k, cut.u);
                    let Some(grad) = p.torque_gradient(&f, cut.j) else {
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
                        Limited::Travel => 0,
                        Limited::Velocity => 1,
                        Limited::Acceleration => 2,
                        _ => 3,
                    };
                    let f = p
                        .knots
                        .functional(&x[cut.j], cut.j, cut.k, cut.u, r, h[cut.k]);
                    row.add(1.0, &f, &x[cut.j], cut.j * nv, dh_col(cut.k));
                }
            }
            for sign in [1.0, -1.0] {
                if cut.side * sign < 0.0 {
                    continue;
                }
                let mut terms: Vec<(usize, f64)> =
                    row.terms.iter().map(|&(c, v)| (c, sign * v)).collect();
                if cut.q == Limited::Jerk {
                    terms.iter_mut().for_each(|t| t.1 *= k_j);
                    terms.push((s_col, -k_j));
                    lp.at_most(&terms, -sign * row.constant * k_j);
                } else if cut.q == Limited::Travel {
                    // q ≤ max and −q ≤ −min, a hair inside, elastic in σ
                    // relative to the span.
                    let Some((lo, hi, span)) = p.travel_of(cut.j) else {
                        continue;
                    };
                    let end = if sign > 0.0 { hi } else { -lo };
                    terms.push((sigma, -span));
                    lp.at_most(&terms, end - TRAVEL_MARGIN * span - sign * row.constant);
                } else {
                    let lim = p.limit(cut.q);
                    terms.push((sigma, -lim));
                    lp.at_most(&terms, lim - sign * row.constant);
                }
            }
        }
    }

    /// The program: its rows after the cuts'.
    pub(crate) fn finish(self, p: &Problem) -> Lp {
        let (h, trust) = (self.h, self.trust);
        let mut lp = self.lp;
        let nv = p.nv();
        let nseg = p.nseg();
        let dh0 = 3 * nv;
        let s_col = dh0 + if trust.is_some() { nseg } else { 0 };
        let sigma = s_col + 1;
        lp.at_most(&[(sigma, -1.0)], 0.0);

        if let Some(delta) = trust {
            let slack = p.total_time - h.iter().sum::<f64>();
            let all: Vec<(usize, f64)> = (0..nseg).map(|k| (dh0 + k, 1.0)).collect();
            lp.at_most(&all, slack.max(0.0));
            for (k, &hk) in h.iter().enumerate() {
                lp.at_most(&[(dh0 + k, 1.0)], (delta * hk).min(p.h_max - hk).max(0.0));
                lp.at_most(&[(dh0 + k, -1.0)], (delta * hk).min(hk - p.h_min).max(0.0));
            }
        }
        lp
    }
}

impl Problem {
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
}

/// Appends the cuts of `found` that `cuts` does not hold yet (same
/// quantity, joint, segment, normalised time and side).
pub(crate) fn add_new_cuts(cuts: &mut Vec<Cut>, found: &[Cut]) {
    for c in found {
        if !near_any(cuts, c, 1e-9) {
            cuts.push(*c);
        }
    }
}

/// Whether `cuts` holds one of `c`'s quantity, joint, segment and side
/// within `du` of its normalised time.
pub(crate) fn near_any(cuts: &[Cut], c: &Cut, du: f64) -> bool {
    cuts.iter().any(|d| {
        d.q == c.q && d.j == c.j && d.k == c.k && d.side == c.side && (d.u - c.u).abs() < du
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::search_tests::{example_problem, uneven_intervals};

    /// Markov–Lukács makes the program's jerk bound exact on whole
    /// segments: with jerk alone and h fixed, one solve's bound is the
    /// exact maximum of its point.
    #[test]
    fn one_solve_of_the_jerk_program_is_exact() {
        let p = example_problem("paper-case2.toml").relaxed();
        let h = uneven_intervals(&p);
        let x0 = p.zero_x();
        let lp = p.build(&h, &x0, &[], None, 1.0);
        let sol = p.solve(&lp).unwrap();
        let s_lp = sol[3 * p.nv()];
        let mut x = p.unpack(&sol);
        p.project(&h, &mut x);
        let exact = p.evaluate(&h, &x).jerk;
        assert!(
            (exact - s_lp).abs() <= 1e-6 * exact,
            "bound {s_lp}, exact {exact}"
        );
    }

    #[test]
    fn a_trust_region_keeps_the_intervals_within_it() {
        let p = example_problem("paper-case1.toml").relaxed();
        let h = uneven_intervals(&p);
        let x = p.evaluate(&h, &p.zero_x()).x;
        let delta = 0.1;
        let lp = p.build(&h, &x, &[], Some(delta), 1.0);
        let sol = p.solve(&lp).unwrap();
        let dh0 = 3 * p.nv();
        let total: f64 = (0..p.nseg()).map(|k| h[k] + sol[dh0 + k]).sum();
        assert!(total <= p.total_time * (1.0 + 1e-7), "{total}");
        for k in 0..p.nseg() {
            assert!(
                sol[dh0 + k].abs() <= delta * h[k] * (1.0 + 1e-6),
                "segment {k}"
            );
        }
    }

    #[test]
    fn new_cuts_are_added_once() {
        let cut = |k: usize, u: f64| Cut {
            q: Limited::Velocity,
            j: 0,
            k,
            u,
            side: 1.0,
        };
        let mut cuts = vec![cut(0, 0.5)];
        add_new_cuts(&mut cuts, &[cut(0, 0.5 + 1e-12), cut(1, 0.5), cut(1, 0.5)]);
        assert_eq!(cuts, vec![cut(0, 0.5), cut(1, 0.5)]);
        // The other side of a cut already held is a new cut.
        let below = Cut {
            side: -1.0,
            ..cut(0, 0.5)
        };
        add_new_cuts(&mut cuts, &[below]);
        assert_eq!(cuts, vec![cut(0, 0.5), cut(1, 0.5), below]);
        // Near: the same limit, joint, segment and side within the distance.
        assert!(near_any(&cuts, &cut(1, 0.5005), 1e-3));
        assert!(!near_any(&cuts, &cut(1, 0.502), 1e-3));
        assert!(!near_any(&cuts, &cut(2, 0.5), 1e-3));
        assert!(!near_any(&[below], &cut(0, 0.5), 1e-3));
    }

    /// A cut bounds its extremum's side alone (one row); travel both.
    #[test]
    fn a_cut_holds_one_row_for_its_side() {
        let p = example_problem("paper-case2.toml");
        let h = uneven_intervals(&p);
        let x = p.zero_x();
        let rows = |cuts: &[Cut]| {
            let mut program = p.program_at(&h, &x, None, 1.0);
            program.add_cuts(&p, cuts);
            program.finish(&p).rows()
        };
        let base = rows(&[]);
        let cut = Cut {
            q: Limited::Acceleration,
            j: 1,
            k: 2,
            u: 0.25,
            side: -1.0,
        };
        assert_eq!(rows(&[cut]), base + 1);
        assert_eq!(rows(&[cut, Cut { side: 1.0, ..cut }]), base + 2);
    }
}
