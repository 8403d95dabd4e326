//! An independent Lagrangian formulation of the same machine, in f64.
//!
//! It shares no algebra with [`crate::dynamics`]: energies are written body by
//! body (strut centre-of-mass velocity plus the rod's angular velocity
//! ω = d × ḋ / l²), the Cartesian mass matrix M(r) is the same energy's
//! quadratic form written term by term, and its velocity terms come from
//! each body's acceleration (tested against central differences of M).
//! Lagrange's equations in the platform coordinates r give Q = M r̈ + Ṁ ṙ −
//! ½ ∂(ṙᵀMṙ)/∂r + ∇V, and virtual work maps Q to joint forces: F = J⁻ᵀ Q.
//!
//! Used to cross-check the drives' feedforward and, with deliberately different
//! parameters, as the plant model of the virtual hardware.

use nalgebra::{Matrix3, Vector3};

use crate::Model;
use crate::kinematics::{KinematicsError, Pose};

/// Kinetic energy (J) of the whole machine at a pose with joint velocities `qd`.
pub fn kinetic_energy(m: &Model<f64>, pose: &Pose<f64>, qd: &Vector3<f64>) -> f64 {
    let rd = pose.cartesian_velocity(qd);
    let mut t = 0.5 * m.platform_mass * rd.norm_squared();
    for i in 0..3 {
        let slider_v = Vector3::new(0.0, 0.0, qd[i]);
        // Strut: centre-of-mass translation plus rotation about the centre.
        let v_c = (rd + slider_v) * 0.5;
        let d = pose.struts[i];
        let d_rate = rd - slider_v;
        let omega = d.cross(&d_rate) / m.l2;
        let i_perp = m.strut_mass * m.l2 / 12.0;
        t += 0.5 * m.strut_mass * v_c.norm_squared() + 0.5 * i_perp * omega.norm_squared();
        t += 0.5 * m.slider_mass * qd[i] * qd[i];
        let rotor_rate = m.ratio * qd[i];
        t += 0.5 * m.rotor_inertia * rotor_rate * rotor_rate;
    }
    t
}

/// Potential energy (J), zero at z = 0: platform, sliders, and strut centres.
pub fn potential_energy(m: &Model<f64>, pose: &Pose<f64>) -> f64 {
    let z = pose.r.z;
    let mut v = m.platform_mass * z;
    for i in 0..3 {
        v += m.slider_mass * pose.q[i] + m.strut_mass * 0.5 * (z + pose.q[i]);
    }
    v * m.gravity
}

/// Cartesian mass matrix M(r): T = ½ ṙᵀ M ṙ, body by body as in
/// [`kinetic_energy`], each body's velocity a linear map of ṙ (q̇_i = w_i·ṙ):
/// the platform m_p·I, each strut (m_s/4)·AᵢᵀAᵢ with Aᵢ = I + e_z w_iᵀ for its
/// centre and (I⊥/l⁴)·CᵢᵀCᵢ with Cᵢ = \[d_i\]×(I − e_z w_iᵀ) for its rotation,
/// each slider and rotor (m_sl + I_r·ratio²)·w_i w_iᵀ.
pub fn mass_matrix(m: &Model<f64>, pose: &Pose<f64>) -> Matrix3<f64> {
    let mut mass = Matrix3::identity() * m.platform_mass;
    let i_perp = m.strut_mass * m.l2 / 12.0;
    let spin = i_perp / (m.l2 * m.l2);
    let axial = m.slider_mass + m.rotor_inertia * m.ratio * m.ratio;
    for i in 0..3 {
        let d = pose.struts[i];
        let w = d / d.z;
        let ez_w = Matrix3::from_rows(&[
            Vector3::zeros().transpose(),
            Vector3::zeros().transpose(),
            w.transpose(),
        ]);
        let a = Matrix3::identity() + ez_w;
        let c = d.cross_matrix() * (Matrix3::identity() - ez_w);
        mass +=
            a.tr_mul(&a) * (0.25 * m.strut_mass) + c.tr_mul(&c) * spin + w * w.transpose() * axial;
    }
    mass
}

/// Velocity- and gravity-dependent generalised force n(r, ṙ) in Cartesian
/// coordinates: Ṁṙ − ½ ∂(ṙᵀMṙ)/∂r + ∇V.
///
/// Every body's energy is ½ m_b |ṗ_b|² for a position p_b(r) with ṗ_b = A_b ṙ
/// (the strut's spin too: |d × ḋ|² = l²|ḋ|² since d·ḋ = 0, so it is
/// ½ (I⊥/l²)|ḋ|²). For such a body Lagrange's velocity terms reduce to
/// m_b A_bᵀ (Ȧ_b ṙ), and every Ȧ_b ṙ is e_z times the slider's acceleration
/// at r̈ = 0, a_i = |ḋ_i|²/d_iz (from differentiating d_i·ḋ_i = 0 twice).
fn bias_force(m: &Model<f64>, pose: &Pose<f64>, rd: &Vector3<f64>) -> Vector3<f64> {
    let ez = Vector3::z();
    // I⊥/l² of the rod, I⊥ = m_s l²/12 as in `kinetic_energy`.
    let spin = m.strut_mass / 12.0;
    let axial = m.slider_mass + m.rotor_inertia * m.ratio * m.ratio;
    // ∇V: the platform and the strut centres' halves of z, and each slider
    // and strut centre's half of q_i, with ∂q_i/∂r = w_i.
    let mut n = ez * (m.platform_mass + 1.5 * m.strut_mass) * m.gravity;
    for d in &pose.struts {
        let w = d / d.z;
        let d_rate = rd - ez * w.dot(rd);
        let a = d_rate.norm_squared() / d.z;
        n += ((ez + w) * (0.25 * m.strut_mass) + (w - ez) * spin + w * axial) * a
            + w * ((m.slider_mass + 0.5 * m.strut_mass) * m.gravity);
    }
    n
}

/// Motor torques (N·m) by the Lagrangian route.
pub fn inverse_dynamics(
    m: &Model<f64>,
    q: &Vector3<f64>,
    qd: &Vector3<f64>,
    qdd: &Vector3<f64>,
) -> Result<Vector3<f64>, KinematicsError> {
    let pose = Pose::from_joints(m, *q)?;
    let rd = pose.cartesian_velocity(qd);
    let rdd = pose.cartesian_acceleration(&rd, qd, qdd);
    let q_r = mass_matrix(m, &pose) * rdd + bias_force(m, &pose, &rd);
    // Virtual work: F·δq = Q·δr with δr = G δq, so F = Gᵀ Q.
    Ok(pose.platform_jacobian().tr_mul(&q_r) / m.ratio)
}

/// Joint accelerations (m/s²) under motor torques `tau` (N·m) and `external`
/// joint forces (N, e.g. friction): M r̈ + n = Jᵀ F with F = (2π/p) τ + external.
pub fn forward_dynamics(
    m: &Model<f64>,
    q: &Vector3<f64>,
    qd: &Vector3<f64>,
    tau: &Vector3<f64>,
    external: &Vector3<f64>,
) -> Result<Vector3<f64>, KinematicsError> {
    let pose = Pose::from_joints(m, *q)?;
    let rd = pose.cartesian_velocity(qd);
    let force = tau * m.ratio + external;
    let mass = mass_matrix(m, &pose);
    let rhs = pose.jacobian().tr_mul(&force) - bias_force(m, &pose, &rd);
    let rdd = mass
        .cholesky()
        .ok_or(KinematicsError::Singular)?
        .solve(&rhs);
    Ok(pose.joint_acceleration(&rd, &rdd, qd))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Robot;

    #[test]
    fn forward_dynamics_inverts_inverse_dynamics() {
        let m = Robot::default().model::<f64>();
        let q = Pose::from_cartesian(&m, Vector3::new(0.02, -0.03, 0.62))
            .unwrap()
            .q;
        let qd = Vector3::new(0.1, -0.2, 0.05);
        let qdd = Vector3::new(0.5, 0.3, -0.8);
        let tau = inverse_dynamics(&m, &q, &qd, &qdd).unwrap();
        let back = forward_dynamics(&m, &q, &qd, &tau, &Vector3::zeros()).unwrap();
        assert!((back - qdd).norm() < 1e-6, "{back} vs {qdd}");
    }

    /// Platform positions (m) and velocities (m/s) the tests sample.
    const POSES: [[f64; 3]; 3] = [[0.0, 0.0, 0.60], [0.02, -0.03, 0.62], [-0.09, 0.09, 0.68]];
    const RATES: [[f64; 3]; 3] = [[0.1, -0.2, 0.05], [0.0, 0.0, 1.0], [-0.3, 0.4, -0.2]];

    /// Ṁṙ − ½ ∂(ṙᵀMṙ)/∂r + ∇V by central differences of M and V.
    fn bias_by_differences(m: &Model<f64>, r: Vector3<f64>, rd: Vector3<f64>) -> Vector3<f64> {
        const H: f64 = 2e-5;
        let pose = |r: Vector3<f64>| Pose::from_cartesian(m, r).unwrap();
        let mass = |r: Vector3<f64>| mass_matrix(m, &pose(r));
        let mut n = (mass(r + rd * H) - mass(r - rd * H)) / (2.0 * H) * rd;
        for k in 0..3 {
            let mut e = Vector3::zeros();
            e[k] = H;
            let quad = |r: Vector3<f64>| rd.dot(&(mass(r) * rd));
            let v = |r: Vector3<f64>| potential_energy(m, &pose(r));
            n[k] +=
                -0.5 * (quad(r + e) - quad(r - e)) / (2.0 * H) + (v(r + e) - v(r - e)) / (2.0 * H);
        }
        n
    }

    #[test]
    fn the_bias_force_is_lagranges_by_differences() {
        let m = Robot::default().model::<f64>();
        for r in POSES.map(Vector3::from) {
            let pose = Pose::from_cartesian(&m, r).unwrap();
            // Gravity alone, then the velocity terms alone.
            let gravity = bias_force(&m, &pose, &Vector3::zeros());
            let g_diff = bias_by_differences(&m, r, Vector3::zeros());
            assert!((gravity - g_diff).norm() < 1e-8 * g_diff.norm(), "{r}");
            for rd in RATES.map(Vector3::from) {
                let closed = bias_force(&m, &pose, &rd) - gravity;
                let diff = bias_by_differences(&m, r, rd) - g_diff;
                let err = (closed - diff).norm();
                assert!(
                    err <= 1e-6 * diff.norm() + 1e-9,
                    "{r} {rd}: {closed} vs {diff}"
                );
            }
        }
    }

    #[test]
    fn mass_matrix_is_the_kinetic_energys_quadratic_form() {
        let m = Robot::default().model::<f64>();
        for r in POSES.map(Vector3::from) {
            let pose = Pose::from_cartesian(&m, r).unwrap();
            let mass = mass_matrix(&m, &pose);
            assert!((mass - mass.transpose()).norm() < 1e-12 * mass.norm());
            for rd in RATES.map(Vector3::from) {
                let t = kinetic_energy(&m, &pose, &pose.joint_velocity(&rd));
                let quad = 0.5 * rd.dot(&(mass * rd));
                assert!((quad - t).abs() <= 1e-12 * t, "{r} {rd}: {quad} vs {t}");
            }
        }
    }
}
