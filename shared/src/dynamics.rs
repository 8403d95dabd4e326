//! Inverse dynamics by the principle of virtual work (paper section "Dynamics
//! analysis"): the feedforward torque every drive computes each control tick.
//!
//! Bodies: the platform (point mass, with payload), three struts (slender rods
//! of mass m_s between their two universal joints), three sliders (point
//! masses on z) and three rotors (motor + coupling + leadscrew, turning at
//! (2π/p)·q̇_i). Gravity acts along −z. Friction is neglected, the screw ideal.
//!
//! A slender rod's kinetic energy in terms of its end velocities is
//! (m/6)(|v_A|² + v_A·v_B + |v_B|²) (translation of the centre plus rotation
//! perpendicular to the rod), so its inertial force at each end is
//! (m/6)(2a_A + a_B) and (m/6)(a_A + 2a_B), and gravity puts m g/2 on each end.
//! The lower end A_i moves with slider i (δA_i = δq_i e_z), the upper end B_i
//! with the platform (δB_i = G δq, G = ∂r/∂q), which gives, with ez = e_z:
//!
//! ```text
//! F = Gᵀ[(m_p + m_s) r̈ + (m_s/6) Σq̈_i ez + (m_p + 3m_s/2) g ez]
//!   + m_q(q̈ + g) + (m_s/6)(2q̈ + r̈_z) + (m_s/2) g        (per axis)
//! τ_i = F_i p/(2π) + I_rot (2π/p) q̈_i
//! ```
//!
//! Positive torque drives its slider up (+z).

use nalgebra::Vector3;

use crate::kinematics::{KinematicsError, Pose};
use crate::quintic::JointMotion;
use crate::{Model, Real, c};

/// Motor torques (N·m) for joint positions (m), velocities (m/s) and accelerations (m/s²).
pub fn torque<T: Real>(
    m: &Model<T>,
    q: &Vector3<T>,
    qd: &Vector3<T>,
    qdd: &Vector3<T>,
) -> Result<Vector3<T>, KinematicsError> {
    let pose = Pose::from_joints(m, *q)?;
    Ok(torque_at(m, &pose, qd, qdd))
}

/// Motor torques (N·m) for a joint state: a [`JointMotion`] (what a quintic
/// evaluates to) or, with `alloc`, a plan's `JointState` at a plan time
/// (`plan.at(t)`). The jerk does not enter. Fails, as [`torque`] does, where
/// the joints admit no pose (outside the workspace, singular, non-finite).
///
/// ```
/// use triquint_shared::dynamics::state_torque;
/// use triquint_shared::quintic::Quintic;
/// use triquint_shared::{KinematicsError, Robot};
///
/// let m = Robot::default().model::<f64>();
/// // All three sliders at 0.3 m, rising at 0.1 m/s: the platform straight up.
/// let seg = Quintic { coeffs: [[0.3, 0.1, 0.0, 0.0, 0.0, 0.0]; 3], duration: 1.0 };
/// let tau = state_torque(&m, seg.eval(0.0))?;
/// assert!(tau.iter().all(|t| *t > 0.0)); // holding the platform up
/// assert!((tau[0] - tau[1]).abs() < 1e-9 && (tau[1] - tau[2]).abs() < 1e-9);
/// // Sliders too far apart for the struts to meet.
/// let apart = Quintic { coeffs: [[0.0; 6], [0.0; 6], [1.0, 0.0, 0.0, 0.0, 0.0, 0.0]], duration: 1.0 };
/// assert_eq!(state_torque(&m, apart.eval(0.0)), Err(KinematicsError::NoAssembly));
/// # Ok::<(), KinematicsError>(())
/// ```
pub fn state_torque<T: Real>(
    m: &Model<T>,
    state: impl Into<JointMotion<T>>,
) -> Result<Vector3<T>, KinematicsError> {
    let s = state.into();
    torque(m, &s.q, &s.qd, &s.qdd)
}

/// [`torque`] for a pose already solved.
pub fn torque_at<T: Real>(
    m: &Model<T>,
    pose: &Pose<T>,
    qd: &Vector3<T>,
    qdd: &Vector3<T>,
) -> Vector3<T> {
    let rd = pose.cartesian_velocity(qd);
    let rdd = pose.cartesian_acceleration(&rd, qd, qdd);
    let g = m.gravity;
    let ms = m.strut_mass;
    let ms6 = ms / c(6.0);
    let half: T = c(0.5);
    let mut w = rdd * (m.platform_mass + ms);
    w.z += ms6 * qdd.sum() + (m.platform_mass + ms * c(1.5)) * g;
    let mut f = pose.platform_jacobian().tr_mul(&w);
    for i in 0..3 {
        f[i] += m.slider_mass * (qdd[i] + g) + ms6 * (qdd[i] * c(2.0) + rdd.z) + ms * half * g;
    }
    f * m.inv_ratio + qdd * (m.rotor_inertia * m.ratio)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::tests::random_poses;
    use crate::{Robot, lagrangian};
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    fn random_state(rng: &mut ChaCha8Rng, m: &Model<f64>, r: Vector3<f64>) -> [Vector3<f64>; 3] {
        let q = Pose::from_cartesian(m, r).unwrap().q;
        let qd = Vector3::from_fn(|_, _| rng.random_range(-0.5..0.5));
        let qdd = Vector3::from_fn(|_, _| rng.random_range(-1.2..1.2));
        [q, qd, qdd]
    }

    /// Route 1: a Lagrangian of the same bodies, written independently.
    #[test]
    fn virtual_work_agrees_with_lagrangian() {
        for robot in [
            Robot::default(),
            Robot {
                payload_mass: 2.0,
                strut_mass: 3.0,
                ..Robot::default()
            },
        ] {
            let m = robot.model::<f64>();
            let mut rng = ChaCha8Rng::seed_from_u64(10);
            let mut worst: f64 = 0.0;
            for r in random_poses(500, 11) {
                let [q, qd, qdd] = random_state(&mut rng, &m, r);
                let a = torque(&m, &q, &qd, &qdd).unwrap();
                let b = lagrangian::inverse_dynamics(&m, &q, &qd, &qdd).unwrap();
                let rel = (a - b).norm() / a.norm().max(1e-3);
                worst = worst.max(rel);
            }
            std::eprintln!("virtual work vs Lagrangian: worst relative {worst:e}");
            assert!(worst < 1e-6, "worst relative disagreement {worst:e}");
        }
    }

    /// Route 2: power balance Σ τ_i θ̇_i = dE/dt along a random trajectory.
    #[test]
    fn power_balance_along_random_trajectories() {
        let m = Robot::default().model::<f64>();
        let mut rng = ChaCha8Rng::seed_from_u64(12);
        let mut worst: f64 = 0.0;
        for r0 in random_poses(50, 13) {
            // A smooth Cartesian path r(t) = r0 + a sin(ωt) + b t².
            let a = Vector3::from_fn(|_, _| rng.random_range(-0.04..0.04));
            let b = Vector3::from_fn(|_, _| rng.random_range(-0.2..0.2));
            let w = rng.random_range(2.0..8.0);
            let state = |t: f64| {
                let r = r0 + a * (w * t).sin() + b * t * t;
                let rd = a * (w * (w * t).cos()) + b * (2.0 * t);
                let rdd = a * (-w * w * (w * t).sin()) + b * 2.0;
                let pose = Pose::from_cartesian(&m, r).unwrap();
                let qd = pose.joint_velocity(&rd);
                let qdd = pose.joint_acceleration(&rd, &rdd, &qd);
                (pose, qd, qdd)
            };
            let energy = |t: f64| {
                let (pose, qd, _) = state(t);
                lagrangian::kinetic_energy(&m, &pose, &qd) + lagrangian::potential_energy(&m, &pose)
            };
            for k in 0..10 {
                let t = 0.02 * k as f64;
                let (pose, qd, qdd) = state(t);
                let tau = torque_at(&m, &pose, &qd, &qdd);
                let power = tau.dot(&(qd * m.ratio));
                let h = 1e-4;
                // Fourth-order central difference of E(t).
                let de = (-energy(t + 2.0 * h) + 8.0 * energy(t + h) - 8.0 * energy(t - h)
                    + energy(t - 2.0 * h))
                    / (12.0 * h);
                let scale = tau.abs().dot(&(qd.abs() * m.ratio)).max(1e-3);
                worst = worst.max((power - de).abs() / scale);
            }
        }
        std::eprintln!("power balance: worst relative residual {worst:e}");
        assert!(worst < 1e-7, "power balance residual {worst:e}");
    }

    /// Route 3: at rest, torque = ∂V/∂θ, the gradient of potential energy.
    #[test]
    fn static_torque_is_gradient_of_potential() {
        let m = Robot::default().model::<f64>();
        let v =
            |q: Vector3<f64>| lagrangian::potential_energy(&m, &Pose::from_joints(&m, q).unwrap());
        for r in random_poses(300, 14) {
            let q = Pose::from_cartesian(&m, r).unwrap().q;
            let tau = torque(&m, &q, &Vector3::zeros(), &Vector3::zeros()).unwrap();
            let h = 1e-6;
            for i in 0..3 {
                let mut e = Vector3::zeros();
                e[i] = h;
                let dv_dtheta = (v(q + e) - v(q - e)) / (2.0 * h) / m.ratio;
                assert!(
                    (tau[i] - dv_dtheta).abs() < 1e-8 * tau.norm().max(1.0),
                    "axis {i}: {} vs {dv_dtheta}",
                    tau[i]
                );
                // Holding the platform up takes positive torque.
                assert!(tau[i] > 0.0);
            }
        }
    }

    #[test]
    fn f32_feedforward_tracks_f64() {
        let robot = Robot::default();
        let m64 = robot.model::<f64>();
        let m32 = robot.model::<f32>();
        let mut rng = ChaCha8Rng::seed_from_u64(15);
        let mut worst: f64 = 0.0;
        for r in random_poses(5000, 16) {
            let [q, qd, qdd] = random_state(&mut rng, &m64, r);
            let a = torque(&m64, &q, &qd, &qdd).unwrap();
            let b = torque(&m32, &q.cast(), &qd.cast(), &qdd.cast())
                .unwrap()
                .cast::<f64>();
            for i in 0..3 {
                let tol = (1e-3 * a[i].abs()).max(1e-4);
                worst = worst.max((a[i] - b[i]).abs() / tol);
            }
        }
        std::eprintln!("f32 vs f64 torque: worst {worst:.4} of the tolerance");
        assert!(worst <= 1.0, "f32 torque error {worst} × tolerance");
    }
}
