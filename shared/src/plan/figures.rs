//! A plan's kinematic figures computed from its segments, exactly in
//! continuous time (the extrema of each quintic, [`super::extrema`]): the
//! largest |v|, |a|, |jerk| and the lowest and highest slider position per
//! joint. Whoever needs them (the check, the drives' stop ramps and override
//! cap) computes them here rather than trusting a plan's recorded `max_abs`.

use super::Segment;
use super::extrema::{argmax_abs_on_interval, derivative, eval, roots_in};

/// Exact continuous-time extremes of a plan's joint motion, per joint.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Kinematics {
    /// max |v| (m/s).
    pub velocity: [f64; 3],
    /// max |a| (m/s²).
    pub acceleration: [f64; 3],
    /// max |jerk| (m/s³).
    pub jerk: [f64; 3],
    /// Lowest slider position (m); +∞ for no segments.
    pub position_min: [f64; 3],
    /// Highest slider position (m); −∞ for no segments.
    pub position_max: [f64; 3],
}

impl Kinematics {
    /// Largest |v|, |a|, |jerk| over the three joints.
    pub fn largest(&self) -> [f64; 3] {
        let m = |x: [f64; 3]| x.iter().fold(0.0f64, |a, b| a.max(*b));
        [m(self.velocity), m(self.acceleration), m(self.jerk)]
    }
}

/// The figures of `segments`. A NaN coefficient gives NaN figures (every
/// comparison with a limit then fails).
pub fn kinematics(segments: &[Segment]) -> Kinematics {
    let mut m = Kinematics {
        position_min: [f64::INFINITY; 3],
        position_max: [f64::NEG_INFINITY; 3],
        ..Kinematics::default()
    };
    let worse = |old: f64, new: f64, bigger: bool| {
        if new.is_nan() || old.is_nan() {
            f64::NAN
        } else if bigger {
            old.max(new)
        } else {
            old.min(new)
        }
    };
    for seg in segments {
        let h = seg.duration_s;
        for j in 0..3 {
            let q = &seg.coeffs[j];
            let vel = derivative(q);
            let acc = derivative(&vel);
            let jerk = derivative(&acc);
            m.velocity[j] = worse(m.velocity[j], argmax_abs_on_interval(&vel, 0.0, h).1, true);
            m.acceleration[j] = worse(
                m.acceleration[j],
                argmax_abs_on_interval(&acc, 0.0, h).1,
                true,
            );
            m.jerk[j] = worse(m.jerk[j], argmax_abs_on_interval(&jerk, 0.0, h).1, true);
            // Position extremes: the ends, the roots of v and (against
            // near-double roots of v) those of a.
            let (r1, r2) = (roots_in(&vel, 0.0, h), roots_in(&acc, 0.0, h));
            for t in [0.0, h].iter().chain(&r1).chain(&r2) {
                let p = eval(q, *t);
                m.position_min[j] = worse(m.position_min[j], p, false);
                m.position_max[j] = worse(m.position_max[j], p, true);
            }
        }
    }
    m
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_quintic_overshoot_between_knots_is_found() {
        // q = t² (1 − t)² · 4 + 0.1 on [0, 1]: 0.1 at both ends, 0.35 at t = ½.
        let seg = Segment {
            t0_s: 0.0,
            duration_s: 1.0,
            coeffs: [[0.1, 0.0, 4.0, -8.0, 4.0, 0.0]; 3],
        };
        let k = kinematics(core::slice::from_ref(&seg));
        assert!((k.position_max[0] - 0.35).abs() < 1e-15, "{k:?}");
        assert_eq!(k.position_min[0], 0.1);
        // v = 8t − 24t² + 16t³: max |v| at t = ½ ∓ √3/6.
        let t: f64 = 0.5 - libm::sqrt(3.0) / 6.0;
        let v = 8.0 * t - 24.0 * t * t + 16.0 * t * t * t;
        assert!((k.velocity[1] - v).abs() < 1e-14);
        assert_eq!(k.jerk[2], 48.0);
    }
}
