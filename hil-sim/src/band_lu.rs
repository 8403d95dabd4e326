//! LU with partial pivoting of a banded matrix, in O(n · band²) time and
//! O(n · band) memory where a dense LU is O(n³) and O(n²): a spline's C4
//! system is banded, and the long fixtures have thousands of knots.
//!
//! The arithmetic is nalgebra's dense `LU::new` and `LU::solve` with the
//! entries that are structurally zero left out: the same pivot (the first
//! largest |entry| of the column, and below the band the column is zero),
//! multipliers by the pivot's reciprocal, each entry's updates in the same
//! order, the row interchanges applied to the right-hand side step by step
//! (the same operations on each value as permuting it first; a + b is
//! b + a in IEEE arithmetic, so `+=` is nalgebra's axpy). So the
//! fixtures it builds are the dense LU's to the bit (the test below checks
//! it against nalgebra on random banded systems).

/// A square matrix with `kl` sub- and `ku` super-diagonals; each row stores
/// the columns r − kl ..= r + kl + ku, room for the pivoting's fill.
#[derive(Clone, Debug)]
pub(crate) struct Banded {
    n: usize,
    kl: usize,
    ku: usize,
    a: Vec<f64>,
}

/// [`Banded::lu`]: U in the rows' storage, L by elimination step.
pub(crate) struct BandLu {
    u: Banded,
    /// The multipliers of step i for the rows i + 1 ..= i + kl.
    l: Vec<f64>,
    /// The row interchanged with row i at step i.
    piv: Vec<usize>,
}

impl Banded {
    pub(crate) fn zeros(n: usize, kl: usize, ku: usize) -> Self {
        Self {
            n,
            kl,
            ku,
            a: vec![0.0; n * (2 * kl + ku + 1)],
        }
    }

    fn width(&self) -> usize {
        2 * self.kl + self.ku + 1
    }

    /// Storage index of (r, c); c must lie within the row's stored columns.
    fn at(&self, r: usize, c: usize) -> usize {
        debug_assert!(
            c + self.kl >= r && c <= r + self.kl + self.ku,
            "({r}, {c}) off the band"
        );
        r * self.width() + c + self.kl - r
    }

    /// The stored columns of row r.
    fn cols(&self, r: usize) -> std::ops::RangeInclusive<usize> {
        r.saturating_sub(self.kl)..=(r + self.kl + self.ku).min(self.n - 1)
    }

    pub(crate) fn get(&self, r: usize, c: usize) -> f64 {
        self.a[self.at(r, c)]
    }

    pub(crate) fn add(&mut self, r: usize, c: usize, v: f64) {
        assert!(
            c + self.kl >= r && c <= r + self.ku,
            "({r}, {c}) outside the band"
        );
        let i = self.at(r, c);
        self.a[i] += v;
    }

    /// The largest |entry| of row r.
    pub(crate) fn row_amax(&self, r: usize) -> f64 {
        self.cols(r)
            .fold(0.0, |m: f64, c| m.max(self.get(r, c).abs()))
    }

    /// Row r divided by `s`.
    pub(crate) fn unscale_row(&mut self, r: usize, s: f64) {
        for c in self.cols(r) {
            let i = self.at(r, c);
            self.a[i] /= s;
        }
    }

    /// The product with x, each row summed in column order.
    pub(crate) fn mul(&self, x: &[f64]) -> Vec<f64> {
        (0..self.n)
            .map(|r| {
                let mut cols = self.cols(r);
                let first = cols.next().map_or(0.0, |c| self.get(r, c) * x[c]);
                cols.fold(first, |y, c| self.get(r, c) * x[c] + y)
            })
            .collect()
    }

    /// Factors it (as nalgebra's `LU::new`: a zero pivot column is skipped,
    /// and then [`BandLu::solve`] gives None).
    pub(crate) fn lu(self) -> BandLu {
        let (n, kl, ku) = (self.n, self.kl, self.ku);
        let mut a = self;
        let mut l = vec![0.0; n * kl];
        let mut piv: Vec<usize> = (0..n).collect();
        for i in 0..n {
            let last = (i + kl).min(n - 1);
            let mut p = i;
            let mut max = a.get(i, i).abs();
            for r in i + 1..=last {
                if a.get(r, i).abs() > max {
                    max = a.get(r, i).abs();
                    p = r;
                }
            }
            let diag = a.get(p, i);
            if diag == 0.0 {
                continue;
            }
            let right = (i + kl + ku).min(n - 1);
            if p != i {
                piv[i] = p;
                for c in i..=right {
                    let (x, y) = (a.at(i, c), a.at(p, c));
                    a.a.swap(x, y);
                }
            }
            let inv = 1.0 / diag;
            for r in i + 1..=last {
                l[i * kl + (r - i - 1)] = a.get(r, i) * inv;
            }
            for c in i + 1..=right {
                let u = -a.get(i, c);
                for r in i + 1..=last {
                    let k = a.at(r, c);
                    a.a[k] += u * l[i * kl + (r - i - 1)];
                }
            }
        }
        BandLu { u: a, l, piv }
    }
}

impl BandLu {
    /// x with A x = b; None when a pivot is zero.
    pub(crate) fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        let (n, kl, ku) = (self.u.n, self.u.kl, self.u.ku);
        let mut x = b.to_vec();
        for i in 0..n {
            x.swap(i, self.piv[i]);
            let c = -x[i];
            for r in i + 1..=(i + kl).min(n - 1) {
                x[r] += c * self.l[i * kl + (r - i - 1)];
            }
        }
        for i in (0..n).rev() {
            let d = self.u.get(i, i);
            if d == 0.0 {
                return None;
            }
            let c = x[i] / d;
            x[i] = c;
            for r in i.saturating_sub(kl + ku)..i {
                x[r] += -c * self.u.get(r, i);
            }
        }
        Some(x)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};

    /// On random banded systems, some with rows scaled far apart (pivots
    /// off the diagonal), the factors and solutions are nalgebra's dense
    /// LU's to the bit.
    #[test]
    fn it_is_the_dense_lu_to_the_bit() {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(35);
        for case in 0..200 {
            let n = rng.random_range(1..40);
            let (kl, ku) = (rng.random_range(0..4), rng.random_range(0..4));
            let mut band = Banded::zeros(n, kl, ku);
            let mut dense = nalgebra::DMatrix::<f64>::zeros(n, n);
            for r in 0..n {
                let scale = if case % 2 == 0 {
                    1.0
                } else {
                    10f64.powi(rng.random_range(-5..5))
                };
                for c in r.saturating_sub(kl)..=(r + ku).min(n - 1) {
                    let v = scale * rng.random_range(-1.0..1.0);
                    band.add(r, c, v);
                    dense[(r, c)] += v;
                }
            }
            let b: Vec<f64> = (0..n).map(|_| rng.random_range(-1.0..1.0)).collect();
            let product = band.mul(&b);
            let dense_product = &dense * nalgebra::DVector::from_vec(b.clone());
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(
                bits(&product),
                bits(dense_product.as_slice()),
                "case {case}: A x"
            );
            let x = band.lu().solve(&b);
            let dense_x = dense.lu().solve(&nalgebra::DVector::from_vec(b));
            match (x, dense_x) {
                (Some(x), Some(d)) => assert_eq!(bits(&x), bits(d.as_slice()), "case {case}"),
                (x, d) => assert_eq!(x.is_some(), d.is_some(), "case {case}"),
            }
        }
    }
}
