//! The machine's ceilings, held by the drive from its own configuration
//! whatever the host sends (docs/protocol.md, "Ceilings"): a segment whose
//! exact maxima exceed them, whose maxima scaled to the override cap would,
//! or for which no stop ramp within the drive's longest keeps a stop within
//! the budget its jerk ceiling allows, is refused on the receive side with
//! a code naming which.

use triquint_shared::protocol::contract::RELATIVE_LIMIT_MARGIN;
use triquint_shared::protocol::segment_maxima::{
    PieceMaxima, overall, piece_maxima, piece_ramps_and_units,
};
use triquint_shared::protocol::{DriveConfig, Reject};

use crate::f32_cast::{ramp_units, ramp_us};
use crate::segment::{Seg, UnitRamps};

/// Largest |q′|, |q″|, |q‴| over the three joints of a segment (m/s,
/// m/s², m/s³), exact up to f32 rounding, and each joint's on each piece.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Maxima {
    pub v: f32,
    pub a: f32,
    pub j: f32,
    pub pieces: PieceMaxima,
}

impl Maxima {
    /// Of a queued segment (`segment_maxima::piece_maxima`, the host's too).
    pub fn of(seg: &Seg) -> Self {
        let pieces = piece_maxima(&seg.b, seg.inv_h);
        let [v, a, j] = overall(&pieces);
        Self { v, a, j, pieces }
    }

    /// The drive's own stop ramps for this segment (controlled, quick; µs,
    /// as the configured ramps are rounded): within
    /// the stop budgets of `cfg`'s jerk limit held to its jerk ceiling, at
    /// its override cap, over each joint's maxima on each piece
    /// (`segment_maxima::piece_ramps`). None within the longest ramp:
    /// `StopAboveCeiling`.
    pub fn ramps_us(&self, cfg: &DriveConfig) -> Result<(u32, u32), Reject> {
        self.ramps_and_units(cfg).map(|(full, _)| full)
    }

    /// [`Maxima::ramps_us`] and, from the same pass, each piece's own
    /// ramps for a stop along the path from σ ≤ 1, its acceleration within
    /// the configured ceiling (`segment_maxima::piece_ramps_and_units`;
    /// 100 µs units, rounded up): what a stop carrying a ramp for the path
    /// ahead is held to where it passes that piece.
    pub fn ramps_and_units(&self, cfg: &DriveConfig) -> Result<((u32, u32), UnitRamps), Reject> {
        let (full, units) = piece_ramps_and_units(
            &self.pieces,
            cfg.max_jerk,
            cfg.ceiling_jerk,
            cfg.override_cap,
            cfg.ceiling_acceleration,
        )
        .ok_or(Reject::StopAboveCeiling)?;
        let pieces = units.map(|(s, _)| ramp_units(s));
        let quick = units
            .iter()
            .fold(0.0f32, |m, u| if u.1 > m { u.1 } else { m });
        let controlled = pieces.iter().fold(0, |m, &u| if u > m { u } else { m });
        Ok((
            (ramp_us(full.0), ramp_us(full.1)),
            UnitRamps {
                pieces,
                largest: [controlled, ramp_units(quick)],
            },
        ))
    }

    /// Held to `cfg`'s ceilings (with [`RELATIVE_LIMIT_MARGIN`]):
    /// - the segment itself: v, a, j;
    /// - at the override cap σ: σv, σ²a, σ³j;
    ///
    /// Its stop ramps are the drive's own ([`Maxima::ramps_us`]).
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
            ramps_us: (0, 0),
            unit_ramps: UnitRamps::default(),
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

    /// Each joint's maxima on each piece are its peaks there: never
    /// below a sampled value (so every instant of the piece is within
    /// them), never above the piece's largest beyond f32 rounding.
    #[test]
    fn piece_maxima_are_each_joints_peaks_on_each_piece() {
        use triquint_shared::protocol::segment_maxima::PIECES;
        let mut rng = ChaCha8Rng::seed_from_u64(35);
        let n = 4_000;
        for _ in 0..200 {
            let b: [[f32; 6]; 3] =
                core::array::from_fn(|_| core::array::from_fn(|_| rng.random_range(-0.2..0.2)));
            let s = seg(b, rng.random_range(0.05..2.0));
            let got = Maxima::of(&s).pieces;
            let ih = s.inv_h as f64;
            for (joint, b) in s.b.iter().enumerate() {
                let b = b.map(|x| x as f64);
                for p in 0..PIECES {
                    let mut m = [0.0f64; 3];
                    for i in p * n / PIECES..=(p + 1) * n / PIECES {
                        let u = i as f64 / n as f64;
                        let v = b[1]
                            + u * (2.0 * b[2]
                                + u * (3.0 * b[3] + u * (4.0 * b[4] + u * 5.0 * b[5])));
                        let a = 2.0 * b[2] + u * (6.0 * b[3] + u * (12.0 * b[4] + u * 20.0 * b[5]));
                        let j = 6.0 * b[3] + u * (24.0 * b[4] + u * 60.0 * b[5]);
                        m[0] = m[0].max(v.abs() * ih);
                        m[1] = m[1].max(a.abs() * ih * ih);
                        m[2] = m[2].max(j.abs() * ih * ih * ih);
                    }
                    let g = got[joint * PIECES + p];
                    for (g, d) in g.iter().zip(m) {
                        let g = *g as f64;
                        assert!(g >= d * (1.0 - 1e-5) - 1e-9, "{joint} {p}: {g} < {d}");
                        assert!(g <= d * (1.0 + 1e-5) + 1e-9, "{joint} {p}: {g} > {d}");
                    }
                }
            }
        }
    }

    /// Each piece's own ramp for a stop from σ ≤ 1 is its three joints' on
    /// that piece: the largest of each joint's triple there sized alone (in
    /// 100 µs units, rounded up); a segment's largest, controlled and
    /// quick, is the one over all its triples at once.
    #[test]
    fn each_piece_is_held_to_its_own_joints_ramps() {
        use triquint_shared::protocol::segment_maxima::{PIECES, overall};
        use triquint_shared::protocol::stop_ramp::{budgets, pieces_ramp_and_at_unit};
        let mut rng = ChaCha8Rng::seed_from_u64(11);
        let mut cfg = config();
        (cfg.ceiling_acceleration, cfg.ceiling_jerk) = (50.0, 500.0);
        (cfg.max_jerk, cfg.override_cap) = (100.0, 1.0);
        let mut differ = 0;
        for _ in 0..200 {
            let b: [[f32; 6]; 3] =
                core::array::from_fn(|_| core::array::from_fn(|_| rng.random_range(-0.2..0.2)));
            let s = seg(b, rng.random_range(0.5..2.0));
            let m = Maxima::of(&s);
            let (_, units) = m.ramps_and_units(&cfg).unwrap();
            let bs = budgets(overall(&m.pieces)[2], cfg.max_jerk, cfg.ceiling_jerk, 1.0);
            let ramps = |t: &[[f32; 3]]| {
                let [_, at_unit] = pieces_ramp_and_at_unit(t, bs, 1.0, 50.0).unwrap();
                at_unit.map(ramp_units)
            };
            for (p, got) in units.pieces.iter().enumerate() {
                let own = (0..3)
                    .map(|j| ramps(&[m.pieces[j * PIECES + p]])[0])
                    .max()
                    .unwrap();
                assert!(got.abs_diff(own) <= 1, "piece {p}: {got} against {own}");
            }
            let whole = ramps(&m.pieces);
            for (got, want) in units.largest.iter().zip(whole) {
                assert!(got.abs_diff(want) <= 1, "{got} against {want}");
            }
            let largest = units.largest[0];
            differ += usize::from(units.pieces.iter().any(|&u| u + 5 < largest));
        }
        // The pieces differ: a stop that passes only some is held to less.
        assert!(differ > 100, "{differ}");
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
        let cases: [(Change, Reject); 4] = [
            (|c| c.ceiling_velocity *= 0.98, Reject::AboveVelocityCeiling),
            (
                |c| c.ceiling_acceleration *= 0.98,
                Reject::AboveAccelerationCeiling,
            ),
            (|c| c.ceiling_jerk *= 0.98, Reject::AboveJerkCeiling),
            // At σ = 1.1 the velocity would be 0.55 > 0.5·1.01.
            (|c| c.override_cap = 1.1, Reject::OverrideAboveCeiling),
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

    #[test]
    fn a_segment_at_the_jerk_ceiling_has_no_stop_ramp_and_is_refused() {
        let m = Maxima::of(&cubic());
        // Its own jerk, 1, is the ceiling: no room left for a stop.
        assert_eq!(m.ramps_us(&config()), Err(Reject::StopAboveCeiling));
        // A host's stop time plays no part.
        let mut c = config();
        c.stop_time = 10.0;
        assert_eq!(m.ramps_us(&c), Err(Reject::StopAboveCeiling));
        // Twice the ceiling: a ramp, within the longest.
        c.ceiling_jerk = 2.0;
        let (s, q) = m.ramps_us(&c).unwrap();
        assert!(s >= q && q >= 50_000 && s <= 4_000_000, "{s} {q}");
    }
}
