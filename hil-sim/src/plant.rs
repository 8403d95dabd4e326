//! The plant: joint-space forward dynamics M(q)q̈ = τ − h(q, q̇) from the
//! independent Lagrangian formulation in `shared`, with a machine that differs
//! from the controller's model the way a real one does: more payload, less
//! rotor inertia, Coulomb and viscous friction on every screw, integrated by
//! fixed-step RK4 finer than the control tick.

use nalgebra::Vector3;
use triquint_shared::kinematics::KinematicsError;
use triquint_shared::{Model, Robot, lagrangian};

/// How the real machine differs from the nominal robot.
#[derive(Clone, Debug, PartialEq)]
pub struct PlantConfig {
    /// Extra payload as a fraction of the platform mass (0.15 = +15 %).
    pub payload_fraction: f64,
    /// Rotor inertia scale (0.9 = −10 %).
    pub rotor_inertia_scale: f64,
    /// Coulomb friction force on each slider (N), smoothed over `stiction_velocity`.
    pub coulomb_n: f64,
    /// Viscous friction (N per m/s).
    pub viscous_n_s_per_m: f64,
    /// Velocity below which Coulomb friction is smoothed (tanh), m/s.
    pub stiction_velocity: f64,
    /// Largest RK4 step (s).
    pub max_step_s: f64,
}

impl Default for PlantConfig {
    fn default() -> Self {
        Self {
            payload_fraction: 0.15,
            rotor_inertia_scale: 0.9,
            coulomb_n: 6.0,
            viscous_n_s_per_m: 30.0,
            stiction_velocity: 1e-3,
            max_step_s: 250e-6,
        }
    }
}

impl PlantConfig {
    /// The real machine for a nominal robot.
    pub fn true_robot(&self, nominal: &Robot) -> Robot {
        Robot {
            payload_mass: nominal.payload_mass * (1.0 + self.payload_fraction)
                + nominal.platform_mass * self.payload_fraction,
            motor_inertia: nominal.motor_inertia * self.rotor_inertia_scale,
            coupling_inertia: nominal.coupling_inertia * self.rotor_inertia_scale,
            leadscrew_inertia: nominal.leadscrew_inertia * self.rotor_inertia_scale,
            ..nominal.clone()
        }
    }
}

/// State of the machine.
#[derive(Clone, Debug)]
pub struct Plant {
    pub cfg: PlantConfig,
    pub model: Model<f64>,
    pub q: Vector3<f64>,
    pub qd: Vector3<f64>,
    /// Motor torques acting now (N·m).
    pub tau: Vector3<f64>,
    /// Brakes on: the machine does not move (before the drives are enabled).
    pub braked: bool,
}

impl Plant {
    pub fn new(nominal: &Robot, cfg: PlantConfig, q0: Vector3<f64>) -> Self {
        let model = cfg.true_robot(nominal).model::<f64>();
        Self {
            cfg,
            model,
            q: q0,
            qd: Vector3::zeros(),
            tau: Vector3::zeros(),
            braked: true,
        }
    }

    fn friction(&self, qd: &Vector3<f64>) -> Vector3<f64> {
        qd.map(|v| {
            -self.cfg.coulomb_n * (v / self.cfg.stiction_velocity).tanh()
                - self.cfg.viscous_n_s_per_m * v
        })
    }

    fn accel(&self, q: &Vector3<f64>, qd: &Vector3<f64>) -> Result<Vector3<f64>, KinematicsError> {
        lagrangian::forward_dynamics(&self.model, q, qd, &self.tau, &self.friction(qd))
    }

    /// Integrates `dt` seconds with RK4 steps no longer than `max_step_s`.
    pub fn advance(&mut self, dt: f64) -> Result<(), KinematicsError> {
        if self.braked {
            self.qd = Vector3::zeros();
            return Ok(());
        }
        if dt <= 0.0 {
            return Ok(());
        }
        let n = (dt / self.cfg.max_step_s).ceil().max(1.0) as usize;
        let h = dt / n as f64;
        for _ in 0..n {
            let (q, v) = (self.q, self.qd);
            let a1 = self.accel(&q, &v)?;
            let (q2, v2) = (q + v * (h / 2.0), v + a1 * (h / 2.0));
            let a2 = self.accel(&q2, &v2)?;
            let (q3, v3) = (q + v2 * (h / 2.0), v + a2 * (h / 2.0));
            let a3 = self.accel(&q3, &v3)?;
            let (q4, v4) = (q + v3 * h, v + a3 * h);
            let a4 = self.accel(&q4, &v4)?;
            self.q = q + (v + v2 * 2.0 + v3 * 2.0 + v4) * (h / 6.0);
            self.qd = v + (a1 + a2 * 2.0 + a3 * 2.0 + a4) * (h / 6.0);
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use triquint_shared::dynamics;
    use triquint_shared::kinematics::Pose;

    #[test]
    fn plant_differs_from_the_nominal_model() {
        let nominal = Robot::default();
        let cfg = PlantConfig::default();
        let real = cfg.true_robot(&nominal);
        assert!((real.payload_mass - 0.525).abs() < 1e-12);
        assert!((real.rotor_inertia() - 0.9 * nominal.rotor_inertia()).abs() < 1e-15);
    }

    #[test]
    fn nominal_static_torque_holds_the_nominal_plant() {
        // With the real machine equal to the nominal one and no friction, the
        // virtual-work static torque holds the Lagrangian plant still.
        let nominal = Robot::default();
        let cfg = PlantConfig {
            payload_fraction: 0.0,
            rotor_inertia_scale: 1.0,
            coulomb_n: 0.0,
            viscous_n_s_per_m: 0.0,
            ..PlantConfig::default()
        };
        let m = nominal.model::<f64>();
        let q0 = Pose::from_cartesian(&m, Vector3::new(-0.02, 0.02, 0.62))
            .unwrap()
            .q;
        let mut p = Plant::new(&nominal, cfg, q0);
        p.braked = false;
        p.tau = dynamics::torque(&m, &q0, &Vector3::zeros(), &Vector3::zeros()).unwrap();
        p.advance(0.1).unwrap();
        assert!((p.q - q0).norm() < 1e-9, "{}", (p.q - q0).norm());
        // A zero-length step changes nothing (two drives ticking at one instant).
        let v = p.qd;
        p.advance(0.0).unwrap();
        assert_eq!(p.qd, v);
        // And without torque it falls.
        p.tau = Vector3::zeros();
        p.advance(0.05).unwrap();
        assert!(p.qd.iter().all(|v| *v < 0.0));
    }
}
