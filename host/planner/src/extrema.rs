//! Exact extrema and absolute integrals of low-degree polynomials on an
//! interval: the functions of [`triquint_shared::plan::extrema`] (where the
//! link computes a plan's maxima the same way), tested here against dense
//! sampling and Sturm sequences.

pub use triquint_shared::plan::extrema::{
    antiderivative, argmax_abs_on_interval, derivative, eval, integral_abs_on_interval,
    max_abs_on_interval, roots_in,
};

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    // One dense-sampling reference and one root-to-coefficient helper for
    // both root finders' tests.
    use crate::sturm::tests::{from_roots, sampled_max};

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
