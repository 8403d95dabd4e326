//! Exact extrema and absolute integrals of low-degree polynomials on an interval.
//!
//! A polynomial is a coefficient slice `c` with p(t) = Σ_k `c[k]` t^k (ascending
//! powers, the plan file's convention). Its extrema on [t0, t1] lie at the ends
//! or at real roots of p′. Roots are found in closed form for degree ≤ 2; for
//! higher degrees the roots of p′ split the interval into pieces on which p is
//! monotone, so each piece holds at most one root, bracketed by a sign change
//! and refined by safeguarded Newton (Newton inside the bracket, bisection
//! otherwise). Fixed-size buffers, no allocation, degree ≤ 7; the planner uses ≤ 5.
//! Here in `shared` so that every reader of a plan (the planner, its check,
//! the link's drive configurations) computes a plan's maxima from its
//! segments the same way, never from a recorded summary.

use alloc::vec;
use alloc::vec::Vec;

/// p(t) by Horner's rule.
pub fn eval(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &k| acc * t + k)
}

/// Coefficients of p′.
pub fn derivative(c: &[f64]) -> Vec<f64> {
    c.iter()
        .enumerate()
        .skip(1)
        .map(|(k, &ck)| k as f64 * ck)
        .collect()
}

/// Coefficients of the antiderivative P with P(0) = 0.
pub fn antiderivative(c: &[f64]) -> Vec<f64> {
    core::iter::once(0.0)
        .chain(c.iter().enumerate().map(|(k, &ck)| ck / (k + 1) as f64))
        .collect()
}

/// `c` without trailing exact zeros (so the last coefficient is the leading one).
fn trimmed(c: &[f64]) -> &[f64] {
    let n = c.iter().rposition(|&x| x != 0.0).map_or(0, |i| i + 1);
    &c[..n]
}

/// Orders the ends, so callers may pass [t1, t0].
fn ordered(t0: f64, t1: f64) -> (f64, f64) {
    if t0 <= t1 { (t0, t1) } else { (t1, t0) }
}

/// Coefficient capacity of the allocation-free core: degree ≤ 7.
const CAP: usize = 8;

/// A polynomial of degree < CAP, trimmed (c[n − 1] ≠ 0 unless n = 0).
#[derive(Clone, Copy)]
struct Poly {
    c: [f64; CAP],
    n: usize,
}

impl Poly {
    fn new(c: &[f64]) -> Self {
        let c = trimmed(c);
        assert!(
            c.len() <= CAP,
            "extrema: degree {} polynomial, at most {} supported",
            c.len() - 1,
            CAP - 1
        );
        let mut p = Self {
            c: [0.0; CAP],
            n: c.len(),
        };
        p.c[..c.len()].copy_from_slice(c);
        p
    }
    fn eval(&self, t: f64) -> f64 {
        eval(&self.c[..self.n], t)
    }
    fn derivative(&self) -> Self {
        let mut d = Self {
            c: [0.0; CAP],
            n: self.n.saturating_sub(1),
        };
        for k in 1..self.n {
            d.c[k - 1] = k as f64 * self.c[k];
        }
        d
    }
}

/// Up to CAP roots, ascending, without allocation.
#[derive(Clone, Copy, Default)]
struct Roots {
    r: [f64; CAP],
    n: usize,
}

impl Roots {
    fn push(&mut self, x: f64) {
        if self.n < CAP && (self.n == 0 || self.r[self.n - 1] != x) {
            self.r[self.n] = x;
            self.n += 1;
        }
    }
    fn as_slice(&self) -> &[f64] {
        &self.r[..self.n]
    }
}

/// Real roots of p in [t0, t1], ascending, each isolated root once.
///
/// The zero polynomial (every point a root) and constants have none. Roots of
/// even multiplicity (where p touches zero without crossing) are found when
/// they coincide with a root of p′ that evaluates to exactly zero; otherwise
/// they may be missed, which never matters for extrema (see
/// [`argmax_abs_on_interval`], which also evaluates p at the roots of p″).
///
/// # Panics
/// If the degree exceeds 7 (after dropping trailing zero coefficients).
pub fn roots_in(c: &[f64], t0: f64, t1: f64) -> Vec<f64> {
    let (t0, t1) = ordered(t0, t1);
    poly_roots(&Poly::new(c), t0, t1).as_slice().to_vec()
}

fn poly_roots(p: &Poly, t0: f64, t1: f64) -> Roots {
    let mut out = Roots::default();
    if !(t0.is_finite() && t1.is_finite()) {
        return out;
    }
    let c = &p.c[..p.n];
    let (mut r, k) = match p.n {
        0 | 1 => return out,
        2 => ([-c[0] / c[1], 0.0], 1),
        3 => quadratic_roots(c[0], c[1], c[2]),
        _ => return higher_roots(p, t0, t1),
    };
    if k == 2 && r[1] < r[0] {
        r.swap(0, 1);
    }
    for &x in &r[..k] {
        if x.is_finite() && x >= t0 && x <= t1 {
            out.push(x);
        }
    }
    out
}

/// Real roots of a + b t + c t², c ≠ 0, by the cancellation-free formula
/// (roots, how many).
fn quadratic_roots(a: f64, b: f64, c: f64) -> ([f64; 2], usize) {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        // A double root lost to rounding still is an extremum of the
        // polynomial this quadratic is the derivative of; the vertex is the
        // best estimate when the discriminant is negative only by rounding.
        let scale = (b * b).max((4.0 * a * c).abs());
        return if -disc <= 8.0 * f64::EPSILON * scale {
            ([-b / (2.0 * c), 0.0], 1)
        } else {
            ([0.0; 2], 0)
        };
    }
    if disc == 0.0 {
        return ([-b / (2.0 * c), 0.0], 1);
    }
    // disc > 0, so q ≠ 0.
    let q = -0.5 * (b + b.signum() * libm::sqrt(disc));
    ([q / c, a / q], 2)
}

/// Degree ≥ 3: split at the roots of p′, refine each sign change.
fn higher_roots(p: &Poly, t0: f64, t1: f64) -> Roots {
    let dp = p.derivative();
    let crit = poly_roots(&dp, t0, t1);
    let mut roots = Roots::default();
    let mut a = t0;
    let mut fa = p.eval(a);
    for &b in crit.as_slice().iter().chain(core::iter::once(&t1)) {
        let fb = p.eval(b);
        if fa == 0.0 {
            roots.push(a);
        } else if fb != 0.0 && (fa < 0.0) != (fb < 0.0) {
            roots.push(refine(p, &dp, a, b, fa));
        }
        (a, fa) = (b, fb);
    }
    if fa == 0.0 {
        roots.push(t1);
    }
    roots
}

/// Root of p in [a, b] where p(a) = fa and p(b) have opposite signs:
/// Newton's step when it stays in the bracket and shrinks fast enough,
/// bisection otherwise; the bracket always holds the root.
fn refine(p: &Poly, dp: &Poly, mut a: f64, mut b: f64, fa: f64) -> f64 {
    let neg_at_a = fa < 0.0;
    let mut x = 0.5 * (a + b);
    let mut dx_old = b - a;
    for _ in 0..200 {
        let fx = p.eval(x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == neg_at_a {
            a = x;
        } else {
            b = x;
        }
        let newton = x - fx / dp.eval(x);
        let step_ok = newton > a && newton < b && (newton - x).abs() * 2.0 < dx_old;
        let next = if step_ok { newton } else { 0.5 * (a + b) };
        dx_old = (next - x).abs();
        let tol = 2.0 * f64::EPSILON * a.abs().max(b.abs()).max(f64::MIN_POSITIVE);
        if next == x || b - a <= tol || dx_old <= tol {
            return next;
        }
        x = next;
    }
    x
}

/// The largest |p(t)| on [t0, t1] and a time where it occurs (the earliest
/// candidate on ties): candidates are the ends, the roots of p′ and, for
/// robustness against near-double roots of p′, the roots of p″. No allocation.
///
/// # Panics
/// If the degree exceeds 7 (after dropping trailing zero coefficients).
pub fn argmax_abs_on_interval(coeffs: &[f64], t0: f64, t1: f64) -> (f64, f64) {
    let (t0, t1) = ordered(t0, t1);
    let p = Poly::new(coeffs);
    let d1 = p.derivative();
    let d2 = d1.derivative();
    let mut best = (t0, p.eval(t0).abs());
    let (r1, r2) = (poly_roots(&d1, t0, t1), poly_roots(&d2, t0, t1));
    for &t in r1.as_slice().iter().chain(r2.as_slice()).chain([&t1]) {
        let v = p.eval(t).abs();
        if v > best.1 || v.is_nan() {
            best = (t, v);
        }
    }
    best
}

/// The largest |p(t)| on [t0, t1], exact up to rounding (see
/// [`argmax_abs_on_interval`]); `coeffs` in ascending powers, degree ≤ 7.
pub fn max_abs_on_interval(coeffs: &[f64], t0: f64, t1: f64) -> f64 {
    argmax_abs_on_interval(coeffs, t0, t1).1
}

/// ∫ |p(t)| dt over [t0, t1], exact: p keeps its sign between its roots, and
/// on each such piece the integral is the change of the antiderivative.
/// Degree ≤ 7.
pub fn integral_abs_on_interval(coeffs: &[f64], t0: f64, t1: f64) -> f64 {
    let (t0, t1) = ordered(t0, t1);
    let anti = antiderivative(coeffs);
    let mut breaks = vec![t0];
    breaks.extend(roots_in(coeffs, t0, t1));
    breaks.push(t1);
    breaks
        .windows(2)
        .map(|w| (eval(&anti, w[1]) - eval(&anti, w[0])).abs())
        .sum()
}
