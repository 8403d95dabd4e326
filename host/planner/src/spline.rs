//! C3 piecewise-quintic joint splines in Hermite form.
//!
//! Each segment k (knot k → k+1, duration h_k) of joint j is the quintic
//! Hermite interpolant of (position, velocity, acceleration) at both ends, so
//! positions, C1 and C2 hold by construction. The unknowns of joint j are the
//! velocities and accelerations at the interior knots (ends are at rest):
//! x_j = (v_1..v_{n−2}, a_1..a_{n−2}). C3 (jerk continuity at interior knots)
//! and zero jerk at both ends are linear equalities in x_j for fixed h.
//!
//! Every derivative of order r at normalised time u ∈ [0, 1] of segment k is
//! affine in x_j with coefficients that depend on h_k alone:
//! q^(r)(t_k + u h_k) = Σ_m H_m^(r)(u) h_k^(e_m − r) w_m, with
//! w = (p_k, v_k, a_k, p_k+1, v_k+1, a_k+1) and e = (0, 1, 2, 0, 1, 2).

// Index loops over joints and segments mirror the maths.
#![allow(clippy::needless_range_loop)]

use triquint_shared::quintic::eval_poly;

/// Power coefficients (in u) of the quintic Hermite basis H_0..H_5.
const BASIS: [[f64; 6]; 6] = [
    [1.0, 0.0, 0.0, -10.0, 15.0, -6.0],
    [0.0, 1.0, 0.0, -6.0, 8.0, -3.0],
    [0.0, 0.0, 0.5, -1.5, 1.5, -0.5],
    [0.0, 0.0, 0.0, 10.0, -15.0, 6.0],
    [0.0, 0.0, 0.0, -4.0, 7.0, -3.0],
    [0.0, 0.0, 0.0, 0.5, -1.0, 0.5],
];
/// Power of h that scales each Hermite datum: positions h⁰, velocities h¹, accelerations h².
const EXP: [i32; 6] = [0, 1, 2, 0, 1, 2];

/// An affine form of one joint's unknowns and its segment's duration:
/// value at the current point, ∂/∂x_j (up to four entries), and ∂/∂h_k.
#[derive(Clone, Copy, Debug, Default)]
pub struct Affine {
    pub value: f64,
    pub dx: [(usize, f64); 4],
    pub ndx: usize,
    pub dh: f64,
}

impl Affine {
    pub fn dx(&self) -> &[(usize, f64)] {
        &self.dx[..self.ndx]
    }
}

/// Joint-space knots (the IK images of the via-points) of a plan.
#[derive(Clone, Debug)]
pub struct Knots {
    /// q[i][j]: joint j at knot i (m).
    pub q: Vec<[f64; 3]>,
}

impl Knots {
    pub fn len(&self) -> usize {
        self.q.len()
    }
    pub fn segments(&self) -> usize {
        self.q.len() - 1
    }
    /// Unknowns per joint: v and a at each interior knot.
    pub fn vars(&self) -> usize {
        2 * (self.q.len() - 2)
    }

    /// Index of knot `i`'s datum of `kind` (1 velocity, 2 acceleration) in x_j,
    /// or None at the rest ends.
    fn var(&self, i: usize, kind: usize) -> Option<usize> {
        let n = self.q.len();
        if i == 0 || i == n - 1 {
            None
        } else {
            Some((kind - 1) * (n - 2) + (i - 1))
        }
    }

    /// Hermite datum `m` of segment `k` of joint `j`. Positions enter as
    /// the start and the change over the segment (H₀ = 1 − H₃), not as two
    /// absolute positions: their difference is small, and on short segments
    /// the absolute terms q/h³ would swamp the jerk in rounding error.
    fn datum(&self, x: &[f64], j: usize, k: usize, m: usize) -> f64 {
        match m {
            0 => self.q[k][j],
            3 => self.q[k + 1][j] - self.q[k][j],
            _ => self.var(k + m / 3, m % 3).map_or(0.0, |v| x[v]),
        }
    }

    /// Derivative of order `r` of joint `j` at normalised time `u` of segment `k`.
    pub fn functional(&self, x: &[f64], j: usize, k: usize, u: f64, r: usize, h: f64) -> Affine {
        let mut out = Affine::default();
        for (m, basis) in BASIS.iter().enumerate() {
            // Start position: H₀ + H₃ = 1, so only its value (r = 0) remains.
            let b = if m == 0 {
                if r == 0 { 1.0 } else { 0.0 }
            } else {
                let b = eval_poly(basis, u);
                if r < 4 {
                    b[r]
                } else {
                    quartic_plus(basis, u, r)
                }
            };
            if b == 0.0 {
                continue;
            }
            let e = EXP[m] - r as i32;
            let mult = b * h.powi(e);
            let dmult = e as f64 * b * h.powi(e - 1);
            let datum = self.datum(x, j, k, m);
            out.value += mult * datum;
            out.dh += dmult * datum;
            if m % 3 > 0
                && let Some(v) = self.var(k + m / 3, m % 3)
            {
                out.dx[out.ndx] = (v, mult);
                out.ndx += 1;
            }
        }
        out
    }

    /// Power coefficients in segment-local time t of joint j on segment k.
    pub fn coefficients(&self, x: &[f64], j: usize, k: usize, h: f64) -> [f64; 6] {
        let mut c = [0.0; 6];
        c[0] = self.q[k][j];
        for (m, basis) in BASIS.iter().enumerate().skip(1) {
            let datum = self.datum(x, j, k, m) * h.powi(EXP[m]);
            for (ci, bi) in c.iter_mut().zip(basis) {
                *ci += datum * bi;
            }
        }
        for (p, ci) in c.iter_mut().enumerate() {
            *ci /= h.powi(p as i32);
        }
        c
    }
}

/// Fourth and fifth derivatives (not needed by the limits, kept for completeness).
fn quartic_plus(c: &[f64; 6], u: f64, r: usize) -> f64 {
    match r {
        4 => 24.0 * c[4] + 120.0 * c[5] * u,
        5 => 120.0 * c[5],
        _ => 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn functional_matches_coefficients_and_h_derivative() {
        let knots = Knots {
            q: vec![
                [0.1, 0.2, 0.3],
                [0.15, 0.1, 0.32],
                [0.2, 0.05, 0.3],
                [0.18, 0.1, 0.25],
            ],
        };
        let x = [0.05, -0.02, 0.3, -0.1];
        for k in 0..3 {
            let h = 0.4 + 0.1 * k as f64;
            let c = knots.coefficients(&x, 1, k, h);
            for r in 0..4 {
                for u in [0.0, 0.3, 1.0] {
                    let f = knots.functional(&x, 1, k, u, r, h);
                    let direct = eval_poly(&c, u * h)[r];
                    assert!((f.value - direct).abs() < 1e-12 * (1.0 + direct.abs()));
                    let eps = 1e-6;
                    let fd = (knots.functional(&x, 1, k, u, r, h + eps).value
                        - knots.functional(&x, 1, k, u, r, h - eps).value)
                        / (2.0 * eps);
                    assert!(
                        (f.dh - fd).abs() < 1e-5 * (1.0 + fd.abs()),
                        "{} vs {fd}",
                        f.dh
                    );
                    // Affine in x: the value is the sum of the linear terms plus the positions.
                    let lin: f64 = f.dx().iter().map(|&(v, a)| a * x[v]).sum();
                    let zero = knots.functional(&[0.0; 4], 1, k, u, r, h).value;
                    assert!((zero + lin - f.value).abs() < 1e-12);
                }
            }
        }
    }
}
