//! The machine's ceilings, held by the drive from its own configuration
//! whatever the host sends (docs/protocol.md, "Ceilings"): a segment whose
//! exact maxima exceed them, whose maxima scaled to the override cap would,
//! or on which a stop or hold ramp would exceed the stop budget, is refused
//! on the receive side with a code naming which.

use triquint_shared::protocol::config::{SMOOTHSTEP_MAX_D1, SMOOTHSTEP_MAX_D2};
use triquint_shared::protocol::contract::RELATIVE_LIMIT_MARGIN;
use triquint_shared::protocol::{DriveConfig, Reject};

use crate::segment::Seg;

/// Bisection steps on u ∈ [0, 1]: f32's 24-bit mantissa.
const BISECT_STEPS: usize = 24;

/// Largest |q′|, |q″|, |q‴| over the three joints of a segment (m/s,
/// m/s², m/s³), exact up to f32 rounding.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Maxima {
    pub v: f32,
    pub a: f32,
    pub j: f32,
}

/// Σ c_k u^k by Horner's rule (`c` lowest power first).
fn poly(c: &[f32], u: f32) -> f32 {
    c.iter().rev().fold(0.0, |acc, x| acc * u + x)
}

/// The root of `c` in (lo, hi) where it changes sign there (monotone on
/// it: at most one), by bisection.
fn root_in(c: &[f32], lo: f32, hi: f32) -> Option<f32> {
    let (mut lo, mut hi) = (lo, hi);
    let (flo, fhi) = (poly(c, lo), poly(c, hi));
    if flo == 0.0 || fhi == 0.0 || (flo < 0.0) == (fhi < 0.0) {
        return None;
    }
    for _ in 0..BISECT_STEPS {
        let mid = 0.5 * (lo + hi);
        if (poly(c, mid) < 0.0) == (flo < 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// The roots in (0, 1) of `c`, given the points (sorted, 0 and 1
/// included) between which it is monotone, sorted and with 0 and 1: the
/// points between which its antiderivative is monotone. Returns how many.
fn roots(c: &[f32], pieces: &[f32], out: &mut [f32; 6]) -> usize {
    let inner = pieces.windows(2).filter_map(|w| match *w {
        [lo, hi] => root_in(c, lo, hi),
        _ => None,
    });
    let mut n = 0;
    for x in core::iter::once(0.0)
        .chain(inner)
        .chain(core::iter::once(1.0))
    {
        if let Some(slot) = out.get_mut(n) {
            *slot = x;
            n += 1;
        }
    }
    n
}

/// Largest |c(u)| over the points.
fn largest(c: &[f32], points: &[f32]) -> f32 {
    points.iter().fold(0.0f32, |m, u| m.max(poly(c, *u).abs()))
}

impl Maxima {
    /// Of a queued segment, in normalised time u = t/h: q‴ is a quadratic,
    /// so q″ is monotone between q⁗'s root and the ends, q′ between q‴'s
    /// roots; each derivative peaks at an end or at a root of the next.
    pub fn of(seg: &Seg) -> Self {
        let ih = seg.inv_h;
        let mut m = [0.0f32; 3];
        for b in &seg.b {
            let d1 = [b[1], 2.0 * b[2], 3.0 * b[3], 4.0 * b[4], 5.0 * b[5]];
            let d2 = [2.0 * b[2], 6.0 * b[3], 12.0 * b[4], 20.0 * b[5]];
            let d3 = [6.0 * b[3], 24.0 * b[4], 60.0 * b[5]];
            let d4 = [24.0 * b[4], 120.0 * b[5]];
            let (mut p4, mut p3, mut p2) = ([0.0; 6], [0.0; 6], [0.0; 6]);
            // `get` rather than slicing: no panic path on the receive side.
            let n4 = roots(&d4, &[0.0, 1.0], &mut p4);
            let p4 = p4.get(..n4).unwrap_or(&[]);
            let n3 = roots(&d3, p4, &mut p3);
            let p3 = p3.get(..n3).unwrap_or(&[]);
            let n2 = roots(&d2, p3, &mut p2);
            let p2 = p2.get(..n2).unwrap_or(&[]);
            m[0] = m[0].max(largest(&d1, p2));
            m[1] = m[1].max(largest(&d2, p3));
            m[2] = m[2].max(largest(&d3, p4));
        }
        Self {
            v: m[0] * ih,
            a: m[1] * ih * ih,
            j: m[2] * ih * ih * ih,
        }
    }

    /// Held to `cfg`'s ceilings (with [`RELATIVE_LIMIT_MARGIN`]):
    /// - the segment itself: v, a, j;
    /// - at the override cap σ: σv, σ²a, σ³j;
    /// - its stop ramps T (controlled T_s, quick T_q) at the cap: the
    ///   time-scaling's own jerk terms, v·max|S″|/T² and 3a·σ·max|S′|/T,
    ///   each within the share of the stop budget the host's sizing gives
    ///   it (`stop_ramp::stop_time`; docs/protocol.md, "Ceilings"):
    ///   1.5 and 3 × `ceiling_jerk` for T_s, 3 and 6 × for T_q.
    ///
    /// NaN anywhere fails.
    pub fn check(&self, cfg: &DriveConfig) -> Result<(), Reject> {
        let k = 1.0 + RELATIVE_LIMIT_MARGIN;
        let (cv, ca, cj) = (
            cfg.ceiling_velocity * k,
            cfg.ceiling_acceleration * k,
            cfg.ceiling_jerk * k,
        );
        let within = |x: f32, c: f32| x <= c;
        if !within(self.v, cv) {
            return Err(Reject::AboveVelocityCeiling);
        }
        if !within(self.a, ca) {
            return Err(Reject::AboveAccelerationCeiling);
        }
        if !within(self.j, cj) {
            return Err(Reject::AboveJerkCeiling);
        }
        let s = cfg.override_cap;
        if !(within(s * self.v, cv) && within(s * s * self.a, ca) && within(s * s * s * self.j, cj))
        {
            return Err(Reject::OverrideAboveCeiling);
        }
        let d1 = SMOOTHSTEP_MAX_D1 as f32;
        let d2 = SMOOTHSTEP_MAX_D2 as f32;
        let ramp_ok = |t: f32, share: f32| {
            within(self.v * d2, share * cj * t * t)
                && within(3.0 * self.a * s * d1, 2.0 * share * cj * t)
        };
        if !(ramp_ok(cfg.stop_time, 1.5) && ramp_ok(cfg.quick_stop_time, 3.0)) {
            return Err(Reject::StopAboveCeiling);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use triquint_shared::protocol::config::DriveSettings;
    use triquint_shared::{Limits, Robot};

    fn seg(b: [[f32; 6]; 3], h: f32) -> Seg {
        Seg {
            seq: 0,
            start_ns: 0,
            duration_us: (h * 1e6) as u32,
            inv_h: 1.0 / h,
            b,
            first: true,
            last: false,
            crc: 0,
        }
    }

    /// Largest |q′|, |q″|, |q‴| on a grid of n + 1 points (f64).
    fn sampled(s: &Seg, n: usize) -> [f64; 3] {
        let ih = s.inv_h as f64;
        let mut m = [0.0f64; 3];
        for b in &s.b {
            let b = b.map(|x| x as f64);
            for i in 0..=n {
                let u = i as f64 / n as f64;
                let v =
                    b[1] + u * (2.0 * b[2] + u * (3.0 * b[3] + u * (4.0 * b[4] + u * 5.0 * b[5])));
                let a = 2.0 * b[2] + u * (6.0 * b[3] + u * (12.0 * b[4] + u * 20.0 * b[5]));
                let j = 6.0 * b[3] + u * (24.0 * b[4] + u * 60.0 * b[5]);
                m[0] = m[0].max(v.abs() * ih);
                m[1] = m[1].max(a.abs() * ih * ih);
                m[2] = m[2].max(j.abs() * ih * ih * ih);
            }
        }
        m
    }

    #[test]
    fn maxima_are_the_exact_peaks() {
        let mut rng = ChaCha8Rng::seed_from_u64(36);
        for _ in 0..300 {
            let b: [[f32; 6]; 3] =
                core::array::from_fn(|_| core::array::from_fn(|_| rng.random_range(-0.2..0.2)));
            let s = seg(b, rng.random_range(0.05..2.0));
            let got = Maxima::of(&s);
            let dense = sampled(&s, 20_000);
            for (g, d) in [got.v, got.a, got.j].into_iter().zip(dense) {
                let g = g as f64;
                // Never below the peak (beyond f32 rounding), never above it.
                assert!(g >= d * (1.0 - 1e-5) - 1e-9, "{g} < {d}");
                assert!(g <= d * (1.0 + 1e-5) + 1e-9, "{g} > {d}");
            }
        }
    }

    /// q = 0.3 + t³/6 on every joint over 1 s: v ½, a 1, jerk 1.
    fn cubic() -> Seg {
        seg([[0.3, 0.0, 0.0, 1.0 / 6.0, 0.0, 0.0]; 3], 1.0)
    }

    fn config() -> DriveConfig {
        let mut c = DriveConfig::new(
            &Robot::default(),
            &Limits::default(),
            0,
            &DriveSettings::default(),
            2.0,
            1.5,
        );
        (c.ceiling_velocity, c.ceiling_acceleration, c.ceiling_jerk) = (0.5, 1.0, 1.0);
        c
    }

    #[test]
    fn each_ceiling_refuses_with_its_own_code() {
        let m = Maxima::of(&cubic());
        assert_eq!(m.check(&config()), Ok(()));
        type Change = fn(&mut DriveConfig);
        let cases: [(Change, Reject); 6] = [
            (|c| c.ceiling_velocity *= 0.98, Reject::AboveVelocityCeiling),
            (
                |c| c.ceiling_acceleration *= 0.98,
                Reject::AboveAccelerationCeiling,
            ),
            (|c| c.ceiling_jerk *= 0.98, Reject::AboveJerkCeiling),
            // At σ = 1.1 the velocity would be 0.55 > 0.5·1.01.
            (|c| c.override_cap = 1.1, Reject::OverrideAboveCeiling),
            // A 10 ms controlled stop: v·5.77/T² = 28 900 ≫ 1.5 m/s³.
            (|c| c.stop_time = 0.01, Reject::StopAboveCeiling),
            (|c| c.quick_stop_time = 0.01, Reject::StopAboveCeiling),
        ];
        for (f, want) in cases {
            let mut c = config();
            f(&mut c);
            assert_eq!(m.check(&c), Err(want));
        }
        let mut c = config();
        c.ceiling_velocity = f32::NAN;
        assert_eq!(m.check(&c), Err(Reject::AboveVelocityCeiling));
    }
}
