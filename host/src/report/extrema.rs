//! Exact extrema and absolute integrals of low-degree polynomials on an interval.
//!
//! A polynomial is a coefficient slice `c` with p(t) = Σ_k c[k] t^k (ascending
//! powers, the plan file's convention). Its extrema on [t0, t1] lie at the ends
//! or at real roots of p′. Roots are found in closed form for degree ≤ 2; for
//! higher degrees the roots of p′ split the interval into pieces on which p is
//! monotone, so each piece holds at most one root, bracketed by a sign change
//! and refined by safeguarded Newton (Newton inside the bracket, bisection
//! otherwise). The recursion works for any degree; the planner uses ≤ 5.

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
    std::iter::once(0.0)
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

/// Real roots of p in [t0, t1], ascending, each isolated root once.
///
/// The zero polynomial (every point a root) and constants have none. Roots of
/// even multiplicity (where p touches zero without crossing) are found when
/// they coincide with a root of p′ that evaluates to exactly zero; otherwise
/// they may be missed, which never matters for extrema (see
/// [`argmax_abs_on_interval`], which also evaluates p at the roots of p″).
pub fn roots_in(c: &[f64], t0: f64, t1: f64) -> Vec<f64> {
    let (t0, t1) = ordered(t0, t1);
    if !(t0.is_finite() && t1.is_finite()) {
        return Vec::new();
    }
    let c = trimmed(c);
    let mut roots = match c.len() {
        0 | 1 => Vec::new(),
        2 => vec![-c[0] / c[1]],
        3 => quadratic_roots(c[0], c[1], c[2]),
        _ => return higher_roots(c, t0, t1),
    };
    roots.retain(|r| r.is_finite() && *r >= t0 && *r <= t1);
    roots.sort_by(f64::total_cmp);
    roots.dedup();
    roots
}

/// Real roots of a + b t + c t², c ≠ 0, by the cancellation-free formula.
fn quadratic_roots(a: f64, b: f64, c: f64) -> Vec<f64> {
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        // A double root lost to rounding still is an extremum of the
        // polynomial this quadratic is the derivative of; the vertex is the
        // best estimate when the discriminant is negative only by rounding.
        let scale = (b * b).max((4.0 * a * c).abs());
        return if -disc <= 8.0 * f64::EPSILON * scale {
            vec![-b / (2.0 * c)]
        } else {
            Vec::new()
        };
    }
    if disc == 0.0 {
        return vec![-b / (2.0 * c)];
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    if q == 0.0 {
        // b = 0 and a c < 0 handled above via disc > 0, so q = 0 means a = b = 0.
        return vec![0.0];
    }
    vec![q / c, a / q]
}

/// Degree ≥ 3: split at the roots of p′, refine each sign change.
fn higher_roots(c: &[f64], t0: f64, t1: f64) -> Vec<f64> {
    let dc = derivative(c);
    let mut breaks = vec![t0];
    breaks.extend(roots_in(&dc, t0, t1));
    breaks.push(t1);
    let mut roots: Vec<f64> = Vec::new();
    let push = |r: f64, roots: &mut Vec<f64>| {
        if roots.last() != Some(&r) {
            roots.push(r);
        }
    };
    for w in breaks.windows(2) {
        let (a, b) = (w[0], w[1]);
        let (fa, fb) = (eval(c, a), eval(c, b));
        if fa == 0.0 {
            push(a, &mut roots);
        } else if fb != 0.0 && (fa < 0.0) != (fb < 0.0) {
            push(refine(c, &dc, a, b, fa), &mut roots);
        }
    }
    if eval(c, t1) == 0.0 {
        push(t1, &mut roots);
    }
    roots
}

/// Root of p in [a, b] where p(a) = fa and p(b) have opposite signs:
/// Newton's step when it stays in the bracket and shrinks fast enough,
/// bisection otherwise; the bracket always holds the root.
fn refine(c: &[f64], dc: &[f64], mut a: f64, mut b: f64, fa: f64) -> f64 {
    let neg_at_a = fa < 0.0;
    let mut x = 0.5 * (a + b);
    let mut dx_old = b - a;
    for _ in 0..200 {
        let fx = eval(c, x);
        if fx == 0.0 {
            return x;
        }
        if (fx < 0.0) == neg_at_a {
            a = x;
        } else {
            b = x;
        }
        let d = eval(dc, x);
        let newton = x - fx / d;
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
/// robustness against near-double roots of p′, the roots of p″.
pub fn argmax_abs_on_interval(coeffs: &[f64], t0: f64, t1: f64) -> (f64, f64) {
    let (t0, t1) = ordered(t0, t1);
    let d1 = derivative(coeffs);
    let d2 = derivative(&d1);
    let mut best = (t0, eval(coeffs, t0).abs());
    let candidates = roots_in(&d1, t0, t1)
        .into_iter()
        .chain(roots_in(&d2, t0, t1))
        .chain(std::iter::once(t1));
    for t in candidates {
        let v = eval(coeffs, t).abs();
        if v > best.1 || v.is_nan() {
            best = (t, v);
        }
    }
    best
}

/// The largest |p(t)| on [t0, t1], exact up to rounding (see [`argmax_abs_on_interval`]).
pub fn max_abs_on_interval(coeffs: &[f64], t0: f64, t1: f64) -> f64 {
    argmax_abs_on_interval(coeffs, t0, t1).1
}

/// ∫ |p(t)| dt over [t0, t1], exact: p keeps its sign between its roots, and
/// on each such piece the integral is the change of the antiderivative.
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

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Dense sampling, then a second dense pass around the best sample.
    fn sampled_max(c: &[f64], t0: f64, t1: f64) -> f64 {
        let n = 20_000;
        let step = (t1 - t0) / n as f64;
        let mut best = (t0, eval(c, t0).abs());
        for i in 0..=n {
            let t = t0 + step * i as f64;
            let v = eval(c, t).abs();
            if v > best.1 {
                best = (t, v);
            }
        }
        let (lo, hi) = ((best.0 - step).max(t0), (best.0 + step).min(t1));
        for i in 0..=4000 {
            let t = lo + (hi - lo) * i as f64 / 4000.0;
            best.1 = best.1.max(eval(c, t).abs());
        }
        best.1
    }

    fn from_roots(roots: &[f64], scale: f64) -> Vec<f64> {
        let mut c = vec![scale];
        for &r in roots {
            let mut next = vec![0.0; c.len() + 1];
            for (k, &ck) in c.iter().enumerate() {
                next[k + 1] += ck;
                next[k] -= r * ck;
            }
            c = next;
        }
        c
    }

    #[test]
    fn random_polynomials_match_dense_sampling() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for case in 0..3000 {
            let deg = case % 6;
            let c: Vec<f64> = (0..=deg)
                .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-3..3)))
                .collect();
            let t0 = rng.random_range(-2.0..1.0);
            let t1 = t0 + rng.random_range(0.01..3.0);
            let exact = max_abs_on_interval(&c, t0, t1);
            let sampled = sampled_max(&c, t0, t1);
            let scale = sampled.max(1e-300);
            assert!(
                exact >= sampled * (1.0 - 1e-13),
                "case {case}: exact {exact:e} below sampled {sampled:e} for {c:?} on [{t0}, {t1}]"
            );
            assert!(
                (exact - sampled) / scale <= 1e-9,
                "case {case}: exact {exact:e} vs sampled {sampled:e} for {c:?} on [{t0}, {t1}]"
            );
        }
    }

    #[test]
    fn roots_of_polynomials_with_known_roots() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        for _ in 0..2000 {
            let deg = rng.random_range(1..=5);
            let mut roots: Vec<f64> = (0..deg).map(|_| rng.random_range(0.0..1.0)).collect();
            roots.sort_by(f64::total_cmp);
            if roots.windows(2).any(|w| w[1] - w[0] < 1e-3) {
                continue;
            }
            let c = from_roots(&roots, rng.random_range(0.5..2.0));
            let found = roots_in(&c, -0.01, 1.01);
            assert_eq!(found.len(), roots.len(), "{roots:?} -> {found:?}");
            for (f, r) in found.iter().zip(&roots) {
                assert!((f - r).abs() < 1e-9, "{roots:?} -> {found:?}");
            }
        }
    }

    #[test]
    fn clustered_roots_match_dense_sampling() {
        // Nearly double roots of p′ (close pairs of extrema) are the hard case.
        let mut rng = ChaCha8Rng::seed_from_u64(5);
        for _ in 0..1000 {
            let a = rng.random_range(0.1..0.9);
            let gap = 10f64.powi(rng.random_range(-8..-2));
            let b = rng.random_range(0.0..1.0);
            let c = from_roots(&[a, a + gap, b, rng.random_range(-0.5..1.5)], 1.0);
            // Integrate so that the cluster sits in p′.
            let p = antiderivative(&c);
            let exact = max_abs_on_interval(&p, 0.0, 1.0);
            let sampled = sampled_max(&p, 0.0, 1.0);
            assert!(exact >= sampled * (1.0 - 1e-13), "{exact:e} < {sampled:e}");
            assert!((exact - sampled) / sampled.max(1e-300) <= 1e-9);
        }
    }

    #[test]
    fn multiple_roots_and_degenerate_cases() {
        // p = (t − 0.3)² (t − 0.7)³: p′ has a double root at 0.7, |p| peaks inside.
        let c = from_roots(&[0.3, 0.3, 0.7, 0.7, 0.7], 1.0);
        let exact = max_abs_on_interval(&c, 0.0, 1.0);
        assert!(exact >= sampled_max(&c, 0.0, 1.0) * (1.0 - 1e-13));
        // Chebyshev T5 on [−1, 1]: equioscillates with |T5| = 1 at 6 points.
        let t5 = [0.0, 5.0, 0.0, -20.0, 0.0, 16.0];
        assert!((max_abs_on_interval(&t5, -1.0, 1.0) - 1.0).abs() < 1e-14);
        assert_eq!(roots_in(&t5, -1.0, 1.0).len(), 5);
        // Constants, zero, reversed interval, trailing zeros.
        assert_eq!(max_abs_on_interval(&[], 0.0, 1.0), 0.0);
        assert_eq!(max_abs_on_interval(&[-2.5, 0.0, 0.0], 0.0, 1.0), 2.5);
        assert_eq!(max_abs_on_interval(&[0.0, 1.0], 3.0, 1.0), 3.0);
        // A quadratic with a double root at 0.5 (discriminant exactly 0).
        assert_eq!(roots_in(&[0.25, -1.0, 1.0], 0.0, 1.0), vec![0.5]);
    }

    #[test]
    fn integral_of_absolute_value() {
        // ∫₀² |t − 1| dt = 1; ∫_{-1}^{1} |t³| dt = 1/2.
        assert!((integral_abs_on_interval(&[-1.0, 1.0], 0.0, 2.0) - 1.0).abs() < 1e-15);
        assert!((integral_abs_on_interval(&[0.0, 0.0, 0.0, 1.0], -1.0, 1.0) - 0.5).abs() < 1e-15);
        // Against a fine midpoint rule on random quintics.
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        for _ in 0..200 {
            let c: Vec<f64> = (0..6).map(|_| rng.random_range(-1.0..1.0)).collect();
            let n = 200_000;
            let h = 2.0 / n as f64;
            let mid: f64 = (0..n)
                .map(|i| eval(&c, -1.0 + h * (i as f64 + 0.5)).abs() * h)
                .sum();
            let exact = integral_abs_on_interval(&c, -1.0, 1.0);
            assert!((exact - mid).abs() < 1e-7, "{exact} vs {mid}");
        }
    }
}
