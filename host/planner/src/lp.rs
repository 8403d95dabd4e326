//! A small sparse linear program with optional second-order cones, solved by
//! Clarabel (interior point).

use clarabel::algebra::CscMatrix;
use clarabel::solver::{
    DefaultSettingsBuilder, DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// minimise costᵀx subject to equality rows (Σ a x = b) and inequality rows (Σ a x ≤ b).
#[derive(Debug, Default)]
pub struct Lp {
    pub vars: usize,
    pub cost: Vec<f64>,
    eq: Rows,
    ineq: Rows,
    /// Three rows per second-order cone: (t, a, b) with ‖(a, b)‖ ≤ t.
    soc: Rows,
    /// Relative accuracy asked of the solver.
    pub tolerance: f64,
    /// Iterative refinement of each KKT solve (off trades accuracy for speed).
    pub refine: bool,
}

#[derive(Debug, Default)]
struct Rows {
    row: Vec<usize>,
    col: Vec<usize>,
    val: Vec<f64>,
    rhs: Vec<f64>,
}

impl Rows {
    fn push(&mut self, terms: &[(usize, f64)], rhs: f64) {
        let r = self.rhs.len();
        for &(c, v) in terms {
            if v != 0.0 {
                self.row.push(r);
                self.col.push(c);
                self.val.push(v);
            }
        }
        self.rhs.push(rhs);
    }
}

/// The LP has no solution, the solver gave up, or the search was cancelled.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LpFailure {
    Status(SolverStatus),
    Cancelled,
}

impl Lp {
    pub fn new(vars: usize) -> Self {
        Self {
            vars,
            cost: vec![0.0; vars],
            tolerance: 1e-11,
            refine: true,
            ..Self::default()
        }
    }

    pub fn equal(&mut self, terms: &[(usize, f64)], rhs: f64) {
        self.eq.push(terms, rhs);
    }

    pub fn at_most(&mut self, terms: &[(usize, f64)], rhs: f64) {
        self.ineq.push(terms, rhs);
    }

    /// ‖(L₂, L₃)‖ ≤ L₁ for affine L_i = terms_i·x + constant_i.
    pub fn second_order_cone(&mut self, rows: [(&[(usize, f64)], f64); 3]) {
        for (terms, constant) in rows {
            // Clarabel's cone rows are b − A x: A = −terms, b = constant.
            let neg: Vec<(usize, f64)> = terms.iter().map(|&(c, v)| (c, -v)).collect();
            self.soc.push(&neg, constant);
        }
    }

    pub fn rows(&self) -> usize {
        self.eq.rhs.len() + self.ineq.rhs.len() + self.soc.rhs.len()
    }

    /// Triplets of the constraint matrix in the solver's row order.
    fn triplets(&self) -> (Vec<usize>, Vec<usize>, Vec<f64>) {
        let neq = self.eq.rhs.len();
        let nineq = self.ineq.rhs.len();
        let rows = self
            .eq
            .row
            .iter()
            .copied()
            .chain(self.ineq.row.iter().map(|r| r + neq))
            .chain(self.soc.row.iter().map(|r| r + neq + nineq))
            .collect();
        let cols = [&self.eq, &self.ineq, &self.soc]
            .iter()
            .flat_map(|r| r.col.iter().copied())
            .collect();
        let vals = [&self.eq, &self.ineq, &self.soc]
            .iter()
            .flat_map(|r| r.val.iter().copied())
            .collect();
        (rows, cols, vals)
    }

    /// Solves; returns the primal solution.
    pub fn solve(&self) -> Result<Vec<f64>, LpFailure> {
        let neq = self.eq.rhs.len();
        let nineq = self.ineq.rhs.len();
        let m = self.rows();
        let (rows, cols, vals) = self.triplets();
        let a = csc(m, self.vars, rows, cols, vals);
        let b: Vec<f64> = [&self.eq, &self.ineq, &self.soc]
            .iter()
            .flat_map(|r| r.rhs.iter().copied())
            .collect();
        let p = CscMatrix::zeros((self.vars, self.vars));
        let mut cones = vec![
            SupportedConeT::ZeroConeT(neq),
            SupportedConeT::NonnegativeConeT(nineq),
        ];
        cones.extend((0..self.soc.rhs.len() / 3).map(|_| SupportedConeT::SecondOrderConeT(3)));
        let settings = DefaultSettingsBuilder::default()
            .verbose(false)
            .presolve_enable(false)
            .tol_gap_abs(self.tolerance)
            .tol_gap_rel(self.tolerance)
            .tol_feas(self.tolerance)
            .max_iter(200)
            .iterative_refinement_enable(self.refine)
            .build()
            .map_err(|_| LpFailure::Status(SolverStatus::NumericalError))?;
        let mut solver = DefaultSolver::new(&p, &self.cost, &a, &b, &cones, settings)
            .map_err(|_| LpFailure::Status(SolverStatus::NumericalError))?;
        solver.solve();
        if std::env::var_os("TRIQUINT_LP_DEBUG").is_some() {
            eprintln!(
                "lp: {} vars {} rows, {} iterations, {:.3} ms, status {:?}",
                self.vars,
                m,
                solver.solution.iterations,
                solver.solution.solve_time * 1e3,
                solver.solution.status
            );
        }
        match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => Ok(solver.solution.x.clone()),
            other => Err(LpFailure::Status(other)),
        }
    }
}

/// The constraint matrix in compressed columns, in linear time: the
/// triplets come in ascending rows, so one counting pass by column keeps
/// each column's rows ascending (Clarabel's constructor sorts them, a
/// tenth of a small program's solve); repeated entries are summed in
/// order, as it does.
fn csc(m: usize, n: usize, rows: Vec<usize>, cols: Vec<usize>, vals: Vec<f64>) -> CscMatrix<f64> {
    if !rows.windows(2).all(|w| w[0] <= w[1]) {
        return CscMatrix::new_from_triplets(m, n, rows, cols, vals);
    }
    let mut start = vec![0usize; n + 1];
    for &c in &cols {
        start[c + 1] += 1;
    }
    for c in 0..n {
        start[c + 1] += start[c];
    }
    let mut next = start.clone();
    let mut rowval = vec![0; vals.len()];
    let mut nzval = vec![0.0; vals.len()];
    for ((&r, &c), &v) in rows.iter().zip(&cols).zip(&vals) {
        rowval[next[c]] = r;
        nzval[next[c]] = v;
        next[c] += 1;
    }
    let mut colptr = vec![0usize; n + 1];
    let mut w = 0;
    for c in 0..n {
        let first = w;
        for i in start[c]..start[c + 1] {
            if w > first && rowval[w - 1] == rowval[i] {
                nzval[w - 1] += nzval[i];
            } else {
                rowval[w] = rowval[i];
                nzval[w] = nzval[i];
                w += 1;
            }
        }
        colptr[c + 1] = w;
    }
    rowval.truncate(w);
    nzval.truncate(w);
    CscMatrix::new(m, n, colptr, rowval, nzval)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn columns_equal_clarabels_own_constructor() {
        // Ascending rows, repeated entries, empty columns and rows.
        let rows = vec![0, 0, 0, 1, 3, 3, 3, 4];
        let cols = vec![2, 0, 2, 1, 0, 4, 0, 2];
        let vals = vec![1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0];
        let ours = csc(5, 6, rows.clone(), cols.clone(), vals.clone());
        let theirs = CscMatrix::new_from_triplets(5, 6, rows, cols, vals);
        assert_eq!(ours.colptr, theirs.colptr);
        assert_eq!(ours.rowval, theirs.rowval);
        assert_eq!(ours.nzval, theirs.nzval);
        assert_eq!(ours.nzval, vec![2.0, 12.0, 4.0, 4.0, 8.0, 6.0]);
    }

    #[test]
    fn small_lp() {
        // min -x - y, x + 2y ≤ 4, 3x + y ≤ 6, x = y... → x = y = 4/3.
        let mut lp = Lp::new(2);
        lp.cost = vec![-1.0, -1.0];
        lp.at_most(&[(0, 1.0), (1, 2.0)], 4.0);
        lp.at_most(&[(0, 3.0), (1, 1.0)], 6.0);
        lp.equal(&[(0, 1.0), (1, -1.0)], 0.0);
        let x = lp.solve().unwrap();
        assert!((x[0] - 4.0 / 3.0).abs() < 1e-8 && (x[1] - 4.0 / 3.0).abs() < 1e-8);
        let mut bad = Lp::new(1);
        bad.at_most(&[(0, 1.0)], -1.0);
        bad.at_most(&[(0, -1.0)], -1.0);
        assert!(bad.solve().is_err());
    }
}
