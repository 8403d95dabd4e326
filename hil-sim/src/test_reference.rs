//! TEST REFERENCES: motions run through the firmware's control law on a
//! plant, below the drives' segment checks. The drives refuse a
//! jerk-discontinuous plan (`Reject::Discontinuous`), rightly; to measure
//! what such a profile does to a flexible machine, this runs it anyway, on
//! one clock, with no bus: the law (`triquint_firmware::law`, the same
//! feedforward 1.5 ticks ahead, PID and one-tick actuation delay as a
//! drive's tick), the encoder quantised, the plant. Nothing here reaches a
//! drive; a plan and a profile of the same move run the same way, so their
//! figures compare.

use nalgebra::Vector3;
use triquint_firmware::derived_config::DerivedConfig;
use triquint_firmware::law::{self, Gains, LawState};
use triquint_shared::Limits;
use triquint_shared::kinematics::KinematicsError;
use triquint_shared::protocol::DriveConfig;
use triquint_shared::quintic::JointMotion;

use crate::plant_model::PlantModel;

/// A jerk-limited 7-phase (S-curve) profile from `q0` to `q1` along the
/// straight joint-space line, time-optimal within the joint limits: the jerk
/// is ±J or 0, and it jumps at every phase boundary.
#[derive(Clone, Debug, PartialEq)]
pub struct SevenPhase {
    q0: Vector3<f64>,
    dq: Vector3<f64>,
    /// (duration s, path jerk 1/s³) of each phase.
    phases: [(f64, f64); 7],
}

impl SevenPhase {
    /// The profile, none for a move shorter than a micrometre (a closed
    /// path's start and end) or limits that are not finite and positive.
    pub fn new(q0: Vector3<f64>, q1: Vector3<f64>, limits: &Limits) -> Option<Self> {
        let dq = q1 - q0;
        let len = dq.amax();
        let ok = |x: f64| x.is_finite() && x > 0.0;
        if !ok(len - 1e-6) || !ok(limits.velocity) || !ok(limits.acceleration) || !ok(limits.jerk) {
            return None;
        }
        // Limits on the path parameter s ∈ [0, 1], from the joint that moves most.
        let (v, a, j) = (
            limits.velocity / len,
            limits.acceleration / len,
            limits.jerk / len,
        );
        // Peak velocity: the limit, or what a move of length 1 reaches.
        let rises = |vp: f64| {
            if vp * j >= a * a {
                (a / j, a / j + vp / a)
            } else {
                ((vp / j).sqrt(), 2.0 * (vp / j).sqrt())
            }
        };
        let (mut tj, mut ta) = rises(v);
        let mut vp = v;
        if vp * ta > 1.0 {
            // No cruise: v_p·T_a = 1.
            let with_a = (-(a / j) + ((a / j) * (a / j) + 4.0 / a).sqrt()) * a / 2.0;
            vp = if with_a * j >= a * a {
                with_a
            } else {
                (j / 4.0).cbrt()
            };
            (tj, ta) = rises(vp);
        }
        let tv = ((1.0 - vp * ta) / vp).max(0.0);
        let tc = (ta - 2.0 * tj).max(0.0);
        Some(Self {
            q0,
            dq,
            phases: s_curve(tj, tc, tv, j),
        })
    }

    pub fn duration(&self) -> f64 {
        self.phases.iter().map(|p| p.0).sum()
    }

    /// The motion at `t` (s), at rest before 0 and after the end.
    pub fn at(&self, t: f64) -> JointMotion<f64> {
        // Past the end: exactly at the target, at rest.
        let [s, v, a, jerk] = integrate(&self.phases, t).unwrap_or([1.0, 0.0, 0.0, 0.0]);
        JointMotion {
            q: self.q0 + self.dq * s,
            qd: self.dq * v,
            qdd: self.dq * a,
            qddd: self.dq * jerk,
        }
    }
}

/// The seven (duration, jerk) phases of a rest-to-rest S-curve: jerk
/// ramps `tj` at ±`j`, constant acceleration `tc`, cruise `tv`.
fn s_curve(tj: f64, tc: f64, tv: f64, j: f64) -> [(f64, f64); 7] {
    [
        (tj, j),
        (tc, 0.0),
        (tj, -j),
        (tv, 0.0),
        (tj, -j),
        (tc, 0.0),
        (tj, j),
    ]
}

/// Position, velocity, acceleration and jerk at `t` of a profile that starts
/// at rest at 0 and runs through `phases` (duration, jerk); none past the end.
fn integrate(phases: &[(f64, f64); 7], t: f64) -> Option<[f64; 4]> {
    let (mut s, mut v, mut a) = (0.0, 0.0, 0.0);
    let mut left = t.max(0.0);
    for &(d, j) in phases {
        let h = left.min(d);
        s += v * h + a * h * h / 2.0 + j * h * h * h / 6.0;
        v += a * h + j * h * h / 2.0;
        a += j * h;
        left -= h;
        if left <= 0.0 {
            return Some([s, v, a, if h < d { j } else { 0.0 }]);
        }
    }
    None
}

/// A path's own time driven by a 7-phase profile: τ(t) goes from 0 to the
/// path's duration T in the same T, at rest at both ends, its jerk ±J or 0
/// (it jumps at every phase boundary), so the retimed motion
/// q(t) = path(τ(t)) follows the path's geometry with jerk steps wherever the
/// path moves. This is the 7-phase profile of a move that is not a straight
/// line (a closed path has none).
///
/// The phases are fixed fractions of T: jerk phases T/12, constant
/// acceleration T/12, cruise T/2, so τ̇ peaks at 4/3 (a path already at its
/// velocity limit exceeds it by a third: the same duration with a slower
/// start and end must cruise faster), τ̈ at 8/T and J = 96/T².
#[derive(Clone, Debug, PartialEq)]
pub struct Retiming {
    duration: f64,
    phases: [(f64, f64); 7],
}

impl Retiming {
    /// The retiming of a path `duration_s` long; none unless it is finite and positive.
    pub fn new(duration_s: f64) -> Option<Self> {
        if !(duration_s.is_finite() && duration_s > 0.0) {
            return None;
        }
        let (tj, tc, tv) = (duration_s / 12.0, duration_s / 12.0, duration_s / 2.0);
        let j = 96.0 / (duration_s * duration_s);
        Some(Self {
            duration: duration_s,
            phases: s_curve(tj, tc, tv, j),
        })
    }

    pub fn duration(&self) -> f64 {
        self.duration
    }

    /// τ and its first three derivatives at `t`, at rest before 0 and after the end.
    pub fn time_at(&self, t: f64) -> [f64; 4] {
        integrate(&self.phases, t).unwrap_or([self.duration, 0.0, 0.0, 0.0])
    }

    /// The motion at `t` of `path` (its motion at its own time τ) retimed:
    /// the chain rule through τ(t).
    pub fn at(&self, path: &dyn Fn(f64) -> JointMotion<f64>, t: f64) -> JointMotion<f64> {
        let [tau, v, a, j] = self.time_at(t);
        let p = path(tau.clamp(0.0, self.duration));
        JointMotion {
            q: p.q,
            qd: p.qd * v,
            qdd: p.qdd * (v * v) + p.qd * a,
            qddd: p.qddd * (v * v * v) + p.qdd * (3.0 * v * a) + p.qd * j,
        }
    }
}

/// What a test-reference run leaves: the plant (with its records) and when,
/// in plant time, the reference began and ended.
pub struct LawRun {
    pub plant: PlantModel,
    pub start_s: f64,
    pub end_s: f64,
    /// Largest |reference − encoder| of any axis from the reference's start (m).
    pub max_error_m: f64,
    /// What the encoders read at each tick, from plant time 0 (m).
    pub encoder_m: Vec<Vector3<f64>>,
}

/// Runs `reference` (motion at time since its start, `duration_s` long) on
/// `plant` through the control law of drives configured by `configs`:
/// `hold_s` holding the start first (the drives' armed hold), `settle_s`
/// holding the end after.
pub fn run(
    mut plant: PlantModel,
    configs: &[DriveConfig; 3],
    reference: &dyn Fn(f64) -> JointMotion<f64>,
    duration_s: f64,
    hold_s: f64,
    settle_s: f64,
) -> Result<LawRun, KinematicsError> {
    let cfg = &configs[0];
    let model = cfg.robot().native_model();
    let derived = configs.map(|c| DerivedConfig::new(&c, 0));
    let gains = [0, 1, 2].map(|i| Gains::new(&configs[i], &derived[i]));
    let dt = 1.0 / f64::from(cfg.control_rate);
    let mut law_state = [LawState::default(); 3];
    let mut acting = Vector3::zeros();
    let ticks = ((hold_s + duration_s + settle_s) / dt).ceil() as usize;
    let mut max_error: f64 = 0.0;
    let mut encoder_m = Vec::with_capacity(ticks);
    plant.set_braked(false);
    for k in 0..ticks {
        let t = k as f64 * dt - hold_s;
        let r = reference(t.clamp(0.0, duration_s));
        let ahead = reference((t + 1.5 * dt).clamp(0.0, duration_s));
        let ahead32 = JointMotion {
            q: ahead.q.cast::<f32>(),
            qd: ahead.qd.cast::<f32>(),
            qdd: ahead.qdd.cast::<f32>(),
            qddd: ahead.qddd.cast::<f32>(),
        };
        let q = plant.q();
        let mut command = Vector3::zeros();
        let mut read = Vector3::zeros();
        for i in 0..3 {
            let c = &configs[i];
            let counts = (q[i] * f64::from(c.counts_per_metre)).floor();
            read[i] = counts / f64::from(c.counts_per_metre);
            let measured = read[i] as f32;
            let ff = if c.feedforward != 0.0 {
                law::feedforward(&model, c, &ahead32, i).unwrap_or(0.0)
            } else {
                0.0
            };
            let out = law::step(&mut law_state[i], &gains[i], r.q[i] as f32, measured, ff);
            if t >= 0.0 {
                max_error = max_error.max(f64::from(out.error).abs());
            }
            command[i] = f64::from(out.torque * c.direction);
        }
        encoder_m.push(read);
        // One tick of actuation delay, as on a drive.
        for i in 0..3 {
            plant.set_torque(i, acting[i]);
        }
        acting = command;
        plant.advance(dt)?;
    }
    Ok(LawRun {
        plant,
        start_s: hold_s,
        end_s: hold_s + duration_s,
        max_error_m: max_error,
        encoder_m,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_seven_phase_profile_reaches_its_target_within_its_limits() {
        let limits = Limits::default();
        let q0 = Vector3::new(0.30, 0.25, 0.35);
        for q1 in [
            Vector3::new(0.40, 0.20, 0.33),
            Vector3::new(0.301, 0.25, 0.35),
        ] {
            let p = SevenPhase::new(q0, q1, &limits).unwrap();
            let end = p.at(p.duration());
            assert!((end.q - q1).amax() < 1e-12, "{:?}", end.q - q1);
            assert!(end.qd.amax() < 1e-9 && end.qdd.amax() < 1e-9);
            let n = 2000;
            let mut jumps = 0;
            let mut last = p.at(0.0).qddd;
            for k in 0..=n {
                let m = p.at(p.duration() * k as f64 / n as f64);
                assert!(m.qd.amax() <= limits.velocity * (1.0 + 1e-9));
                assert!(m.qdd.amax() <= limits.acceleration * (1.0 + 1e-9));
                assert!(m.qddd.amax() <= limits.jerk * (1.0 + 1e-9));
                if (m.qddd - last).amax() > 0.5 * limits.jerk {
                    jumps += 1;
                }
                last = m.qddd;
            }
            // The jerk jumps: that is the point of it.
            assert!(jumps >= 3, "{jumps}");
        }
        assert!(SevenPhase::new(q0, q0, &limits).is_none());
        let closed = q0 + Vector3::new(1e-9, 0.0, 0.0);
        assert!(SevenPhase::new(q0, closed, &limits).is_none());
    }

    /// A path retimed by the 7-phase profile: same start, end and duration,
    /// q, q̇ and q̈ continuous and each the integral of the next, the jerk
    /// stepping where the path moves.
    #[test]
    fn a_retimed_path_keeps_its_ends_and_steps_only_in_jerk() {
        let (q0, dq, t_end) = (
            Vector3::new(0.30, 0.25, 0.35),
            Vector3::new(0.05, -0.02, 0.01),
            2.0,
        );
        // A minimum-jerk quintic at its own time: at rest at both ends.
        let path = move |tau: f64| {
            let u = tau / t_end;
            let (s, v, a, j) = (
                u * u * u * (10.0 - 15.0 * u + 6.0 * u * u),
                30.0 * u * u * (1.0 - u) * (1.0 - u) / t_end,
                60.0 * u * (1.0 - 3.0 * u + 2.0 * u * u) / (t_end * t_end),
                60.0 * (1.0 - 6.0 * u + 6.0 * u * u) / (t_end * t_end * t_end),
            );
            JointMotion {
                q: q0 + dq * s,
                qd: dq * v,
                qdd: dq * a,
                qddd: dq * j,
            }
        };
        let r = Retiming::new(t_end).unwrap();
        assert_eq!(r.duration(), t_end);
        let [tau, v, a, _] = r.time_at(t_end);
        assert!((tau - t_end).abs() < 1e-12 && v.abs() < 1e-12 && a.abs() < 1e-12);
        assert!((r.at(&path, 0.0).q - q0).amax() < 1e-15);
        let end = r.at(&path, t_end);
        assert!((end.q - (q0 + dq)).amax() < 1e-12);
        assert!(end.qd.amax() < 1e-12 && end.qdd.amax() < 1e-12);
        let h = 1e-5;
        let (mut steps, mut largest_step) = (0, 0.0_f64);
        // Every phase boundary (multiples of T/12) on the grid.
        let n = 4800;
        for k in 1..n {
            let t = t_end * k as f64 / n as f64;
            let (b, m, f) = (r.at(&path, t - h), r.at(&path, t), r.at(&path, t + h));
            assert!(((f.q - b.q) / (2.0 * h) - m.qd).amax() < 1e-7, "q̇ at {t}");
            assert!(
                ((f.qd - b.qd) / (2.0 * h) - m.qdd).amax() < 1e-5,
                "q̈ at {t}"
            );
            assert!((f.qdd - b.qdd).amax() < 2.0 * h * 10.0, "q̈ jumps at {t}");
            let step = (f.qddd - b.qddd).amax();
            if step > 3e-4 {
                steps += 1;
                largest_step = largest_step.max(step);
            } else {
                assert!(
                    ((f.qdd - b.qdd) / (2.0 * h) - m.qddd).amax() < 1e-5,
                    "jerk at {t}"
                );
            }
        }
        // The six interior boundaries, where the path moves (at t = 0 and
        // T the path is at rest, so τ's jerk steps vanish there).
        assert_eq!(steps, 6, "{steps}");
        // |Δq⃛| = |q'(τ)|·J, J = 96/T², q' at most 1.875 |dq| / T.
        let bound = 1.875 * dq.amax() / t_end * 96.0 / (t_end * t_end);
        assert!(largest_step <= 1.01 * bound, "{largest_step} vs {bound}");
        assert!(Retiming::new(0.0).is_none() && Retiming::new(f64::NAN).is_none());
    }
}
