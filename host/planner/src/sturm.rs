//! Independent real-root and |p|-maximum finder for the plan verifier.
//!
//! A polynomial is a coefficient slice `c` with p(t) = Σ_k c[k] t^k (ascending
//! powers). This module deliberately shares no method with the planner's own
//! extremum code (derivative splitting + safeguarded Newton), so that the
//! verifier checks the planner with an unrelated algorithm.
//!
//! # Method
//!
//! 1. **Normalise.** The interval [t0, t1] is mapped onto [0, 1]: the
//!    coefficients of q(s) = p(t0 + h s), h = t1 − t0, come from a Taylor shift
//!    (repeated synthetic division) followed by scaling by h^k, and are then
//!    divided by the largest magnitude. On [0, 1] the size of a coefficient is
//!    its contribution to the values, so leading coefficients of relative size
//!    ≤ 2⁻⁵³ are dropped (the degree drops) and the Sturm chain is built from
//!    numbers of size ≈ 1 whatever the scale of the input (1e6 t⁵ on
//!    [0, 1e-3] and 1e-9-sized values alike).
//! 2. **Sturm chain.** q₀ = q, q₁ = q′, q_{k+1} = −rem(q_{k−1}, q_k), each
//!    member rescaled to unit largest coefficient; a remainder whose
//!    coefficients are all below the rounding level of the division is taken
//!    as zero (the chain then ends in the numerical gcd, so multiple roots are
//!    counted once). The number of distinct roots in (a, b] is V(a) − V(b),
//!    V = sign variations of the chain.
//! 3. **Isolation** by bisection on Sturm counts: an interval holding one root
//!    with a sign change of q is refined by the Illinois variant of regula
//!    falsi (bracketing, every step kept inside the bracket); an interval that
//!    still counts roots at width 2⁻⁴⁴ (a cluster or an even-multiplicity root)
//!    yields its midpoint.
//! 4. **Certificate.** The chain can be wrong in floating point (clustered
//!    roots, ill-conditioned remainders). So the result is checked: on every
//!    gap between the roots found (each gap shrunk by 2⁻⁴⁰ at a found root), the
//!    Bernstein coefficients of q, obtained by de Casteljau subdivision, must
//!    all have one strict sign; by the convex-hull property q then has no root
//!    there. A negative Sturm count, an exhausted step budget or a failed
//!    certificate sends the problem to the fallback.
//! 5. **Fallback: Bernstein subdivision.** Descartes' rule on the Bernstein
//!    coefficients (no sign variation ⇒ no root; one ⇒ exactly one, refined by
//!    Illinois), halving by de Casteljau otherwise, down to width 2⁻⁴⁴
//!    (midpoint kept as a cluster candidate). Sound in the same sense as the
//!    certificate; slower, so used only when the chain fails.
//!
//! [`max_abs`] evaluates |p| (Horner, original coefficients) at both ends, at
//! the roots of q′ and, so that a pair of nearly coincident roots of q′ lost to
//! rounding cannot hide an extremum, at the roots of q″.
//!
//! Every loop and recursion is bounded (depth ≤ 64, ≤ 20 000 subdivision
//! steps, ≤ 400 Illinois steps); nothing panics. Degrees above
//! [`MAX_DEGREE`] (after dropping trailing zeros) and non-finite input give a
//! NaN maximum and no roots.

/// Highest supported degree (after dropping trailing exact zeros).
pub(crate) const MAX_DEGREE: usize = 16;
/// Leading coefficients at most this fraction of the largest one on [0, 1]
/// are dropped: 2⁻⁵³.
const TRIM: f64 = f64::EPSILON / 2.0;
/// Subdivision stops at this width of the unit interval: 2⁻⁴⁴.
const MIN_WIDTH: f64 = 1.0 / 17_592_186_044_416.0;
/// Gaps are certified this far from a found root: 2⁻⁴⁰.
const CERT_MARGIN: f64 = 1.0 / 1_099_511_627_776.0;
/// Largest margin of the certificate: 2⁻¹⁶.
const MAX_MARGIN: f64 = 1.0 / 65_536.0;
/// Roots of the unit problem closer than this are reported once.
const MERGE: f64 = 4.0 * MIN_WIDTH;
const MAX_DEPTH: u32 = 64;
/// Subdivision depth of the certificate of a gap.
const CERT_DEPTH: u32 = 40;
const BUDGET: usize = 20_000;
const ILLINOIS_STEPS: usize = 400;

/// p(t) by Horner's rule.
fn eval(c: &[f64], t: f64) -> f64 {
    c.iter().rev().fold(0.0, |acc, &k| acc * t + k)
}

fn derivative(c: &[f64]) -> Vec<f64> {
    c.iter()
        .enumerate()
        .skip(1)
        .map(|(k, &ck)| k as f64 * ck)
        .collect()
}

/// Divides by the largest magnitude and drops negligible leading terms.
/// `None` when a coefficient is not finite; empty for the zero polynomial.
fn normalised(c: &[f64]) -> Option<Vec<f64>> {
    let m = c.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    if !m.is_finite() || c.iter().any(|x| x.is_nan()) {
        return None;
    }
    if m == 0.0 {
        return Some(Vec::new());
    }
    let mut q: Vec<f64> = c.iter().map(|x| x / m).collect();
    while q.last().is_some_and(|x| x.abs() <= TRIM) {
        q.pop();
    }
    Some(q)
}

/// Coefficients of q(s) = p(t0 + h s), normalised. `None` on overflow or a
/// degree above [`MAX_DEGREE`].
fn to_unit(c: &[f64], t0: f64, h: f64) -> Option<Vec<f64>> {
    let n = c.iter().rposition(|&x| x != 0.0).map_or(0, |i| i + 1);
    if n > MAX_DEGREE + 1 {
        return None;
    }
    let mut r = c[..n].to_vec();
    // Taylor shift: after pass i, r[i] is the i-th Taylor coefficient at t0.
    for i in 0..n.saturating_sub(1) {
        for k in (i..n - 1).rev() {
            r[k] += t0 * r[k + 1];
        }
    }
    let mut hk = 1.0;
    for x in &mut r {
        *x *= hk;
        hk *= h;
    }
    normalised(&r)
}

fn same_strict_sign(a: f64, b: f64) -> bool {
    (a > 0.0 && b > 0.0) || (a < 0.0 && b < 0.0)
}

/// Root in [a, b] of q with q(a) = fa, q(b) = fb of opposite strict signs,
/// by the Illinois method (regula falsi halving the stale end's value), with
/// a bisection step whenever the secant point is not strictly inside.
fn illinois(q: &[f64], mut a: f64, mut b: f64, mut fa: f64, mut fb: f64) -> f64 {
    let mut side = 0_i8;
    for _ in 0..ILLINOIS_STEPS {
        let mid = 0.5 * (a + b);
        if !(mid > a && mid < b) || b - a <= 4.0 * f64::EPSILON * a.abs().max(b.abs()) {
            break;
        }
        let mut x = (a * fb - b * fa) / (fb - fa);
        if !(x > a && x < b) {
            x = mid;
        }
        let fx = eval(q, x);
        if fx == 0.0 {
            return x;
        }
        if same_strict_sign(fx, fb) {
            b = x;
            fb = fx;
            if side == -1 {
                fa *= 0.5;
            }
            side = -1;
        } else {
            a = x;
            fa = fx;
            if side == 1 {
                fb *= 0.5;
            }
            side = 1;
        }
    }
    0.5 * (a + b)
}

// ---------------------------------------------------------------- Sturm ----

/// Remainder of a / b (b trimmed, nonzero lead) and the largest quotient
/// coefficient magnitude.
fn remainder(a: &[f64], b: &[f64]) -> (Vec<f64>, f64) {
    let db = b.len() - 1;
    let lead = b[db];
    let mut r = a.to_vec();
    let mut qmax = 0.0_f64;
    if r.len() > db {
        for i in (db..r.len()).rev() {
            let qi = r[i] / lead;
            qmax = qmax.max(qi.abs());
            for (j, &bj) in b.iter().enumerate() {
                r[i - db + j] -= qi * bj;
            }
            r[i] = 0.0;
        }
        r.truncate(db);
    }
    (r, qmax)
}

/// The Sturm chain of q (normalised, degree ≥ 1); `None` if it breaks down.
fn sturm_chain(q: &[f64]) -> Option<Vec<Vec<f64>>> {
    let mut chain = vec![q.to_vec(), normalised(&derivative(q))?];
    while chain.last().is_some_and(|p| p.len() > 1) && chain.len() <= MAX_DEGREE + 1 {
        let k = chain.len();
        let (r, qmax) = remainder(&chain[k - 2], &chain[k - 1]);
        let tol = 32.0 * f64::EPSILON * (1.0 + qmax);
        let mut r: Vec<f64> = r.iter().map(|x| -x).collect();
        while r.last().is_some_and(|x| x.abs() <= tol) {
            r.pop();
        }
        if r.is_empty() {
            break;
        }
        let r = normalised(&r)?;
        if r.is_empty() {
            break;
        }
        chain.push(r);
    }
    Some(chain)
}

fn variations(chain: &[Vec<f64>], x: f64) -> usize {
    let mut count = 0;
    let mut last = 0.0_f64;
    for p in chain {
        let v = eval(p, x);
        if v != 0.0 {
            if last != 0.0 && (v < 0.0) != (last < 0.0) {
                count += 1;
            }
            last = v;
        }
    }
    count
}

struct Isolator<'a> {
    q: &'a [f64],
    chain: Vec<Vec<f64>>,
    roots: Vec<f64>,
    budget: usize,
    failed: bool,
}

impl Isolator<'_> {
    fn isolate(&mut self, a: f64, b: f64, va: usize, vb: usize, depth: u32) {
        if self.failed || va == vb {
            return;
        }
        if va < vb || self.budget == 0 {
            self.failed = true;
            return;
        }
        self.budget -= 1;
        let (fa, fb) = (eval(self.q, a), eval(self.q, b));
        if va - vb == 1 {
            if fb == 0.0 {
                self.roots.push(b);
                return;
            }
            if fa != 0.0 && !same_strict_sign(fa, fb) {
                self.roots.push(illinois(self.q, a, b, fa, fb));
                return;
            }
        }
        if depth >= MAX_DEPTH || b - a <= MIN_WIDTH {
            self.roots.push(0.5 * (a + b));
            return;
        }
        let m = 0.5 * (a + b);
        let vm = variations(&self.chain, m);
        self.isolate(a, m, va, vm, depth + 1);
        self.isolate(m, b, vm, vb, depth + 1);
    }
}

/// Roots of q (normalised, degree ≥ 2) in [0, 1] from its Sturm chain,
/// certified; `None` if the chain or the certificate fails.
pub(crate) fn sturm_roots(q: &[f64]) -> Option<Vec<f64>> {
    let chain = sturm_chain(q)?;
    let (v0, v1) = (variations(&chain, 0.0), variations(&chain, 1.0));
    let mut iso = Isolator {
        q,
        chain,
        roots: Vec::new(),
        budget: BUDGET,
        failed: false,
    };
    if q[0] == 0.0 {
        iso.roots.push(0.0);
    }
    iso.isolate(0.0, 1.0, v0, v1, 0);
    if iso.failed {
        return None;
    }
    let roots = merged(iso.roots);
    certified(q, &roots).then_some(roots)
}

// ------------------------------------------------------------ Bernstein ----

fn binomial(n: usize, k: usize) -> f64 {
    (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
}

/// Bernstein coefficients on [0, 1] of q given in powers of s.
fn to_bernstein(q: &[f64]) -> Vec<f64> {
    let n = q.len() - 1;
    (0..=n)
        .map(|i| {
            (0..=i)
                .map(|k| binomial(i, k) / binomial(n, k) * q[k])
                .sum()
        })
        .collect()
}

/// de Casteljau: Bernstein coefficients on [0, τ] and on [τ, 1].
fn split(b: &[f64], tau: f64) -> (Vec<f64>, Vec<f64>) {
    let n = b.len() - 1;
    let mut w = b.to_vec();
    let mut left = vec![0.0; n + 1];
    let mut right = vec![0.0; n + 1];
    left[0] = w[0];
    right[n] = w[n];
    for r in 1..=n {
        for i in 0..=n - r {
            w[i] = (1.0 - tau) * w[i] + tau * w[i + 1];
        }
        left[r] = w[0];
        right[n - r] = w[n - r];
    }
    (left, right)
}

/// Bernstein coefficients on [lo, hi] ⊆ [0, 1], lo < hi.
fn restricted(b: &[f64], lo: f64, hi: f64) -> Vec<f64> {
    let (left, _) = split(b, hi);
    split(&left, lo / hi).1
}

fn sign_variations(b: &[f64]) -> usize {
    let mut count = 0;
    let mut last = 0.0_f64;
    for &v in b.iter().filter(|v| **v != 0.0) {
        if last != 0.0 && (v < 0.0) != (last < 0.0) {
            count += 1;
        }
        last = v;
    }
    count
}

/// True if q provably has no root where its Bernstein coefficients are `b`:
/// every piece of a subdivision (by halving, at most [`CERT_DEPTH`] levels,
/// `budget` pieces in all) has coefficients of one strict sign.
fn no_root(b: &[f64], depth: u32, budget: &mut usize) -> bool {
    if b.iter().all(|&x| x > 0.0) || b.iter().all(|&x| x < 0.0) {
        return true;
    }
    let (first, last) = (b[0], b[b.len() - 1]);
    if depth >= CERT_DEPTH || *budget == 0 || !same_strict_sign(first, last) {
        return false;
    }
    *budget -= 1;
    let (left, right) = split(b, 0.5);
    no_root(&left, depth + 1, budget) && no_root(&right, depth + 1, budget)
}

/// True if every gap between consecutive `roots` (sorted, in [0, 1])
/// provably holds no root of q. Each gap stops short of a found root r by the
/// least margin 2^k ≥ [`CERT_MARGIN`] at which |q| exceeds its rounding level
/// (inside that, q is numerically zero and a further root could be neither
/// shown nor ruled out); past [`MAX_MARGIN`] the certificate fails.
fn certified(q: &[f64], roots: &[f64]) -> bool {
    let b = to_bernstein(q);
    // Twice the textbook bound γ₂ₙ Σ|q_k| x^k on Horner's rounding error.
    let abs: Vec<f64> = q.iter().map(|x| x.abs()).collect();
    let noise = |x: f64| 2.0 * q.len() as f64 * f64::EPSILON * eval(&abs, x);
    let margin = |r: f64, dir: f64| {
        let mut m = CERT_MARGIN;
        while m <= MAX_MARGIN {
            let x = r + dir * m;
            if !(0.0..=1.0).contains(&x) || eval(q, x).abs() > noise(x) {
                return Some(m);
            }
            m *= 2.0;
        }
        None
    };
    let mut budget = BUDGET;
    let mut clear = |lo: f64, hi: f64| no_root(&restricted(&b, lo, hi), 0, &mut budget);
    let mut lo = 0.0;
    for &r in roots {
        let (Some(left), Some(right)) = (margin(r, -1.0), margin(r, 1.0)) else {
            return false;
        };
        let hi = r - left;
        if hi > lo && !clear(lo, hi) {
            return false;
        }
        lo = lo.max(r + right);
    }
    lo >= 1.0 || clear(lo, 1.0)
}

struct Subdivider<'a> {
    q: &'a [f64],
    roots: Vec<f64>,
    budget: usize,
    failed: bool,
}

impl Subdivider<'_> {
    fn subdivide(&mut self, b: &[f64], lo: f64, hi: f64, depth: u32) {
        if self.failed {
            return;
        }
        let var = sign_variations(b);
        if var == 0 {
            return;
        }
        if self.budget == 0 {
            self.failed = true;
            return;
        }
        self.budget -= 1;
        if var == 1 {
            let (fa, fb) = (eval(self.q, lo), eval(self.q, hi));
            if fa != 0.0 && fb != 0.0 && !same_strict_sign(fa, fb) {
                self.roots.push(illinois(self.q, lo, hi, fa, fb));
                return;
            }
        }
        let mid = 0.5 * (lo + hi);
        if depth >= MAX_DEPTH || hi - lo <= MIN_WIDTH {
            self.roots.push(mid);
            return;
        }
        if eval(self.q, mid) == 0.0 {
            self.roots.push(mid);
        }
        let (left, right) = split(b, 0.5);
        self.subdivide(&left, lo, mid, depth + 1);
        self.subdivide(&right, mid, hi, depth + 1);
    }
}

/// Roots of q (normalised, degree ≥ 1) in [0, 1] by Bernstein subdivision;
/// `None` only if the step budget runs out.
pub(crate) fn bernstein_roots(q: &[f64]) -> Option<Vec<f64>> {
    let mut sub = Subdivider {
        q,
        roots: Vec::new(),
        budget: BUDGET,
        failed: false,
    };
    if q[0] == 0.0 {
        sub.roots.push(0.0);
    }
    if eval(q, 1.0) == 0.0 {
        sub.roots.push(1.0);
    }
    sub.subdivide(&to_bernstein(q), 0.0, 1.0, 0);
    (!sub.failed).then(|| merged(sub.roots))
}

// ---------------------------------------------------------------- API ----

/// Sorted, with roots closer than [`MERGE`] reported once (their mean).
fn merged(mut roots: Vec<f64>) -> Vec<f64> {
    roots.sort_by(f64::total_cmp);
    let mut out: Vec<f64> = Vec::with_capacity(roots.len());
    let mut group = (0.0, 0.0, 0_u32); // first, sum, count
    for r in roots {
        if group.2 > 0 && r - group.0 <= MERGE {
            group.1 += r;
            group.2 += 1;
        } else {
            if group.2 > 0 {
                out.push(group.1 / f64::from(group.2));
            }
            group = (r, r, 1);
        }
    }
    if group.2 > 0 {
        out.push(group.1 / f64::from(group.2));
    }
    out
}

/// Roots in [0, 1] of q given in powers of s (any scale). `None` when the
/// input is not finite or the fallback's budget runs out.
fn unit_roots(q: &[f64]) -> Option<Vec<f64>> {
    let q = normalised(q)?;
    match q.len() {
        0 | 1 => Some(Vec::new()),
        2 => {
            let s = -q[0] / q[1];
            Some(if (0.0..=1.0).contains(&s) {
                vec![s]
            } else {
                Vec::new()
            })
        }
        _ => sturm_roots(&q).or_else(|| bernstein_roots(&q)),
    }
}

fn ordered(t0: f64, t1: f64) -> (f64, f64) {
    if t0 <= t1 { (t0, t1) } else { (t1, t0) }
}

/// Distinct real roots of p in [t0, t1] (either order), ascending.
///
/// Roots closer together than about 2⁻⁴² (t1 − t0) are reported once, and a
/// multiple root comes back once, accurate to roughly the square root of the
/// rounding level for a double root. The zero polynomial, constants,
/// non-finite input, degrees above [`MAX_DEGREE`] and overflow give no roots.
/// For t0 == t1, the point itself if p vanishes there.
// The tests check the roots themselves; the verifier needs only the maxima.
#[cfg_attr(not(test), allow(dead_code))]
pub fn real_roots(c: &[f64], t0: f64, t1: f64) -> Vec<f64> {
    if !(t0.is_finite() && t1.is_finite()) || c.iter().any(|x| !x.is_finite()) {
        return Vec::new();
    }
    let (a, b) = ordered(t0, t1);
    let nonzero = c.iter().any(|&x| x != 0.0);
    if a == b {
        return if nonzero && eval(c, a) == 0.0 {
            vec![a]
        } else {
            Vec::new()
        };
    }
    let h = b - a;
    let roots = to_unit(c, a, h).and_then(|q| unit_roots(&q));
    let mut out: Vec<f64> = roots
        .unwrap_or_default()
        .into_iter()
        .map(|s| (a + h * s).clamp(a, b))
        .collect();
    out.dedup();
    out
}

/// The largest |p(t)| on [t0, t1] (ends included, either order) and the
/// earliest candidate time where it occurs: `(t, max |p|)`.
///
/// The maximum is exact up to rounding in evaluating p (Horner, original
/// coefficients). NaN maximum (time NaN) for non-finite input, for a degree
/// above [`MAX_DEGREE`], or on overflow of the normalised problem; callers
/// should test `!(max <= limit)` so that NaN fails a check.
pub fn max_abs(c: &[f64], t0: f64, t1: f64) -> (f64, f64) {
    const NAN: (f64, f64) = (f64::NAN, f64::NAN);
    if !(t0.is_finite() && t1.is_finite()) || c.iter().any(|x| !x.is_finite()) {
        return NAN;
    }
    let (a, b) = ordered(t0, t1);
    let mut candidates = vec![a, b];
    if a < b {
        let h = b - a;
        let Some(q) = to_unit(c, a, h) else {
            return NAN;
        };
        let d1 = derivative(&q);
        let d2 = derivative(&d1);
        for d in [d1, d2] {
            let Some(roots) = unit_roots(&d) else {
                return NAN;
            };
            candidates.extend(roots.into_iter().map(|s| (a + h * s).clamp(a, b)));
        }
    }
    candidates.sort_by(f64::total_cmp);
    let mut best = (a, eval(c, a).abs());
    for t in candidates {
        let v = eval(c, t).abs();
        if v > best.1 || v.is_nan() {
            best = (t, v);
            if v.is_nan() {
                return NAN;
            }
        }
    }
    best
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Ascending coefficients of scale · Π (t − r).
    pub(crate) fn from_roots(roots: &[f64], scale: f64) -> Vec<f64> {
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

    fn antiderivative(c: &[f64]) -> Vec<f64> {
        std::iter::once(0.0)
            .chain(c.iter().enumerate().map(|(k, &ck)| ck / (k + 1) as f64))
            .collect()
    }

    /// Dense sampling (20 000 steps), then 4 000 steps around the best sample.
    pub(crate) fn sampled_max(c: &[f64], t0: f64, t1: f64) -> f64 {
        let n = 20_000;
        let step = (t1 - t0) / n as f64;
        let mut best = (t0, eval(c, t0).abs().max(eval(c, t1).abs()));
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

    /// A random test polynomial and interval, family chosen by `case`:
    /// plain random coefficients; scaled in time and value (P(t/τ)·σ);
    /// clustered roots of p′; multiple roots of p′.
    pub(crate) fn random_case(rng: &mut ChaCha8Rng, case: usize) -> (Vec<f64>, f64, f64) {
        let deg = 1 + case % 5;
        match (case / 5) % 4 {
            0 => {
                let c: Vec<f64> = (0..=deg)
                    .map(|_| rng.random_range(-1.0..1.0) * 10f64.powi(rng.random_range(-3..3)))
                    .collect();
                let t0 = rng.random_range(-2.0..1.0);
                (c, t0, t0 + rng.random_range(0.01..3.0))
            }
            1 => {
                let tau = 10f64.powf(rng.random_range(-4.0..2.0));
                let sigma = 10f64.powf(rng.random_range(-9.0..6.0));
                let c: Vec<f64> = (0..=deg)
                    .map(|k| sigma * rng.random_range(-1.0..1.0) / tau.powi(k as i32))
                    .collect();
                let u0 = rng.random_range(-1.0..0.5);
                (c, tau * u0, tau * (u0 + rng.random_range(0.05..1.5)))
            }
            2 => {
                // p′ with two roots 10^-8..10^-2 apart.
                let a = rng.random_range(0.1..0.9);
                let gap = 10f64.powf(rng.random_range(-8.0..-2.0));
                let mut roots = vec![a, a + gap];
                roots.extend((2..deg).map(|_| rng.random_range(-0.5..1.5)));
                roots.truncate(deg.max(2) - 1);
                let c = antiderivative(&from_roots(&roots, rng.random_range(0.5..2.0)));
                (c, 0.0, 1.0)
            }
            _ => {
                // p′ with a double or triple root.
                let a = rng.random_range(0.0..1.0);
                let m = if deg >= 4 { 3 } else { 2 };
                let mut roots = vec![a; m.min(deg)];
                roots.extend((roots.len() + 1..deg).map(|_| rng.random_range(-0.5..1.5)));
                let c = antiderivative(&from_roots(&roots, rng.random_range(-2.0..2.0)));
                (c, 0.0, 1.0)
            }
        }
    }

    /// Compares [`max_abs`] with `other` on `cases` random polynomials (all the
    /// families of [`random_case`]); returns the worst relative disagreement of
    /// the maxima and the case that had it. For cross-checking the planner's
    /// extremum finder, e.g. `cross_test_against(extrema::argmax_abs_on_interval, 20_000, 1)`.
    pub(crate) fn cross_test_against(
        other: impl Fn(&[f64], f64, f64) -> (f64, f64),
        cases: usize,
        seed: u64,
    ) -> (f64, Option<(Vec<f64>, f64, f64)>) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        let mut worst = (0.0, None);
        for case in 0..cases {
            let (c, t0, t1) = random_case(&mut rng, case);
            let (ta, va) = max_abs(&c, t0, t1);
            let (tb, vb) = other(&c, t0, t1);
            assert!(
                va.is_finite() && vb.is_finite(),
                "{c:?} on [{t0}, {t1}]: {va} {vb}"
            );
            assert!((t0..=t1).contains(&ta) && (t0..=t1).contains(&tb));
            let rel = (va - vb).abs() / va.max(vb).max(f64::MIN_POSITIVE);
            if rel > worst.0 {
                worst = (rel, Some((c, t0, t1)));
            }
        }
        worst
    }

    fn assert_close(got: f64, want: f64, rel: f64) {
        assert!(
            (got - want).abs() <= rel * want.abs().max(f64::MIN_POSITIVE),
            "got {got:e}, want {want:e}"
        );
    }

    #[test]
    fn known_maxima() {
        // Chebyshev T5 equioscillates: |T5| = 1 at six points of [−1, 1].
        let t5 = [0.0, 5.0, 0.0, -20.0, 0.0, 16.0];
        assert_close(max_abs(&t5, -1.0, 1.0).1, 1.0, 1e-15);
        assert_close(max_abs(&t5, -0.5, 0.5).1, 1.0, 1e-15); // interior cos(π/5)…
        // t(1 − t): interior maximum 1/4 at 1/2.
        let (t, v) = max_abs(&[0.0, 1.0, -1.0], 0.0, 1.0);
        assert_close(t, 0.5, 1e-15);
        assert_close(v, 0.25, 1e-15);
        // (t − 0.3)²: double root of p; max at the far end.
        let sq = from_roots(&[0.3, 0.3], 1.0);
        assert_eq!(max_abs(&sq, 0.0, 1.0), (1.0, eval(&sq, 1.0).abs()));
        // (t − 0.3)³ (t − 0.9)²: p′ has a double root at 0.3.
        let c = from_roots(&[0.3, 0.3, 0.3, 0.9, 0.9], 1.0);
        assert_close(max_abs(&c, 0.0, 1.0).1, sampled_max(&c, 0.0, 1.0), 1e-9);
        // Reversed interval, constants, zero polynomial, empty slice.
        assert_eq!(max_abs(&[0.0, 1.0], 3.0, 1.0), (3.0, 3.0));
        assert_eq!(max_abs(&[-2.5, 0.0, 0.0], 0.0, 1.0), (0.0, 2.5));
        assert_eq!(max_abs(&[0.0; 6], 0.0, 1.0), (0.0, 0.0));
        assert_eq!(max_abs(&[], -1.0, 1.0), (-1.0, 0.0));
        // t0 == t1.
        assert_eq!(max_abs(&t5, 0.5, 0.5), (0.5, eval(&t5, 0.5).abs()));
        // Degree 7: (t² − 1/4)³ t on [−1, 1].
        let c7 = from_roots(&[0.5, 0.5, 0.5, -0.5, -0.5, -0.5, 0.0], 1.0);
        assert_close(max_abs(&c7, -1.0, 1.0).1, 27.0 / 64.0, 1e-14);
    }

    #[test]
    fn scales_and_degree_drops() {
        // 1e6 t⁵ on [0, 1e-3]: max 1e-9 at 1e-3.
        assert_eq!(max_abs(&[0.0, 0.0, 0.0, 0.0, 0.0, 1e6], 0.0, 1e-3).0, 1e-3);
        assert_close(
            max_abs(&[0.0, 0.0, 0.0, 0.0, 0.0, 1e6], 0.0, 1e-3).1,
            1e-9,
            1e-15,
        );
        // A jerk-like quintic on a millisecond: T5 stretched to [0, 1e-3], scaled 1e-9.
        let tau = 5e-4;
        let c: Vec<f64> = from_roots(&[-1.0, 1.0], 1.0) // placeholder to get Vec
            .iter()
            .map(|_| 0.0)
            .collect::<Vec<_>>();
        assert_eq!(c.len(), 3);
        // q(t) = 1e-9 T5((t − τ)/τ): expand by shifting numerically.
        let t5 = [0.0, 5.0, 0.0, -20.0, 0.0, 16.0];
        let mut shifted = vec![0.0; 6];
        // T5((t − τ)/τ) = Σ a_k (t/τ − 1)^k.
        for (k, &a) in t5.iter().enumerate() {
            let term = from_roots(&vec![tau; k], a * 1e-9 / tau.powi(k as i32));
            for (j, &x) in term.iter().enumerate() {
                shifted[j] += x;
            }
        }
        assert_close(max_abs(&shifted, 0.0, 2.0 * tau).1, 1e-9, 1e-9);
        assert_eq!(real_roots(&derivative(&shifted), 0.0, 2.0 * tau).len(), 4);
        // Leading coefficient tiny or zero: degree drops.
        assert_close(max_abs(&[0.0, 1.0, -1.0, 1e-300], 0.0, 1.0).1, 0.25, 1e-15);
        assert_close(
            max_abs(&[0.0, 1.0, -1.0, 0.0, 0.0], 0.0, 1.0).1,
            0.25,
            1e-15,
        );
        assert_close(max_abs(&[0.0, 1.0, -1.0, 1e-17], 0.0, 1.0).1, 0.25, 1e-15);
        // Tiny values and huge values.
        assert_close(
            max_abs(&[0.0, 1e-300, -1e-300], 0.0, 1.0).1,
            0.25e-300,
            1e-14,
        );
        assert_close(max_abs(&[0.0, 1e300, -1e300], 0.0, 1.0).1, 0.25e300, 1e-14);
        // Far from the origin.
        let far = from_roots(&[1000.0, 1000.5, 1001.0], 1.0);
        assert_close(
            max_abs(&far, 1000.0, 1001.0).1,
            sampled_max(&far, 1000.0, 1001.0),
            1e-5, // Horner's rounding at t ≈ 1000 (coefficients ≈ 1e9) is ≈ 1e-7 absolute
        );
    }

    #[test]
    fn non_finite_and_unsupported_input() {
        for (c, t0, t1) in [
            (vec![f64::NAN, 1.0], 0.0, 1.0),
            (vec![1.0, 1.0], f64::NAN, 1.0),
            (vec![1.0, 1.0], 0.0, f64::NAN),
            (vec![1.0, f64::INFINITY], 0.0, 1.0),
            (vec![1.0, 1.0], 0.0, f64::INFINITY),
            (vec![1.0; MAX_DEGREE + 2], 0.0, 1.0),
            (vec![1.0, 2.0, 3.0], -1e308, 1e308),
        ] {
            assert!(max_abs(&c, t0, t1).1.is_nan(), "{c:?} [{t0}, {t1}]");
            assert!(real_roots(&c, t0, t1).is_empty());
        }
        // Degree MAX_DEGREE works.
        let mut c = vec![0.0; MAX_DEGREE + 1];
        c[MAX_DEGREE] = 1.0;
        assert_eq!(max_abs(&c, -1.0, 0.5), (-1.0, 1.0));
    }

    #[test]
    fn known_roots() {
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut checked = 0;
        for _ in 0..3000 {
            let deg = rng.random_range(1..=5);
            let mut roots: Vec<f64> = (0..deg).map(|_| rng.random_range(0.0..1.0)).collect();
            roots.sort_by(f64::total_cmp);
            if roots.windows(2).any(|w| w[1] - w[0] < 1e-3) {
                continue;
            }
            checked += 1;
            let c = from_roots(&roots, rng.random_range(0.5..2.0));
            let found = real_roots(&c, -0.01, 1.01);
            assert_eq!(found.len(), roots.len(), "{roots:?} -> {found:?}");
            for (f, r) in found.iter().zip(&roots) {
                assert!((f - r).abs() < 1e-9, "{roots:?} -> {found:?}");
            }
        }
        assert!(checked > 1000);
        // Roots at the ends, a double root, a triple root, a tight cluster.
        assert_eq!(real_roots(&[0.0, 1.0, -1.0], 0.0, 1.0), vec![0.0, 1.0]);
        let d = real_roots(&from_roots(&[0.3, 0.3], 1.0), 0.0, 1.0);
        assert!(d.len() == 1 && (d[0] - 0.3).abs() < 1e-7, "{d:?}");
        let t = real_roots(&from_roots(&[0.3, 0.3, 0.3], 1.0), 0.0, 1.0);
        assert!(
            !t.is_empty() && t.iter().all(|x| (x - 0.3).abs() < 1e-4),
            "{t:?}"
        );
        let k = real_roots(&from_roots(&[0.5, 0.5 + 1e-6, 0.2], 1.0), 0.0, 1.0);
        assert_eq!(k.len(), 3, "{k:?}");
        assert!(
            (k[1] - 0.5).abs() < 1e-8 && (k[2] - 0.5 - 1e-6).abs() < 1e-8,
            "{k:?}"
        );
        // No roots: constants, zero, x² + 1; t0 == t1.
        assert!(real_roots(&[0.0, 0.0], 0.0, 1.0).is_empty());
        assert!(real_roots(&[3.0], 0.0, 1.0).is_empty());
        assert!(real_roots(&[1.0, 0.0, 1.0], -5.0, 5.0).is_empty());
        assert_eq!(real_roots(&[-0.5, 1.0], 0.5, 0.5), vec![0.5]);
        assert!(real_roots(&[-0.5, 1.0], 0.25, 0.25).is_empty());
        // Reversed interval.
        assert_eq!(real_roots(&[-0.5, 1.0], 1.0, 0.0), vec![0.5]);
    }

    #[test]
    fn sturm_and_bernstein_agree() {
        let mut rng = ChaCha8Rng::seed_from_u64(23);
        let (mut fallbacks, mut checked) = (0, 0);
        let n = 4000;
        for case in 0..n {
            let (c, t0, t1) = random_case(&mut rng, case);
            let q = to_unit(&derivative(&c), t0, t1 - t0).unwrap();
            if q.len() < 3 {
                continue;
            }
            let b = bernstein_roots(&q).unwrap();
            let Some(s) = sturm_roots(&q) else {
                fallbacks += 1;
                continue;
            };
            // Well-conditioned roots (a sign change, |q′| not small) of either
            // method must be found by the other; clusters may be reported
            // differently.
            let dq = derivative(&q);
            let simple = |x: f64| {
                let (l, h) = ((x - 1e-9).max(0.0), (x + 1e-9).min(1.0));
                eval(&dq, x).abs() > 1e-4 && !same_strict_sign(eval(&q, l), eval(&q, h))
            };
            for (mine, theirs) in [(&s, &b), (&b, &s)] {
                for &x in mine.iter().filter(|&&x| simple(x)) {
                    assert!(
                        theirs.iter().any(|y| (x - y).abs() < 1e-9),
                        "{q:?}: {s:?} vs {b:?}"
                    );
                }
            }
            checked += 1;
        }
        // Fallbacks come from double roots of p′ (family 3) mostly.
        println!("sturm fallbacks: {fallbacks} of {n}, {checked} compared");
        assert!(checked > n / 2);
        assert!(fallbacks < n / 3, "{fallbacks} fallbacks");
    }

    #[test]
    fn random_polynomials_match_dense_sampling() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for case in 0..10_000 {
            let (c, t0, t1) = random_case(&mut rng, case);
            let (t, exact) = max_abs(&c, t0, t1);
            let sampled = sampled_max(&c, t0, t1);
            assert!((t0..=t1).contains(&t));
            assert_eq!(exact, eval(&c, t).abs());
            assert!(
                exact >= sampled * (1.0 - 1e-12),
                "case {case}: {exact:e} below sampled {sampled:e} for {c:?} on [{t0}, {t1}]"
            );
            assert!(
                (exact - sampled) / sampled.max(f64::MIN_POSITIVE) <= 1e-9,
                "case {case}: {exact:e} vs sampled {sampled:e} for {c:?} on [{t0}, {t1}]"
            );
        }
    }

    #[test]
    fn cross_test_against_itself_is_exact() {
        let (worst, _) = cross_test_against(max_abs, 500, 3);
        assert_eq!(worst, 0.0);
    }

    /// The verifier and the search find the same maxima by different
    /// methods (Sturm / Bernstein here, derivative roots and safeguarded
    /// Newton in `extrema`): seeded random polynomials of degree 1 to 5.
    #[test]
    fn agrees_with_the_search_root_finder() {
        let (worst, case) = cross_test_against(crate::extrema::argmax_abs_on_interval, 40_000, 1);
        assert!(worst <= 1e-9, "{worst:e} at {case:?}");
    }
}
