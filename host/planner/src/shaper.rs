//! A shaper's impulses for a mode, the residual vibration it leaves, and the
//! convolution of a rest-to-rest piecewise quintic with them.
//!
//! The shaped motion is q̃(t) = Σ Aₖ q(t − tₖ), with q held at its start
//! before 0 and at its end after T. Each copy is the motion shifted by tₖ,
//! so between the union of the shifted knots every copy is one quintic (or
//! a constant), and the sum is a quintic: the segments, shifted, re-expanded
//! about the new knots and added. It is C3 wherever the motion is, starts
//! and ends at rest, and since the Aₖ are positive and sum to 1 its |v|,
//! |a|, |jerk| stay within the motion's.

use std::f64::consts::{FRAC_1_SQRT_2, PI, SQRT_2};

use triquint_shared::plan::eval::at;
use triquint_shared::plan::shaping::{Shaper, ShaperSpec};
use triquint_shared::plan::{JointState, Segment};

use crate::error::PlanError;

/// Vibration tolerance of EI and 2HUMP-EI (Klipper's
/// 1/SHAPER_VIBRATION_REDUCTION).
const EI_TOLERANCE: f64 = 0.05;

/// The highest shaper frequency (Hz): the impulses are whole microseconds.
pub const MAX_SHAPER_HZ: f64 = 1000.0;

/// Impulse times (s, whole microseconds, the first 0) and positive
/// amplitudes summing to 1.
#[derive(Clone, Debug, PartialEq)]
pub struct Impulses {
    pub times_s: Vec<f64>,
    pub amplitudes: Vec<f64>,
}

impl Impulses {
    /// The shaper's impulses for a mode at `hz` with damping ratio `damping`
    /// (Singhose's closed forms, as Klipper's `shaper_defs.py` gave them:
    /// the undamped shaper's amplitudes, each later impulse weighted by the
    /// decay K per half period).
    pub fn new(shaper: Shaper, hz: f64, damping: f64) -> Result<Self, PlanError> {
        if !(hz.is_finite() && hz > 0.0 && hz <= MAX_SHAPER_HZ) {
            return Err(PlanError::invalid(
                "shaper.frequency_hz",
                format!("must be in (0, {MAX_SHAPER_HZ}] Hz, got {hz}"),
            ));
        }
        if !(damping.is_finite() && (0.0..1.0).contains(&damping)) {
            return Err(PlanError::invalid(
                "shaper.damping",
                format!("must be in [0, 1), got {damping}"),
            ));
        }
        let df = (1.0 - damping * damping).sqrt();
        let k = (-damping * PI / df).exp();
        let td = 1.0 / (hz * df);
        let (a, t): (Vec<f64>, Vec<f64>) = match shaper {
            Shaper::Zv => (vec![1.0, k], vec![0.0, 0.5 * td]),
            Shaper::Mzv => {
                // Three impulses 3/8 of a period apart.
                let k = (-0.75 * damping * PI / df).exp();
                let a1 = 1.0 - FRAC_1_SQRT_2;
                (
                    vec![a1, (SQRT_2 - 1.0) * k, a1 * k * k],
                    vec![0.0, 0.375 * td, 0.75 * td],
                )
            }
            Shaper::Zvd => (vec![1.0, 2.0 * k, k * k], vec![0.0, 0.5 * td, td]),
            Shaper::Ei => {
                let a1 = 0.25 * (1.0 + EI_TOLERANCE);
                (
                    vec![a1, 0.5 * (1.0 - EI_TOLERANCE) * k, a1 * k * k],
                    vec![0.0, 0.5 * td, td],
                )
            }
            Shaper::TwoHumpEi => {
                let v2 = EI_TOLERANCE * EI_TOLERANCE;
                let x = (v2 * ((1.0 - v2).sqrt() + 1.0)).cbrt();
                let a1 = (3.0 * x * x + 2.0 * x + 3.0 * v2) / (16.0 * x);
                let a2 = (0.5 - a1) * k;
                (
                    vec![a1, a2, a2 * k, a1 * k * k * k],
                    vec![0.0, 0.5 * td, td, 1.5 * td],
                )
            }
        };
        let sum: f64 = a.iter().sum();
        Ok(Self {
            // Whole microseconds, so the shaped knots stay whole too.
            times_s: t.iter().map(|t| (t * 1e6).round() * 1e-6).collect(),
            amplitudes: a.iter().map(|a| a / sum).collect(),
        })
    }

    /// [`Impulses::new`] for a job's or a plan's shaper.
    pub fn for_spec(spec: &ShaperSpec) -> Result<Self, PlanError> {
        Self::new(spec.shaper, spec.frequency_hz, spec.damping)
    }

    /// How much longer the shaped motion lasts (s).
    pub fn duration_s(&self) -> f64 {
        self.times_s.last().copied().unwrap_or(0.0)
    }

    /// The mean delay Σ Aₖtₖ (s): where the shaped motion is, on average,
    /// behind the unshaped one.
    pub fn delay_s(&self) -> f64 {
        self.times_s
            .iter()
            .zip(&self.amplitudes)
            .map(|(t, a)| t * a)
            .sum()
    }

    /// The residual vibration of a mode at `hz` with damping ratio
    /// `damping` after the impulses, relative to one unit impulse (the
    /// vibration curve: 1 unshaped, 0 where the shaper cancels the mode).
    pub fn residual(&self, hz: f64, damping: f64) -> f64 {
        let w = 2.0 * PI * hz;
        let wd = w * (1.0 - damping * damping).sqrt();
        let tn = self.duration_s();
        let (mut c, mut s) = (0.0, 0.0);
        for (t, a) in self.times_s.iter().zip(&self.amplitudes) {
            let e = a * (-damping * w * (tn - t)).exp();
            c += e * (wd * t).cos();
            s += e * (wd * t).sin();
        }
        c.hypot(s)
    }
}

/// Why a motion cannot be convolved.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ConvolveError {
    #[error("no segments to shape")]
    Empty,
    #[error("shaping needs a motion that starts and ends at rest")]
    NotAtRest,
}

fn us(t: f64) -> i64 {
    (t * 1e6).round() as i64
}

/// Coefficients of p(τ + s) in τ, for p with coefficients `c` (Taylor shift).
fn shifted(c: &[f64; 6], s: f64) -> [f64; 6] {
    let binom = |n: usize, k: usize| -> f64 {
        (0..k).fold(1.0, |b, i| b * (n - i) as f64 / (i + 1) as f64)
    };
    let mut out = [0.0; 6];
    for (m, o) in out.iter_mut().enumerate() {
        *o = (m..6)
            .map(|k| c[k] * binom(k, m) * s.powi((k - m) as i32))
            .sum();
    }
    out
}

/// `segments` (starting at 0, whole microseconds) convolved with
/// `impulses`: the segments between the union of the shifted knots.
pub fn convolve(segments: &[Segment], impulses: &Impulses) -> Result<Vec<Segment>, ConvolveError> {
    let last = segments.last().ok_or(ConvolveError::Empty)?;
    let end_t = last.t0_s + last.duration_s;
    // Held before and after: only a motion at rest at both ends stays C3.
    let at_rest = |s: Option<JointState>| {
        s.is_some_and(|s| {
            s.v.iter()
                .chain(&s.a)
                .chain(&s.jerk)
                .all(|x| x.abs() <= 1e-9)
        })
    };
    if !at_rest(at(segments, 0.0)) || !at_rest(at(segments, end_t)) {
        return Err(ConvolveError::NotAtRest);
    }
    let starts: Vec<i64> = segments.iter().map(|s| us(s.t0_s)).collect();
    let end = us(end_t);
    let shifts: Vec<i64> = impulses.times_s.iter().map(|&t| us(t)).collect();
    let mut knots: Vec<i64> = shifts
        .iter()
        .flat_map(|&d| starts.iter().chain([&end]).map(move |&b| b + d))
        .collect();
    knots.sort_unstable();
    knots.dedup();
    let q_start = segments[0].coeffs.map(|c| c[0]);
    let q_end = at(segments, end_t).ok_or(ConvolveError::Empty)?.q;
    let mut out = Vec::with_capacity(knots.len());
    for w in knots.windows(2) {
        let (u0, u1) = (w[0], w[1]);
        let mut coeffs = [[0.0; 6]; 3];
        for (&d, &a) in shifts.iter().zip(&impulses.amplitudes) {
            let local = u0 - d;
            let copy: [[f64; 6]; 3] = if local < 0 {
                q_start.map(|q| [q, 0.0, 0.0, 0.0, 0.0, 0.0])
            } else if local >= end {
                q_end.map(|q| [q, 0.0, 0.0, 0.0, 0.0, 0.0])
            } else {
                // The knots include every shifted boundary: the interval
                // lies inside one segment of this copy.
                let k = starts.partition_point(|&s| s <= local) - 1;
                let s = (local - starts[k]) as f64 * 1e-6;
                segments[k].coeffs.map(|c| shifted(&c, s))
            };
            for j in 0..3 {
                for m in 0..6 {
                    coeffs[j][m] += a * copy[j][m];
                }
            }
        }
        out.push(Segment {
            t0_s: u0 as f64 * 1e-6,
            duration_s: (u1 - u0) as f64 * 1e-6,
            coeffs,
        });
    }
    Ok(out)
}

/// For each knot of the unshaped motion (at `knot_times_s`, positions
/// `knots_m`), the joint-space distance (m, largest joint) of the shaped
/// motion from it at the same time plus the shaper's mean delay: how far
/// shaping moves the path off the knots, and so off the via-points.
pub fn knot_deviation(
    knots_m: &[[f64; 3]],
    knot_times_s: &[f64],
    shaped: &[Segment],
    impulses: &Impulses,
) -> Vec<f64> {
    let delay = impulses.delay_s();
    knots_m
        .iter()
        .zip(knot_times_s)
        .map(|(q, t)| {
            at(shaped, t + delay).map_or(f64::INFINITY, |s| {
                (0..3).map(|j| (s.q[j] - q[j]).abs()).fold(0.0, f64::max)
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The frequency ratios r (mode / shaper frequency) over which the
    /// shaper's residual, at the damping it was designed for, stays at or
    /// below `level`: the largest interval around r = 1, on a 0.5 % grid.
    fn band(shaper: Shaper, damping: f64, level: f64) -> (f64, f64) {
        let f = 40.0;
        let imp = Impulses::new(shaper, f, damping).unwrap();
        let ok = |r: f64| imp.residual(r * f, damping) <= level;
        let (mut lo, mut hi) = (1.0, 1.0);
        while ok(lo - 0.001) && lo > 0.1 {
            lo -= 0.001;
        }
        while ok(hi + 0.001) && hi < 3.0 {
            hi += 0.001;
        }
        (lo, hi)
    }

    #[test]
    fn impulses_are_positive_sum_to_one_and_last_as_klipper_says() {
        // Durations in periods: Klipper's table (docs/Resonance_Compensation.md).
        for (shaper, periods, n) in [
            (Shaper::Zv, 0.5, 2),
            (Shaper::Mzv, 0.75, 3),
            (Shaper::Zvd, 1.0, 3),
            (Shaper::Ei, 1.0, 3),
            (Shaper::TwoHumpEi, 1.5, 4),
        ] {
            for z in [0.0, 0.026, 0.1] {
                let imp = Impulses::new(shaper, 25.0, z).unwrap();
                assert_eq!(imp.amplitudes.len(), n);
                assert!(imp.amplitudes.iter().all(|a| *a > 0.0), "{shaper}");
                assert!((imp.amplitudes.iter().sum::<f64>() - 1.0).abs() < 1e-12);
                let td = 1.0 / (25.0 * (1.0 - z * z).sqrt());
                assert!((imp.duration_s() - periods * td).abs() <= 1e-6, "{shaper}");
                assert!(imp.times_s.windows(2).all(|w| w[0] < w[1]));
            }
        }
        assert!(Impulses::new(Shaper::Zv, 0.0, 0.1).is_err());
        assert!(Impulses::new(Shaper::Zv, 30.0, 1.0).is_err());
        assert!(Impulses::new(Shaper::Zv, f64::NAN, 0.1).is_err());
        assert!(Impulses::new(Shaper::Ei, 2000.0, 0.1).is_err());
    }

    #[test]
    fn each_shaper_cancels_its_mode_as_designed() {
        for z in [0.0, 0.026, 0.1] {
            for shaper in Shaper::ALL {
                let imp = Impulses::new(shaper, 25.5, z).unwrap();
                let v = imp.residual(25.5, z);
                // ZV, MZV and ZVD put a zero at the mode; EI leaves its
                // tolerance there; 2HUMP-EI a zero near it, between humps.
                let bound = match shaper {
                    Shaper::Ei => 0.051,
                    Shaper::TwoHumpEi => 0.051,
                    _ => 2e-3,
                };
                assert!(v <= bound, "{shaper} ζ {z}: {v}");
                // Far from it, no cancellation: a unit impulse leaves 1.
                assert!(Impulses::new(shaper, 25.5, z).unwrap().residual(1e-3, z) > 0.99);
            }
        }
    }

    /// The frequency error over which each shaper keeps the residual within
    /// 5 % and 10 %: Klipper's table ("vibration reduction 20x / 10x",
    /// docs/Resonance_Compensation.md), for the damping the shaper was made
    /// for. The table is approximate (it spans ζ 0.075–0.15), so each band
    /// is asserted to cover the table's within one point of the ratio.
    /// 2HUMP-EI's closed form is narrower than the table's (docs/vibration.md):
    /// its row holds the closed form's own band at ζ 0.05, a few points short.
    #[test]
    fn the_vibration_curves_cover_klippers_table() {
        let table = [
            // (shaper, 5 % band, 10 % band) as ratios of the frequency.
            (Shaper::Zv, None, (0.95, 1.05)),
            (Shaper::Mzv, Some((0.96, 1.04)), (0.90, 1.15)),
            (Shaper::Zvd, Some((0.85, 1.15)), (0.78, 1.22)),
            (Shaper::Ei, Some((0.80, 1.20)), (0.75, 1.25)),
            // Klipper's table: -40…+45 % and -45…+50 %.
            (Shaper::TwoHumpEi, Some((0.64, 1.37)), (0.60, 1.42)),
        ];
        for z in [0.05, 0.1] {
            for (shaper, five, ten) in table {
                let (lo, hi) = band(shaper, z, 0.10);
                assert!(
                    lo <= ten.0 + 0.01 && hi >= ten.1 - 0.01,
                    "{shaper} ζ {z} 10 %: {lo}..{hi}"
                );
                if let Some(five) = five {
                    let (lo, hi) = band(shaper, z, 0.05 + 1e-3);
                    assert!(
                        lo <= five.0 + 0.01 && hi >= five.1 - 0.01,
                        "{shaper} ζ {z} 5 %: {lo}..{hi}"
                    );
                }
            }
        }
        // And at ±20 %, the frequency error: EI and 2HUMP-EI within
        // their 5 %, ZV well above it.
        for shaper in [Shaper::Ei, Shaper::TwoHumpEi] {
            let imp = Impulses::new(shaper, 25.5, 0.05).unwrap();
            for r in [0.8, 1.2] {
                assert!(imp.residual(r * 25.5, 0.05) <= 0.051, "{shaper} {r}");
            }
        }
        let zv = Impulses::new(Shaper::Zv, 25.5, 0.05).unwrap();
        assert!(zv.residual(0.8 * 25.5, 0.05) > 0.25);
    }
}
