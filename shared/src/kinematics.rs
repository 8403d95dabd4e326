//! Kinematics of the vertical 3-PUU: IK, closed-form FK, Jacobians and the
//! velocity/acceleration maps between joint and Cartesian space.
//!
//! Notation: r = (x, y, z) is the platform centre, q_i the height of slider i,
//! and d_i = (x − ρu_ix, y − ρu_iy, z − q_i) the strut vector from slider i's
//! joint to the platform's joint (|d_i| = l). The platform is above the
//! sliders, so d_iz > 0 in every valid pose.

// `!(x > bound)` is deliberate throughout: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use nalgebra::{Matrix3, Vector2, Vector3};

use crate::{Model, Real, c};

/// Why a pose cannot be computed. Never NaN, never a panic.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum KinematicsError {
    /// A coordinate is NaN or infinite.
    #[error("non-finite coordinate")]
    NonFinite,
    /// The point is further from guideway `axis` (1–3) than a strut can reach.
    #[error("out of reach of strut {axis}: the horizontal distance exceeds the strut length")]
    Unreachable { axis: u8 },
    /// Strut `axis` (1–3) would be (nearly) horizontal: the joint-space map blows up.
    #[error("strut {axis} is nearly horizontal (inverse-kinematic singularity)")]
    StrutHorizontal { axis: u8 },
    /// The three struts cannot meet at one platform position for these joints.
    #[error("no platform position fits these slider heights (struts cannot meet)")]
    NoAssembly,
    /// The struts are (nearly) coplanar: the platform is not determined by the joints.
    #[error("singular configuration (struts nearly coplanar)")]
    Singular,
}

/// Smallest allowed vertical strut component, as a fraction of l: below it a
/// strut is called horizontal (its Jacobian row exceeds 1/0.02 = 50).
const MIN_STRUT_RISE: f64 = 0.02;
/// Smallest allowed |det[d_1; d_2; d_3]| / l³ before the pose is called singular.
const MIN_DETERMINANT: f64 = 1e-4;

/// A platform pose with its slider heights and strut vectors.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Pose<T: Real> {
    /// Platform centre (m).
    pub r: Vector3<T>,
    /// Slider heights (m).
    pub q: Vector3<T>,
    /// Strut vectors d_i, slider joint → platform joint (m).
    pub struts: [Vector3<T>; 3],
    /// Inverse of D = [d_1ᵀ; d_2ᵀ; d_3ᵀ], used by every Cartesian map.
    d_inv: Matrix3<T>,
}

fn finite<T: Real>(v: &Vector3<T>) -> bool {
    v.iter().all(|x| x.is_finite())
}

impl<T: Real> Pose<T> {
    /// Inverse kinematics: q_i = z − sqrt(l² − |(x, y) − ρu_i|²).
    pub fn from_cartesian(m: &Model<T>, r: Vector3<T>) -> Result<Self, KinematicsError> {
        if !finite(&r) {
            return Err(KinematicsError::NonFinite);
        }
        let mut q = Vector3::zeros();
        for i in 0..3 {
            let dx = r.x - m.rho_u[i].x;
            let dy = r.y - m.rho_u[i].y;
            let rise2 = m.l2 - (dx * dx + dy * dy);
            if rise2 <= T::zero() {
                return Err(KinematicsError::Unreachable { axis: i as u8 + 1 });
            }
            q[i] = r.z - rise2.sqrt();
        }
        Self::assemble(m, r, q)
    }

    /// Closed-form forward kinematics (paper eq. 16–20): subtracting strut 1's
    /// sphere equation from struts 2 and 3 leaves x and y linear in z; back in
    /// strut 1's equation that is a quadratic in z, whose larger root is the
    /// physical one (platform above the sliders).
    pub fn from_joints(m: &Model<T>, q: Vector3<T>) -> Result<Self, KinematicsError> {
        if !finite(&q) {
            return Err(KinematicsError::NonFinite);
        }
        let half: T = c(0.5);
        let p1 = m.rho_u[0].xy();
        let a = Matrix3::new(
            m.rho_u[1].x - p1.x,
            m.rho_u[1].y - p1.y,
            T::zero(),
            m.rho_u[2].x - p1.x,
            m.rho_u[2].y - p1.y,
            T::zero(),
            T::zero(),
            T::zero(),
            T::one(),
        );
        let a_inv = a.try_inverse().ok_or(KinematicsError::Singular)?;
        let e = Vector3::new(
            (q[1] * q[1] - q[0] * q[0]) * half,
            (q[2] * q[2] - q[0] * q[0]) * half,
            T::zero(),
        );
        let f = Vector3::new(q[0] - q[1], q[0] - q[2], T::zero());
        // (x, y) = a0 + b0 z
        let a0 = (a_inv * e).xy();
        let b0 = (a_inv * f).xy();
        let w: Vector2<T> = a0 - p1;
        let qa = b0.norm_squared() + T::one();
        let qb = (w.dot(&b0) - q[0]) * c(2.0);
        let qc = w.norm_squared() + q[0] * q[0] - m.l2;
        let disc = qb * qb - qa * qc * c(4.0);
        if !(disc >= T::zero()) {
            return Err(KinematicsError::NoAssembly);
        }
        let s = disc.sqrt();
        // Larger root, written to avoid cancellation.
        let z = if qb <= T::zero() {
            (s - qb) / (qa * c(2.0))
        } else {
            (qc * c(2.0)) / (-qb - s)
        };
        let xy = a0 + b0 * z;
        Self::assemble(m, Vector3::new(xy.x, xy.y, z), q)
    }

    fn assemble(m: &Model<T>, r: Vector3<T>, q: Vector3<T>) -> Result<Self, KinematicsError> {
        let min_rise = m.l * c(MIN_STRUT_RISE);
        let mut struts = [Vector3::zeros(); 3];
        for (i, d) in struts.iter_mut().enumerate() {
            *d = Vector3::new(r.x - m.rho_u[i].x, r.y - m.rho_u[i].y, r.z - q[i]);
            if !(d.z > min_rise) {
                return Err(KinematicsError::StrutHorizontal { axis: i as u8 + 1 });
            }
        }
        let dm = Matrix3::from_rows(&[
            struts[0].transpose(),
            struts[1].transpose(),
            struts[2].transpose(),
        ]);
        let det = dm.determinant();
        if !(det.abs() > m.l2 * m.l * c(MIN_DETERMINANT)) {
            return Err(KinematicsError::Singular);
        }
        let d_inv = dm.try_inverse().ok_or(KinematicsError::Singular)?;
        Ok(Self {
            r,
            q,
            struts,
            d_inv,
        })
    }

    /// Vertical components d_iz of the three struts.
    fn rises(&self) -> Vector3<T> {
        Vector3::new(self.struts[0].z, self.struts[1].z, self.struts[2].z)
    }

    /// Jacobian J with q̇ = J ṙ; row i is w_i = d_iᵀ / d_iz (the paper's w_i rows).
    pub fn jacobian(&self) -> Matrix3<T> {
        Matrix3::from_rows(&[
            self.struts[0].transpose() / self.struts[0].z,
            self.struts[1].transpose() / self.struts[1].z,
            self.struts[2].transpose() / self.struts[2].z,
        ])
    }

    /// Inverse Jacobian G = J⁻¹ = ∂r/∂q: the platform's velocity per unit joint velocity.
    pub fn platform_jacobian(&self) -> Matrix3<T> {
        let mut g = self.d_inv;
        for i in 0..3 {
            let dz = self.struts[i].z;
            g.column_mut(i).scale_mut(dz);
        }
        g
    }

    /// q̇ = J ṙ.
    pub fn joint_velocity(&self, rd: &Vector3<T>) -> Vector3<T> {
        Vector3::from_fn(|i, _| self.struts[i].dot(rd) / self.struts[i].z)
    }

    /// ṙ = J⁻¹ q̇, from d_i·ṙ = d_iz q̇_i.
    pub fn cartesian_velocity(&self, qd: &Vector3<T>) -> Vector3<T> {
        self.d_inv * self.rises().component_mul(qd)
    }

    /// ḋ_i = ṙ − q̇_i e_z: the strut vectors' rates.
    pub fn strut_rates(&self, rd: &Vector3<T>, qd: &Vector3<T>) -> [Vector3<T>; 3] {
        [0, 1, 2].map(|i| Vector3::new(rd.x, rd.y, rd.z - qd[i]))
    }

    /// q̈_i = (d_i·r̈ + |ḋ_i|²) / d_iz, from differentiating d_i·ṙ = d_iz q̇_i.
    pub fn joint_acceleration(
        &self,
        rd: &Vector3<T>,
        rdd: &Vector3<T>,
        qd: &Vector3<T>,
    ) -> Vector3<T> {
        let dd = self.strut_rates(rd, qd);
        Vector3::from_fn(|i, _| (self.struts[i].dot(rdd) + dd[i].norm_squared()) / self.struts[i].z)
    }

    /// r̈ = D⁻¹ (d_iz q̈_i − |ḋ_i|²).
    pub fn cartesian_acceleration(
        &self,
        rd: &Vector3<T>,
        qd: &Vector3<T>,
        qdd: &Vector3<T>,
    ) -> Vector3<T> {
        let dd = self.strut_rates(rd, qd);
        let b = Vector3::from_fn(|i, _| self.struts[i].z * qdd[i] - dd[i].norm_squared());
        self.d_inv * b
    }
}

/// Platform centre r (m) for slider heights `q` (m): the closed-form forward
/// kinematics of [`Pose::from_joints`], for example of a plan's `q(t)`
/// (`plan.at(t)?.q`). Takes an array or a vector.
///
/// ```
/// use triquint_shared::kinematics::platform_position;
/// use triquint_shared::{KinematicsError, Robot};
///
/// let m = Robot::default().model::<f64>();
/// // Paper Table 2, P1: q = (376.68, 244.16, 336.13) mm ↔ r = (−90, 90, 680) mm.
/// let r = platform_position(&m, [0.37668, 0.24416, 0.33613])?;
/// assert!((r - nalgebra::Vector3::new(-0.090, 0.090, 0.680)).norm() < 1e-4);
/// assert_eq!(platform_position(&m, [0.0, 0.0, f64::NAN]), Err(KinematicsError::NonFinite));
/// # Ok::<(), KinematicsError>(())
/// ```
pub fn platform_position<T: Real>(
    m: &Model<T>,
    q: impl Into<Vector3<T>>,
) -> Result<Vector3<T>, KinematicsError> {
    Pose::from_joints(m, q.into()).map(|pose| pose.r)
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::Robot;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// (x, y, z) and (q1, q2, q3) in mm: the paper's Tables 2 and 6 as decoded
    /// in the paper README (P5 q1 and Table 6 row 10 q2 restored there).
    const TABLES: [([f64; 3], [f64; 3]); 21] = [
        ([-90.0, 90.0, 680.0], [376.68, 244.16, 336.13]),
        ([-90.0, 90.0, 660.0], [356.68, 224.16, 316.13]),
        ([-90.0, 90.0, 640.0], [336.68, 204.16, 296.13]),
        ([-60.0, 60.0, 620.0], [281.18, 195.62, 256.27]),
        ([-20.0, 20.0, 620.0], [246.37, 218.29, 238.64]),
        ([20.0, -20.0, 620.0], [222.51, 250.90, 229.91]),
        ([60.0, -60.0, 620.0], [207.69, 296.43, 229.48]),
        ([90.0, -90.0, 640.0], [221.91, 362.79, 254.57]),
        ([90.0, -90.0, 660.0], [241.91, 382.79, 274.57]),
        ([90.0, -90.0, 680.0], [261.91, 402.79, 294.57]),
        ([-86.0, 83.66, 597.66], [288.39, 163.71, 248.87]),
        ([-43.0, 97.74, 654.74], [310.62, 222.28, 324.36]),
        ([0.0, 84.85, 684.85], [307.49, 265.09, 355.31]),
        ([43.0, 54.74, 697.74], [292.11, 301.92, 361.50]),
        ([86.0, -2.34, 683.66], [257.33, 335.11, 332.45]),
        ([86.0, -83.66, 602.34], [184.29, 315.81, 216.66]),
        ([43.0, -97.74, 545.26], [147.80, 246.31, 136.30]),
        ([0.0, -84.85, 515.15], [137.79, 185.61, 95.39]),
        ([-43.0, -54.74, 502.26], [148.74, 137.79, 82.20]),
        ([-86.0, 2.34, 516.34], [195.97, 112.72, 115.03]),
        ([-86.0, 83.66, 597.66], [288.39, 163.71, 248.87]),
    ];

    fn model() -> Model<f64> {
        Robot::default().model()
    }

    #[test]
    fn ik_reproduces_paper_tables_to_0_01_mm() {
        let m = model();
        let mut worst: f64 = 0.0;
        for (r, q) in TABLES {
            let pose = Pose::from_cartesian(&m, Vector3::from(r) / 1000.0).unwrap();
            for (i, q_table) in q.iter().enumerate() {
                // Tables are printed to 0.01 mm: rounding leaves at most 0.005 mm.
                let q_mm = pose.q[i] * 1000.0;
                let err = (q_mm - q_table).abs();
                worst = worst.max(err);
                assert!(err <= 0.01, "{r:?} axis {i}: {q_mm} vs {q_table}");
            }
        }
        std::eprintln!("IK vs paper tables: worst {worst:.5} mm");
        assert!(worst <= 0.0051, "worst {worst} mm exceeds table rounding");
    }

    /// A seeded sample of reachable poses: a cylinder around the paper's workspace.
    pub(crate) fn random_poses(n: usize, seed: u64) -> impl Iterator<Item = Vector3<f64>> {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        (0..n).map(move |_| {
            let a = rng.random_range(0.0..core::f64::consts::TAU);
            let rad = 0.15 * rng.random_range(0.0f64..1.0).sqrt();
            Vector3::new(rad * a.cos(), rad * a.sin(), rng.random_range(0.45..0.75))
        })
    }

    #[test]
    fn fk_inverts_ik_to_1e_9() {
        let m = model();
        let mut worst: f64 = 0.0;
        for r in random_poses(10_000, 1) {
            let q = Pose::from_cartesian(&m, r).unwrap().q;
            let back = Pose::from_joints(&m, q).unwrap().r;
            worst = worst.max((back - r).norm());
        }
        std::eprintln!("FK(IK(r)) worst error {worst:e} m");
        assert!(worst < 1e-9, "FK(IK(r)) worst error {worst} m");
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let m = model();
        let h = 1e-6;
        for r in random_poses(200, 2) {
            let j = Pose::from_cartesian(&m, r).unwrap().jacobian();
            for k in 0..3 {
                let mut e = Vector3::zeros();
                e[k] = h;
                let qp = Pose::from_cartesian(&m, r + e).unwrap().q;
                let qm = Pose::from_cartesian(&m, r - e).unwrap().q;
                let col = (qp - qm) / (2.0 * h);
                assert!(
                    (col - j.column(k)).norm() < 1e-7,
                    "{col} vs {}",
                    j.column(k)
                );
            }
        }
    }

    #[test]
    fn velocity_and_acceleration_maps_are_consistent() {
        let m = model();
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let dt = 1e-4;
        for r0 in random_poses(200, 4) {
            let rd = Vector3::from_fn(|_, _| rng.random_range(-0.3..0.3));
            let rdd = Vector3::from_fn(|_, _| rng.random_range(-2.0..2.0));
            let at = |t: f64| r0 + rd * t + rdd * (0.5 * t * t);
            let q = |t: f64| Pose::from_cartesian(&m, at(t)).unwrap().q;
            let pose = Pose::from_cartesian(&m, r0).unwrap();
            let qd = pose.joint_velocity(&rd);
            let qdd = pose.joint_acceleration(&rd, &rdd, &qd);
            let qd_fd = (q(dt) - q(-dt)) / (2.0 * dt);
            let qdd_fd = (q(dt) - q(0.0) * 2.0 + q(-dt)) / (dt * dt);
            assert!((qd - qd_fd).norm() < 1e-7);
            assert!((qdd - qdd_fd).norm() < 1e-4, "{qdd} vs {qdd_fd}");
            assert!((pose.cartesian_velocity(&qd) - rd).norm() < 1e-12);
            assert!((pose.cartesian_acceleration(&rd, &qd, &qdd) - rdd).norm() < 1e-10);
            assert!(
                (pose.platform_jacobian() * pose.jacobian() - Matrix3::identity()).norm() < 1e-12
            );
        }
    }

    #[test]
    fn unreachable_and_bad_input_are_typed_errors() {
        let m = model();
        assert_eq!(
            Pose::from_cartesian(&m, Vector3::new(0.0, 0.0, f64::NAN)).unwrap_err(),
            KinematicsError::NonFinite
        );
        assert!(matches!(
            Pose::from_cartesian(&m, Vector3::new(-0.5, 0.0, 0.6)).unwrap_err(),
            KinematicsError::Unreachable { axis: 1 }
        ));
        // Joints too far apart for the struts to meet.
        assert_eq!(
            Pose::from_joints(&m, Vector3::new(0.0, 0.0, 1.0)).unwrap_err(),
            KinematicsError::NoAssembly
        );
        assert_eq!(
            Pose::from_joints(&m, Vector3::new(0.0, f64::INFINITY, 0.0)).unwrap_err(),
            KinematicsError::NonFinite
        );
    }

    #[test]
    fn f32_kinematics_track_f64() {
        let m64 = model();
        let m32: Model<f32> = Robot::default().model();
        for r in random_poses(2000, 5) {
            let q64 = Pose::from_cartesian(&m64, r).unwrap().q;
            let q32 = Pose::from_cartesian(&m32, r.cast::<f32>()).unwrap().q;
            assert!((q32.cast::<f64>() - q64).norm() < 1e-6);
            let back = Pose::from_joints(&m32, q64.cast::<f32>()).unwrap().r;
            assert!((back.cast::<f64>() - r).norm() < 2e-6);
        }
    }
}
