//! Quintic segments: q_j(t) = Σ_k c_jk t^k on segment-local time t ∈ [0, h],
//! evaluated by Horner's rule with no allocation, in f32 or f64.
//!
//! Segment-local time keeps t ≤ h (about a second), so f32 loses nothing to a
//! large absolute time; the position stays accurate to well under 1 µm.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::{Real, c};

/// Position, velocity, acceleration and jerk of all three joints.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct JointMotion<T: Real> {
    pub q: Vector3<T>,
    pub qd: Vector3<T>,
    pub qdd: Vector3<T>,
    pub qddd: Vector3<T>,
}

impl<T: Real> Default for JointMotion<T> {
    fn default() -> Self {
        Self {
            q: Vector3::zeros(),
            qd: Vector3::zeros(),
            qdd: Vector3::zeros(),
            qddd: Vector3::zeros(),
        }
    }
}

/// Value and first three derivatives of one quintic at `t`, by Horner's rule.
#[inline]
pub fn eval_poly<T: Real>(k: &[T; 6], t: T) -> [T; 4] {
    let p = ((((k[5] * t + k[4]) * t + k[3]) * t + k[2]) * t + k[1]) * t + k[0];
    let v =
        (((k[5] * c(5.0) * t + k[4] * c(4.0)) * t + k[3] * c(3.0)) * t + k[2] * c(2.0)) * t + k[1];
    let a = ((k[5] * c(20.0) * t + k[4] * c(12.0)) * t + k[3] * c(6.0)) * t + k[2] * c(2.0);
    let j = (k[5] * c(60.0) * t + k[4] * c(24.0)) * t + k[3] * c(6.0);
    [p, v, a, j]
}

/// One segment of a plan: three joints' quintic coefficients and the duration.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quintic<T: Real> {
    /// `coeffs[j][k]`: coefficient of t^k for joint j (m/s^k).
    pub coeffs: [[T; 6]; 3],
    /// Segment duration h (s).
    pub duration: T,
}

impl<T: Real> Quintic<T> {
    /// Motion at segment-local time `t`, clamped into [0, duration].
    pub fn eval(&self, t: T) -> JointMotion<T> {
        let t = if t < T::zero() {
            T::zero()
        } else if t > self.duration {
            self.duration
        } else {
            t
        };
        let mut out = JointMotion::default();
        for j in 0..3 {
            let [p, v, a, jk] = eval_poly(&self.coeffs[j], t);
            out.q[j] = p;
            out.qd[j] = v;
            out.qdd[j] = a;
            out.qddd[j] = jk;
        }
        out
    }

    /// Motion at the segment's end.
    pub fn end(&self) -> JointMotion<T> {
        self.eval(self.duration)
    }
}

impl Quintic<f64> {
    /// The same segment in working precision `U` (f32 on the drives).
    pub fn cast<U: Real>(&self) -> Quintic<U> {
        Quintic {
            coeffs: self.coeffs.map(|row| row.map(c)),
            duration: c(self.duration),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    #[test]
    fn horner_matches_power_sum_and_derivatives() {
        let k = [0.3, -0.2, 0.5, 1.5, -2.0, 0.7];
        for i in 0..=20 {
            let t = i as f64 * 0.05;
            let [p, v, a, j] = eval_poly(&k, t);
            let power = |d: usize| -> f64 {
                (d..6)
                    .map(|n| {
                        let fall: f64 = (0..d).map(|m| (n - m) as f64).product();
                        k[n] * fall * t.powi((n - d) as i32)
                    })
                    .sum()
            };
            assert!((p - power(0)).abs() < 1e-14);
            assert!((v - power(1)).abs() < 1e-13);
            assert!((a - power(2)).abs() < 1e-12);
            assert!((j - power(3)).abs() < 1e-12);
        }
    }

    /// f32 drives against the f64 host model: random segments spanning the
    /// paper's limits (|v| ≤ 0.5, |a| ≤ 1.2, |jerk| ≤ 5) and workspace (q ≤ 0.7 m).
    #[test]
    fn f32_evaluation_tracks_f64() {
        let mut rng = ChaCha8Rng::seed_from_u64(20);
        let (mut wp, mut wv, mut wa): (f64, f64, f64) = (0.0, 0.0, 0.0);
        for _ in 0..20_000 {
            let h: f64 = rng.random_range(0.05..1.5);
            let q0: f64 = rng.random_range(0.0..0.7);
            let v0: f64 = rng.random_range(-0.5..0.5);
            let a0: f64 = rng.random_range(-1.2..1.2);
            let j0: f64 = rng.random_range(-5.0..5.0);
            // Higher terms sized so the jerk stays within ±5 m/s³ over the segment.
            let c4: f64 = rng.random_range(-1.0..1.0) * 5.0 / (24.0 * h);
            let c5: f64 = rng.random_range(-1.0..1.0) * 5.0 / (60.0 * h * h);
            let seg = Quintic {
                coeffs: [[q0, v0, a0 / 2.0, j0 / 6.0, c4, c5]; 3],
                duration: h,
            };
            let seg32: Quintic<f32> = seg.cast();
            let (vmax, amax) = (0..=16).fold((1e-3f64, 1e-3f64), |(vm, am), i| {
                let m = seg.eval(h * i as f64 / 16.0);
                (vm.max(m.qd[0].abs()), am.max(m.qdd[0].abs()))
            });
            for i in 0..=64 {
                let t = h * i as f64 / 64.0;
                let a = seg.eval(t);
                let b = seg32.eval(t as f32);
                wp = wp.max((a.q[0] - b.q[0] as f64).abs());
                wv = wv.max((a.qd[0] - b.qd[0] as f64).abs() / vmax);
                wa = wa.max((a.qdd[0] - b.qdd[0] as f64).abs() / amax);
            }
        }
        std::eprintln!(
            "f32 vs f64 quintic: position {wp:e} m, velocity {wv:e}, acceleration {wa:e} of peak"
        );
        assert!(wp < 1e-6, "position error {wp:e} m");
        assert!(wv < 1e-5, "velocity error {wv:e} of the segment's peak");
        assert!(wa < 1e-5, "acceleration error {wa:e} of the segment's peak");
    }

    #[test]
    fn eval_clamps_time() {
        let seg = Quintic {
            coeffs: [[1.0, 1.0, 0.0, 0.0, 0.0, 0.0]; 3],
            duration: 2.0,
        };
        assert_eq!(seg.eval(-1.0).q[0], 1.0);
        assert_eq!(seg.eval(5.0).q[0], 3.0);
        assert_eq!(seg.end().qd[1], 1.0);
    }
}
