//! Least-change corrections Δ = Eᵀ(EEᵀ)⁻¹r for a sparse E whose rows, in
//! order, touch only variables near one another: EEᵀ is banded, so the
//! solve is O(rows · band²) in time and O(rows · band) in memory. Each
//! spline's C3 and end-jerk conditions are such an E (a condition at knot i
//! involves the knots i − 1, i, i + 1), where a dense QR of Eᵀ grew as n³
//! in time and n² in memory.

// Index loops over the band mirror the factorisation's formulas.
#![allow(clippy::needless_range_loop)]

/// Rows of E, each a few (column, value) entries; rows more than `BAND`
/// apart share no column.
pub(crate) struct Rows {
    rows: Vec<Vec<(usize, f64)>>,
    /// LDLᵀ of the row-normalised EEᵀ: d and the `BAND` sub-diagonals of L
    /// per row (l[i][b] is L[i][i − 1 − b]).
    d: Vec<f64>,
    l: Vec<[f64; BAND]>,
    /// Row norms (the rows are normalised before EEᵀ is formed: the
    /// least-change solution is the same, the conditioning is better).
    norm: Vec<f64>,
}

/// Half-bandwidth of EEᵀ.
pub(crate) const BAND: usize = 2;

impl Rows {
    /// Factors EEᵀ; None if it is singular (E without full row rank).
    pub(crate) fn new(rows: Vec<Vec<(usize, f64)>>) -> Option<Rows> {
        let n = rows.len();
        let norm: Vec<f64> = rows
            .iter()
            .map(|r| r.iter().map(|(_, v)| v * v).sum::<f64>().sqrt())
            .collect();
        if norm.iter().any(|&x| !(x > 0.0 && x.is_finite())) {
            return None;
        }
        let dot = |i: usize, k: usize| -> f64 {
            let mut s = 0.0;
            for &(c, a) in &rows[i] {
                for &(c2, b) in &rows[k] {
                    if c == c2 {
                        s += a * b;
                    }
                }
            }
            s / (norm[i] * norm[k])
        };
        let mut d = vec![0.0; n];
        let mut l = vec![[0.0; BAND]; n];
        for i in 0..n {
            // L[i][k] for k = i − BAND .. i − 1, then d[i].
            for b in (0..BAND).rev() {
                let Some(k) = i.checked_sub(b + 1) else {
                    continue;
                };
                let mut s = dot(i, k);
                for b2 in (b + 1)..BAND {
                    // Column m = i − 1 − b2 < k, within both rows' bands.
                    let Some(m) = i.checked_sub(b2 + 1) else {
                        continue;
                    };
                    if let Some(bk) = (k - m).checked_sub(1).filter(|&x| x < BAND) {
                        s -= l[i][b2] * l[k][bk] * d[m];
                    }
                }
                l[i][b] = s / d[k];
            }
            let s = dot(i, i)
                - (0..BAND)
                    .filter(|&b| i > b)
                    .map(|b| l[i][b] * l[i][b] * d[i - 1 - b])
                    .sum::<f64>();
            // Rows are normalised, so a pivot this small is a dependent row.
            if s.is_nan() || s <= 1e-14 {
                return None;
            }
            d[i] = s;
        }
        Some(Rows { rows, d, l, norm })
    }

    /// Δ with EΔ = r of least norm, added into `out` with weight −1
    /// (out ← out − Δ).
    pub(crate) fn subtract_correction(&self, r: &[f64], out: &mut [f64]) {
        let n = self.rows.len();
        // (D⁻¹E)(D⁻¹E)ᵀ y = D⁻¹ r, then Δ = (D⁻¹E)ᵀ y.
        let mut y: Vec<f64> = (0..n).map(|i| r[i] / self.norm[i]).collect();
        for i in 0..n {
            for b in 0..BAND {
                if i > b {
                    y[i] -= self.l[i][b] * y[i - 1 - b];
                }
            }
        }
        for i in 0..n {
            y[i] /= self.d[i];
        }
        for i in (0..n).rev() {
            for b in 0..BAND {
                if i + b + 1 < n {
                    y[i] -= self.l[i + b + 1][b] * y[i + b + 1];
                }
            }
        }
        for (i, row) in self.rows.iter().enumerate() {
            for &(c, a) in row {
                out[c] -= a / self.norm[i] * y[i];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{DMatrix, DVector};

    #[test]
    fn matches_the_dense_least_change_solution() {
        // Rows i touch columns 2i-2 .. 2i+3 (like the spline's conditions).
        let n = 9;
        let cols = 2 * n + 2;
        let mut rows = Vec::new();
        let mut dense = DMatrix::<f64>::zeros(n, cols);
        for i in 0..n {
            let mut row = Vec::new();
            for c in (2 * i).saturating_sub(2)..(2 * i + 4).min(cols) {
                let v = ((i * 7 + c * 3) % 11) as f64 - 5.0 + 0.1 * c as f64;
                row.push((c, v * 10f64.powi(i as i32 % 4)));
                dense[(i, c)] = row.last().unwrap().1;
            }
            rows.push(row);
        }
        let r: Vec<f64> = (0..n).map(|i| (i as f64 * 0.37).sin()).collect();
        let e = Rows::new(rows).unwrap();
        let mut delta = vec![0.0; cols];
        e.subtract_correction(&r, &mut delta);
        let eet = &dense * dense.transpose();
        let y = eet.lu().solve(&DVector::from_vec(r.clone())).unwrap();
        let want = dense.transpose() * y;
        for c in 0..cols {
            assert!(
                (-delta[c] - want[c]).abs() < 1e-9 * (1.0 + want[c].abs()),
                "{c}"
            );
        }
        // And EΔ = r.
        let back = &dense * DVector::from_vec(delta.iter().map(|v| -v).collect());
        for i in 0..n {
            assert!((back[i] - r[i]).abs() < 1e-9);
        }
    }
}
