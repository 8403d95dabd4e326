//! A small sparse linear program with optional second-order cones, solved by
//! Clarabel (interior point).

use std::sync::Mutex;

use clarabel::algebra::CscMatrix;
use clarabel::solver::traits::ProblemData;
use clarabel::solver::{
    DefaultEquilibrationData, DefaultProblemData, DefaultSettings, DefaultSettingsBuilder,
    DefaultSolver, IPSolver, SolverStatus, SupportedConeT,
};

/// minimise costᵀx subject to equality rows (Σ a x = b) and inequality rows (Σ a x ≤ b).
#[derive(Clone, Debug, Default)]
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

#[derive(Clone, Debug, Default)]
struct Rows {
    row: Vec<usize>,
    col: Vec<usize>,
    val: Vec<f64>,
    rhs: Vec<f64>,
}

impl Rows {
    /// A y − b of each of the first `upto` rows, appended to `out`.
    fn residuals(&self, y: &[f64], upto: usize, out: &mut Vec<f64>) {
        let first = out.len();
        out.extend(self.rhs[..upto].iter().map(|b| -b));
        for ((&r, &c), &v) in self.row.iter().zip(&self.col).zip(&self.val) {
            if r < upto {
                out[first + r] += v * y[c];
            }
        }
    }

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

/// How many rows each block of a program holds (equalities,
/// inequalities, cone rows): the rows a program had before more were added.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Marks([usize; 3]);

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

    /// Its rows so far, block by block.
    pub fn marks(&self) -> Marks {
        Marks([self.eq.rhs.len(), self.ineq.rhs.len(), self.soc.rhs.len()])
    }

    /// A y − b of the rows before `upto`, block by block (for a cone row,
    /// minus its slack).
    pub fn residuals(&self, y: &[f64], upto: Marks) -> Vec<f64> {
        let mut out = Vec::with_capacity(upto.0.iter().sum());
        for (rows, n) in [&self.eq, &self.ineq, &self.soc].into_iter().zip(upto.0) {
            rows.residuals(y, n, &mut out);
        }
        out
    }

    /// Moves the right-hand side of the rows before `upto` by `shift`
    /// (in [`Lp::residuals`]' order): b − shift.
    pub fn shift_rhs(&mut self, upto: Marks, shift: &[f64]) {
        let mut s = shift.iter();
        for (rows, n) in [&mut self.eq, &mut self.ineq, &mut self.soc]
            .into_iter()
            .zip(upto.0)
        {
            for (b, d) in rows.rhs[..n].iter_mut().zip(&mut s) {
                *b -= d;
            }
        }
    }

    pub fn rows(&self) -> usize {
        self.eq.rhs.len() + self.ineq.rhs.len() + self.soc.rhs.len()
    }

    /// The constraint matrix in the solver's row order (equalities,
    /// inequalities, cones) in compressed columns, from each block's
    /// triplets without gathering them first.
    fn matrix(&self) -> CscMatrix<f64> {
        let neq = self.eq.rhs.len();
        let nineq = self.ineq.rhs.len();
        fn block(r: &Rows, offset: usize) -> Triplets<'_> {
            Triplets {
                rows: &r.row,
                offset,
                cols: &r.col,
                vals: &r.val,
            }
        }
        compressed(
            self.rows(),
            self.vars,
            &[
                block(&self.eq, 0),
                block(&self.ineq, neq),
                block(&self.soc, neq + nineq),
            ],
        )
    }

    /// Solves; returns the primal solution.
    pub fn solve(&self) -> Result<Vec<f64>, LpFailure> {
        self.solve_keeping(true)
    }

    /// [`Lp::solve`]; `keep` lets it take a kept solver of its shape and
    /// keep its own (the same answer either way).
    fn solve_keeping(&self, keep: bool) -> Result<Vec<f64>, LpFailure> {
        let neq = self.eq.rhs.len();
        let nineq = self.ineq.rhs.len();
        let m = self.rows();
        let a = self.matrix();
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
        let shape = Shape {
            vars: self.vars,
            cones: [neq, nineq, self.soc.rhs.len()],
            colptr: a.colptr.clone(),
            rowval: a.rowval.clone(),
            tolerance: self.tolerance.to_bits(),
            refine: self.refine,
        };
        let kept = keep
            .then(|| take_solver(&shape))
            .flatten()
            .and_then(|mut solver| {
                reload(&mut solver, &p, &self.cost, &a, &b, &cones, &settings).map(|()| solver)
            });
        let mut solver = match kept {
            Some(solver) => solver,
            None => DefaultSolver::new(&p, &self.cost, &a, &b, &cones, settings)
                .map_err(|_| LpFailure::Status(SolverStatus::NumericalError))?,
        };
        solver.solve();
        if std::env::var_os("TRIQUINT_LP_DEBUG").is_some() {
            eprintln!(
                "lp: {} vars {} rows, {} iterations, {:.3} ms, status {:?}, KKT {} and factor {} nonzeros",
                self.vars,
                m,
                solver.solution.iterations,
                solver.solution.solve_time * 1e3,
                solver.solution.status,
                solver.info.linsolver.nnzA,
                solver.info.linsolver.nnzL
            );
        }
        match solver.solution.status {
            SolverStatus::Solved | SolverStatus::AlmostSolved => {
                let x = solver.solution.x.clone();
                if keep {
                    keep_solver(shape, solver);
                }
                Ok(x)
            }
            other => Err(LpFailure::Status(other)),
        }
    }
}

/// What a solver's set-up depends on beyond the program's values: the
/// constraint matrix's pattern, the cones and the settings. Programs of one
/// shape have one KKT pattern, so one AMD ordering and symbolic
/// factorisation (the search's step programs repeat a few shapes).
#[derive(PartialEq, Eq)]
struct Shape {
    vars: usize,
    /// Rows of the zero cone, the nonnegative cone and the 3-D cones.
    cones: [usize; 3],
    colptr: Vec<usize>,
    rowval: Vec<usize>,
    tolerance: u64,
    refine: bool,
}

/// Solvers kept after a successful solve for the next program of the same shape,
/// the most recently used last, with their KKT and factor sizes.
static KEPT: Mutex<Vec<(Shape, DefaultSolver<f64>, usize)>> = Mutex::new(Vec::new());
/// At most this many solvers are kept…
const KEPT_SOLVERS: usize = 16;
/// …holding at most this many KKT and factor nonzeros together: long
/// paths' programs, whose set-up is a small share of their solve, are not
/// kept.
const KEPT_NONZEROS: usize = 400_000;

fn take_solver(shape: &Shape) -> Option<DefaultSolver<f64>> {
    let mut kept = KEPT.lock().ok()?;
    let i = kept.iter().rposition(|(s, ..)| s == shape)?;
    Some(kept.remove(i).1)
}

fn keep_solver(shape: Shape, solver: DefaultSolver<f64>) {
    let size = solver.info.linsolver.nnzA + solver.info.linsolver.nnzL;
    let Ok(mut kept) = KEPT.lock() else {
        return;
    };
    if size > KEPT_NONZEROS {
        return;
    }
    kept.push((shape, solver, size));
    while kept.len() > KEPT_SOLVERS || kept.iter().map(|k| k.2).sum::<usize>() > KEPT_NONZEROS {
        kept.remove(0);
    }
}

/// Loads a program into a solver set up for one of the same shape (None if
/// it refuses), so that it solves as a new solver would, bit for bit: the data equilibrated
/// afresh (Clarabel's own update keeps the first program's scaling) and
/// the scaled matrix's values written into its KKT matrix, whose ordering
/// and symbolic factorisation depend only on the pattern. Everything else
/// the solve starts from is set by its initial point.
fn reload(
    solver: &mut DefaultSolver<f64>,
    p: &CscMatrix<f64>,
    q: &[f64],
    a: &CscMatrix<f64>,
    b: &[f64],
    cones: &[SupportedConeT<f64>],
    settings: &DefaultSettings<f64>,
) -> Option<()> {
    let mut data = DefaultProblemData::new(p, q, a, b, cones, settings);
    data.equilibrate(&solver.cones, settings);
    // The values are already scaled: written through an identity scaling
    // (a product with ones is exact), then the scaling put back for the
    // solve's residuals and its unscaled answer.
    let scaling = std::mem::replace(
        &mut data.equilibration,
        DefaultEquilibrationData::new(data.n, data.m),
    );
    let values = data.A.nzval.clone();
    solver.data = data;
    solver.update_A(&values).ok()?;
    solver.data.equilibration = scaling;
    Some(())
}

/// Triplets in compressed columns as Clarabel's constructor makes them
/// ([`compressed`] when their rows ascend).
#[cfg(test)]
fn csc(m: usize, n: usize, rows: Vec<usize>, cols: Vec<usize>, vals: Vec<f64>) -> CscMatrix<f64> {
    if !rows.windows(2).all(|w| w[0] <= w[1]) {
        return CscMatrix::new_from_triplets(m, n, rows, cols, vals);
    }
    let all = Triplets {
        rows: &rows,
        offset: 0,
        cols: &cols,
        vals: &vals,
    };
    compressed(m, n, &[all])
}

/// Triplets (row + `offset`, column, value) in ascending rows.
struct Triplets<'a> {
    rows: &'a [usize],
    offset: usize,
    cols: &'a [usize],
    vals: &'a [f64],
}

/// A matrix in compressed columns from its triplets, in linear time: the
/// triplets come in blocks, each block's rows ascending and above the last
/// block's, so one counting pass by column keeps each column's rows
/// ascending (Clarabel's constructor sorts them, a tenth of a small
/// program's solve); repeated entries are summed in order, as it does.
fn compressed(m: usize, n: usize, blocks: &[Triplets]) -> CscMatrix<f64> {
    let nnz: usize = blocks.iter().map(|b| b.vals.len()).sum();
    let mut start = vec![0usize; n + 1];
    for b in blocks {
        for &c in b.cols {
            start[c + 1] += 1;
        }
    }
    for c in 0..n {
        start[c + 1] += start[c];
    }
    let mut next = start.clone();
    let mut rowval = vec![0; nnz];
    let mut nzval = vec![0.0; nnz];
    for b in blocks {
        for ((&r, &c), &v) in b.rows.iter().zip(b.cols).zip(b.vals) {
            rowval[next[c]] = r + b.offset;
            nzval[next[c]] = v;
            next[c] += 1;
        }
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

    /// The program's matrix is its rows' triplets in the solver's row
    /// order, as Clarabel's constructor compresses them.
    #[test]
    fn a_programs_matrix_is_its_rows_in_order() {
        let mut lp = Lp::new(4);
        lp.at_most(&[(2, 1.0), (0, -2.0), (2, 0.5)], 1.0);
        lp.equal(&[(3, 4.0), (1, 0.0), (0, 1.5)], 0.0);
        lp.second_order_cone([(&[(1, 1.0)], 1.0), (&[(0, 2.0), (3, 1.0)], 0.0), (&[], 0.5)]);
        lp.at_most(&[(1, -1.0)], 0.0);
        lp.equal(&[(0, 1.0), (0, 2.0)], 3.0);
        let (mut rows, mut cols, mut vals): (Vec<usize>, Vec<usize>, Vec<f64>) =
            (vec![], vec![], vec![]);
        let mut first = 0;
        for block in [&lp.eq, &lp.ineq, &lp.soc] {
            rows.extend(block.row.iter().map(|r| r + first));
            cols.extend(&block.col);
            vals.extend(&block.val);
            first += block.rhs.len();
        }
        let ours = lp.matrix();
        let theirs = CscMatrix::new_from_triplets(lp.rows(), 4, rows, cols, vals);
        assert_eq!(ours.colptr, theirs.colptr);
        assert_eq!(ours.rowval, theirs.rowval);
        assert_eq!(ours.nzval, theirs.nzval);
    }

    /// A program of one shape solved by a kept solver is solved bit for bit
    /// as by a new one, across programs whose values (and scaling) differ.
    #[test]
    fn a_kept_solver_solves_as_a_new_one() {
        // min t − x − 2y subject to x + y ≤ c, ‖(x, y)‖ ≤ t + d, y ≤ e;
        // an unusual size (7 variables) keeps other tests' solvers apart.
        let program = |c: f64, d: f64, e: f64| {
            let mut lp = Lp::new(7);
            lp.cost[0] = 1.0;
            lp.cost[1] = -1.0;
            lp.cost[2] = -2.0 * c;
            for v in 3..7 {
                lp.cost[v] = 1e-3 * v as f64;
                lp.at_most(&[(v, -1.0)], 0.0);
            }
            lp.at_most(&[(1, 1.0), (2, e * 1e3)], c);
            lp.at_most(&[(2, 1.0)], e);
            lp.equal(&[(3, 1.0), (4, -d)], 0.1);
            lp.second_order_cone([(&[(0, 1.0)], d), (&[(1, 1.0)], 0.0), (&[(2, 1.0)], 0.0)]);
            lp.second_order_cone([(&[(5, 1.0)], 1.0), (&[(6, c)], 0.0), (&[(1, 0.5)], 0.0)]);
            lp
        };
        let first = program(1.0, 0.5, 0.3);
        first.solve().unwrap();
        for (c, d, e) in [(2.0, 0.25, 0.7), (0.3, 4.0, 1e-3), (1.0, 0.5, 0.3)] {
            let lp = program(c, d, e);
            let kept = lp.solve().unwrap();
            let new = lp.solve_keeping(false).unwrap();
            let bits = |x: &[f64]| x.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&kept), bits(&new), "c = {c}");
        }
    }

    /// Residuals are A y − b row by row in the solver's order, up to the
    /// marks; shifting the right-hand side by minus them puts y on every row.
    #[test]
    fn residuals_and_shifted_rows_agree() {
        let mut lp = Lp::new(3);
        lp.equal(&[(0, 1.0), (1, 2.0)], 1.0);
        lp.at_most(&[(2, -1.0)], 0.5);
        lp.second_order_cone([(&[(0, 1.0)], 2.0), (&[(1, 1.0)], 0.0), (&[(2, 3.0)], 1.0)]);
        let marks = lp.marks();
        lp.equal(&[(2, 1.0)], 9.0);
        lp.at_most(&[(0, 1.0)], 9.0);
        let y = [1.0, -2.0, 4.0];
        let r = lp.residuals(&y, marks);
        // Cone rows hold −terms and the constant: −(y₀) − 2, −(y₁), −(3y₂) − 1.
        assert_eq!(r, vec![-4.0, -4.5, -3.0, 2.0, -13.0]);
        let back: Vec<f64> = r.iter().map(|v| -v).collect();
        lp.shift_rhs(marks, &back);
        assert!(lp.residuals(&y, marks).iter().all(|v| *v == 0.0));
        // The rows after the marks keep their right-hand sides.
        assert_eq!((lp.eq.rhs[1], lp.ineq.rhs[1]), (9.0, 9.0));
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
