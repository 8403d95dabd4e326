//! The jerk-only inner problem at fixed intervals without an interior-point
//! solve.
//!
//! With h fixed and only jerk limited, the three joints are independent:
//! each is min s over its knot derivatives x_j subject to the C3 and
//! end-jerk equalities E x_j = f and |J_k(u)| ≤ s on every segment, and the
//! problem's optimum is the largest of the three. Per joint the equalities
//! are eliminated once (x_j = x_p + N z, N an orthonormal basis of E's null
//! space, n − 4 columns for n knots), which leaves a linear Chebyshev
//! problem in (z, s): min s subject to ±(a_i·z + b_i) ≤ s at cut points
//! (k, u). It is solved by a primal active-set method (dense, exact at its
//! vertex), and cut points are added at each segment's exact maximum of
//! |J_k| (a quadratic in u: at u = 0, 1 or its vertex) until the LP's s
//! equals the exact maximum to 1e-9: the LP bound is a lower bound and the
//! exact maximum of its point an upper bound, so the answer is certified.
//! Anything unexpected (rank loss, no progress, too many iterations) returns
//! None and the caller falls back to the interior-point solve.

// Index loops mirror the maths.
#![allow(clippy::needless_range_loop)]

use nalgebra::{DMatrix, DVector, Dyn, LU};

use crate::problem::Problem;

/// Largest number of knots solved here (dense algebra, a QR a pivot:
/// beyond it the interior-point solve of the banded problem is the
/// cheaper; docs/planner-speed.md has where the two cross).
pub(crate) const MAX_KNOTS: usize = 20;
/// Relative gap between the LP bound and the exact maximum that ends the
/// cuts: the interior-point solves' accuracy. The gap falls about fourfold a
/// round, so a tighter gap costs rounds for no change the plan keeps.
const GAP: f64 = 1e-9;
/// Cutting-plane rounds at most.
const ROUNDS: usize = 80;

/// One cut of one joint: ±(a·z + b) ≤ s in the reduced variables.
/// As a row of G in y = (z, s): (±a, −1) · y ≤ ∓b = rhs.
struct Row {
    g: DVector<f64>,
    rhs: f64,
    norm: f64,
}

impl Row {
    /// sign·(a·z + b) ≤ s.
    fn new(a: &DVector<f64>, b: f64, sign: f64) -> Row {
        let d = a.len();
        let g = DVector::from_fn(d + 1, |c, _| if c < d { sign * a[c] } else { -1.0 });
        Row {
            norm: g.norm(),
            g,
            rhs: -sign * b,
        }
    }
}

impl Problem {
    /// Exact jerk-only optimum at fixed `h` per joint, from `x0` (whose
    /// C3 projection is the starting point). None when it does not apply
    /// or does not certify; the caller then solves the program as before.
    pub(crate) fn jerk_only_direct(&self, h: &[f64], x0: &[Vec<f64>; 3]) -> Option<[Vec<f64>; 3]> {
        let n = self.knots.len();
        if !(4..=MAX_KNOTS).contains(&n) || !self.jerk_only {
            return None;
        }
        let mut x = x0.clone();
        self.project(h, &mut x);
        // The conditions' coefficients do not depend on the joint (only
        // their constants do): one null space serves the three.
        let basis = self.jerk_null_space(h)?;
        let mut out: [Vec<f64>; 3] = Default::default();
        for j in 0..3 {
            out[j] = self.joint_direct(h, j, &x[j], &basis)?;
        }
        self.project(h, &mut out);
        Some(out)
    }

    /// An orthonormal basis of the null space of E (the C3 and end-jerk
    /// rows) at intervals `h`, from the full QR of Eᵀ padded to a square
    /// matrix; None when E loses rank.
    fn jerk_null_space(&self, h: &[f64]) -> Option<DMatrix<f64>> {
        let nv = self.knots.vars();
        let zero = vec![0.0; nv];
        let coefficients = |k: usize, u: f64| {
            let f = self.knots.functional(&zero, 0, k, u, 3, h[k]);
            let mut a = DVector::zeros(nv);
            for &(v, c) in f.dx() {
                a[v] += c;
            }
            a
        };
        let conds = self.jerk_conditions();
        let m = conds.len();
        if nv < m {
            return None;
        }
        let mut et = DMatrix::<f64>::zeros(nv, nv);
        for (r, (a, b)) in conds.iter().enumerate() {
            let mut row = coefficients(a.0, a.1);
            if let Some((k, u)) = b {
                row -= &coefficients(*k, *u);
            }
            et.set_column(r, &row);
        }
        let scale = et.amax().max(f64::MIN_POSITIVE);
        let qr = et.qr();
        let r = qr.r();
        for i in 0..m {
            if r[(i, i)].abs() <= 1e-10 * scale {
                return None;
            }
        }
        Some(qr.q().columns(m, nv - m).into_owned())
    }

    /// One joint's min-max jerk from the C3-feasible `xp`, in the
    /// conditions' null space `basis`.
    fn joint_direct(
        &self,
        h: &[f64],
        j: usize,
        xp: &[f64],
        basis: &DMatrix<f64>,
    ) -> Option<Vec<f64>> {
        let nv = self.knots.vars();
        let nseg = self.knots.segments();
        let zero = vec![0.0; nv];
        // Jerk of joint j at (k, u): coefficients in x and the constant.
        let form = |k: usize, u: f64| {
            let f = self.knots.functional(&zero, j, k, u, 3, h[k]);
            let mut a = DVector::zeros(nv);
            for &(v, c) in f.dx() {
                a[v] += c;
            }
            (a, f.value)
        };
        // The forms at u = 0, ½ and 1 of every segment, which the first
        // cuts and every round's exact maxima use.
        const NODES: [f64; 3] = [0.0, 0.5, 1.0];
        let nodes: Vec<[(DVector<f64>, f64); 3]> =
            (0..nseg).map(|k| NODES.map(|u| form(k, u))).collect();
        let form_at = |k: usize, u: f64| match NODES.iter().position(|&v| v == u) {
            Some(i) => nodes[k][i].clone(),
            None => form(k, u),
        };
        let d = basis.ncols();
        let xp = DVector::from_column_slice(xp);
        let mut rows: Vec<Row> = Vec::new();
        let cut_at = |k: usize, u: f64, rows: &mut Vec<Row>| {
            let (a, c) = form_at(k, u);
            let ar = basis.tr_mul(&a);
            let b = a.dot(&xp) + c;
            rows.extend([1.0, -1.0].map(|sign| Row::new(&ar, b, sign)));
        };
        // Knot jerks (u = 0 of every segment but the first, whose is zero)
        // and each segment's middle.
        for k in 0..nseg {
            if k > 0 {
                cut_at(k, 0.0, &mut rows);
            }
            cut_at(k, 0.5, &mut rows);
        }
        // The jerk quadratic of segment k at x: (J(0), c1, c2).
        let quad = |k: usize, x: &DVector<f64>| {
            let at = |i: usize| {
                let (a, c) = &nodes[k][i];
                a.dot(x) + c
            };
            let (j0, jm, j1) = (at(0), at(1), at(2));
            (
                j0,
                -3.0 * j0 + 4.0 * jm - j1,
                2.0 * j0 - 4.0 * jm + 2.0 * j1,
            )
        };
        // Exact max |J| on segment k, and its interior maximiser if any.
        let seg_max = |k: usize, x: &DVector<f64>| {
            let (j0, c1, c2) = quad(k, x);
            let j1 = j0 + c1 + c2;
            let mut best = (j0.abs().max(j1.abs()), None);
            if c2 != 0.0 {
                let u = -c1 / (2.0 * c2);
                if u > 0.0 && u < 1.0 {
                    let v = (j0 + c1 * u + c2 * u * u).abs();
                    if v > best.0 {
                        best = (v, Some(u));
                    }
                }
            }
            best
        };
        let mut z = DVector::zeros(d);
        // Interior cut points added per segment, in order (for extrapolation).
        let mut history: Vec<Vec<f64>> = vec![Vec::new(); nseg];
        // The optimal vertex's rows: after a round's new cuts, the dual
        // simplex restarts from it (a few pivots, where the primal method
        // walks up from one active row again).
        let mut vertex: Option<Vertex> = None;
        for _ in 0..ROUNDS {
            let warm = vertex.take().and_then(|b| dual_simplex(&rows, b));
            let (z_lp, s_lp, at) = match warm {
                Some(w) => w,
                None => chebyshev(&rows, z)?,
            };
            vertex = at;
            z = z_lp;
            let x = &xp + basis * &z;
            let mut worst: f64 = 0.0;
            let mut new_cuts = Vec::new();
            for k in 0..nseg {
                let (v, u) = seg_max(k, &x);
                worst = worst.max(v);
                if let Some(u) = u
                    && v > s_lp * (1.0 + 0.1 * GAP)
                {
                    new_cuts.push((k, u));
                }
            }
            if worst <= s_lp * (1.0 + GAP) + 1e-300 {
                return Some(x.iter().copied().collect());
            }
            if new_cuts.is_empty() {
                return None;
            }
            for (k, u) in new_cuts {
                cut_at(k, u, &mut rows);
                // The maximiser of a binding segment converges only
                // linearly (the LP's vertex bounces between the nearest
                // cuts, the gap falling by about 4 a round): a cut at the
                // Aitken extrapolation of its last three positions as well
                // saves about a third of the rounds.
                let past = &mut history[k];
                past.push(u);
                if let [.., u1, u2, u3] = past[..] {
                    let (d1, d2) = (u2 - u1, u3 - u2);
                    let u_lim = u3 - d2 * d2 / (d2 - d1);
                    if u_lim.is_finite() && u_lim > 0.0 && u_lim < 1.0 && (u_lim - u3).abs() > 1e-15
                    {
                        cut_at(k, u_lim, &mut rows);
                    }
                }
            }
        }
        None
    }
}

/// An optimal (z, s), and its vertex when it is one.
type Optimum = (DVector<f64>, f64, Option<Vertex>);

/// An optimal vertex: its rows, and the dual simplex's work there when it
/// found it (the next rounds' start, which only the new rows change).
struct Vertex {
    basis: Vec<usize>,
    at: Option<Factored>,
}

/// G_B's transpose factored, the vertex y and its multipliers λ, and how
/// many rows were priced at y (none of them enters).
struct Factored {
    gbt: LU<f64, Dyn, Dyn>,
    y: DVector<f64>,
    lambda: DVector<f64>,
    priced: usize,
}

/// min s subject to σ_i(a_i·z + b_i) ≤ s by the dual simplex method from
/// `vertex`, an optimal vertex before rows were added: its
/// multipliers stay feasible (≥ 0, summing to one), the most violated row
/// enters and the ratio test picks the row that leaves. s at any such
/// basis is a lower bound, so the exact check after the LP still
/// certifies. None on anything unexpected (the caller solves from scratch).
fn dual_simplex(rows: &[Row], vertex: Vertex) -> Option<Optimum> {
    let Vertex { mut basis, at } = vertex;
    let mut known = at;
    let dim = rows.first()?.g.len();
    if basis.len() != dim {
        return None;
    }
    let mut cost = DVector::zeros(dim);
    cost[dim - 1] = 1.0;
    let mut in_basis = vec![false; rows.len()];
    for &b in &basis {
        *in_basis.get_mut(b)? = true;
    }
    for _ in 0..(4 * dim + 20) {
        let (gbt, y, lambda, priced) = match known.take() {
            Some(f) => (f.gbt, f.y, f.lambda, f.priced),
            None => {
                let gb = DMatrix::from_fn(dim, dim, |r, c| rows[basis[r]].g[c]);
                let y = gb
                    .clone()
                    .lu()
                    .solve(&DVector::from_fn(dim, |r, _| rows[basis[r]].rhs))?;
                let gbt = gb.transpose().lu();
                let lambda = gbt.solve(&-&cost)?;
                (gbt, y, lambda, 0)
            }
        };
        if lambda.iter().any(|&l| l.is_nan() || l < -1e-12) {
            return None;
        }
        let scale = y.amax().max(1e-300);
        let mut enter: Option<(usize, f64)> = None;
        for (i, row) in rows.iter().enumerate().skip(priced) {
            if in_basis[i] {
                continue;
            }
            let v = (row.g.dot(&y) - row.rhs) / row.norm;
            if v > 1e-14 * scale && enter.is_none_or(|e| v > e.1) {
                enter = Some((i, v));
            }
        }
        let Some((r, _)) = enter else {
            let d = dim - 1;
            let (z, s) = (y.rows(0, d).into_owned(), y[d]);
            let at = Factored {
                gbt,
                y,
                lambda,
                priced: rows.len(),
            };
            return Some((
                z,
                s,
                Some(Vertex {
                    basis,
                    at: Some(at),
                }),
            ));
        };
        // λ_B − t w with G_Bᵀ w = G_rᵀ: the first multiplier to reach zero leaves.
        let w = gbt.solve(&rows[r].g)?;
        let mut leave: Option<(usize, f64)> = None;
        for k in 0..dim {
            if w[k] > 1e-12 * w.amax() {
                let t = lambda[k].max(0.0) / w[k];
                if leave.is_none_or(|l| t < l.1) {
                    leave = Some((k, t));
                }
            }
        }
        let out = std::mem::replace(&mut basis[leave?.0], r);
        in_basis[out] = false;
        in_basis[r] = true;
    }
    None
}

/// min s subject to σ_i(a_i·z + b_i) ≤ s, from `z`: a primal active-set
/// method. Returns (z, s) at an optimal vertex, or None.
fn chebyshev(rows: &[Row], z: DVector<f64>) -> Option<Optimum> {
    let d = z.len();
    let dim = d + 1;
    let m = rows.len();
    let gm = DMatrix::<f64>::from_fn(m, dim, |i, c| rows[i].g[c]);
    let g = DVector::<f64>::from_fn(m, |i, _| rows[i].rhs);
    let norms: Vec<f64> = rows.iter().map(|r| r.norm).collect();
    let mut y = DVector::zeros(dim);
    y.rows_mut(0, d).copy_from(&z);
    // s at the largest σ(a·z + b): feasible, and that row active.
    let lhs = &gm * &y;
    let (first, s0) = (0..m)
        .map(|i| (i, lhs[i] - g[i]))
        .max_by(|a, b| a.1.total_cmp(&b.1))?;
    y[d] = s0;
    let mut active: Vec<usize> = vec![first];
    let mut is_active = vec![false; m];
    is_active[first] = true;
    let mut cost = DVector::zeros(dim);
    cost[d] = 1.0;
    let mut last_dropped = None;
    for _ in 0..(50 * dim + 50) {
        let w = active.len();
        let mut at = DMatrix::zeros(dim, w);
        for (c, &i) in active.iter().enumerate() {
            at.set_column(c, &gm.row(i).transpose());
        }
        let qr = at.qr();
        let r = qr.r();
        // The row just added nearly depends on the others (cuts a hair
        // apart): it is set aside (is_active stays set, so the ratio test
        // skips it); the exact check after the LP catches what that misses.
        if (0..w).any(|i| r[(i, i)].abs() <= 1e-12 * norms[active[i]]) {
            if w == 1 {
                return None;
            }
            active.pop();
            continue;
        }
        let q = qr.q();
        // Steepest descent within the active face.
        let p = -(&cost - &q * q.tr_mul(&cost));
        let pn = p.norm();
        if pn <= 1e-11 {
            // Multipliers: Aᵀ λ = −c.
            let rhs = -q.tr_mul(&cost);
            let lambda = r.solve_upper_triangular(&rhs)?;
            let (worst, lmin) = lambda
                .iter()
                .copied()
                .enumerate()
                .min_by(|a, b| a.1.total_cmp(&b.1))?;
            if lmin >= -1e-12 {
                let vertex = (w == dim).then_some(Vertex {
                    basis: active,
                    at: None,
                });
                return Some((y.rows(0, d).into_owned(), y[d], vertex));
            }
            let i = active.remove(worst);
            is_active[i] = false;
            last_dropped = Some(i);
            continue;
        }
        // Ratio test over the inactive constraints.
        let gp = &gm * &p;
        let gy = &gm * &y;
        let mut step: Option<(f64, f64, usize)> = None;
        for i in 0..m {
            if is_active[i] || Some(i) == last_dropped {
                continue;
            }
            let ap = gp[i];
            if ap <= 1e-12 * norms[i] * pn {
                continue;
            }
            let alpha = (g[i] - gy[i]).max(0.0) / ap;
            let steep = ap / norms[i];
            let better = match step {
                None => true,
                Some((best, bs, _)) => alpha < best || (alpha == best && steep > bs),
            };
            if better {
                step = Some((alpha, steep, i));
            }
        }
        let (alpha, _, i) = step?;
        y += &p * alpha;
        active.push(i);
        is_active[i] = true;
        last_dropped = None;
    }
    None
}

#[cfg(test)]
mod tests {
    use std::path::Path;
    use std::sync::Arc;

    use super::*;
    use crate::Job;
    use crate::run_state::RunState;
    use crate::search::SplitMix;

    /// ±(a·z + b) ≤ s for random a, b in d reduced variables.
    fn random_rows(rng: &mut SplitMix, d: usize, pairs: usize, rows: &mut Vec<Row>) {
        for _ in 0..pairs {
            let a = DVector::from_fn(d, |_, _| 2.0 * rng.next_f64() - 1.0);
            let b = 2.0 * rng.next_f64() - 1.0;
            rows.extend([1.0, -1.0].map(|sign| Row::new(&a, b, sign)));
        }
    }

    #[test]
    fn the_dual_simplex_after_new_rows_equals_a_cold_solve() {
        let mut rng = SplitMix(7);
        for case in 0..40 {
            let d = 2 + case % 7;
            let mut rows = Vec::new();
            random_rows(&mut rng, d, 2 * d + 2, &mut rows);
            let (_, s0, vertex) = chebyshev(&rows, DVector::zeros(d)).unwrap();
            let vertex = vertex.expect("a vertex");
            random_rows(&mut rng, d, 1 + case % 4, &mut rows);
            let (z_warm, s_warm, _) = dual_simplex(&rows, vertex).expect("warm solve");
            let (_, s_cold, _) = chebyshev(&rows, DVector::zeros(d)).unwrap();
            assert!(s_warm >= s0 - 1e-12, "case {case}: rows added, bound fell");
            assert!(
                (s_warm - s_cold).abs() <= 1e-10 * s_cold.abs().max(1.0),
                "case {case}: warm {s_warm} cold {s_cold}"
            );
            let y = DVector::from_fn(d + 1, |c, _| if c < d { z_warm[c] } else { s_warm });
            for r in &rows {
                assert!(
                    r.g.dot(&y) - r.rhs <= 1e-10 * r.norm,
                    "case {case}: infeasible"
                );
            }
        }
    }

    #[test]
    fn the_direct_solve_equals_the_interior_point_solve_on_case_2() {
        let job = Job::load(
            &Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-case2.toml"),
        )
        .unwrap();
        let p = crate::planning::job_problem(&job, &Arc::new(RunState::new(None)))
            .unwrap()
            .relaxed();
        let n = p.knots.segments();
        // Uneven intervals, so that interior jerk maxima need their cuts.
        let h: Vec<f64> = (0..n).map(|k| 0.3 + 0.05 * (k % 3) as f64).collect();
        let direct = p.jerk_only_direct(&h, &p.zero_x()).expect("direct solve");
        let exact = p.evaluate(&h, &direct).jerk;
        let ipm = p
            .inner(&h, &p.zero_x(), crate::inner::Method::CuttingPlanes, 25)
            .unwrap()
            .jerk;
        assert!(
            (exact - ipm).abs() <= 1e-8 * ipm,
            "direct {exact} interior point {ipm}"
        );
    }
}
