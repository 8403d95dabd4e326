//! Machine parameters (paper Table 1) and motion limits (paper Table 3), SI units.

use core::f64::consts::PI;

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::{Real, c};

/// Angles of the three guideways around the base centre (paper Fig. 3).
pub const GUIDEWAY_ANGLES_DEG: [f64; 3] = [0.0, 120.0, 240.0];

/// Geometry and inertia of a vertical 3-PUU machine. Defaults are the paper's Table 1.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Robot {
    /// s: platform circumradius (m).
    pub platform_radius: f64,
    /// S: base circumradius, guideway axes (m).
    pub base_radius: f64,
    /// l: strut length (m).
    pub strut_length: f64,
    /// d: slider offset toward the centre (m).
    pub slider_offset: f64,
    /// m_p: platform mass (kg).
    pub platform_mass: f64,
    /// Extra mass carried by the platform (kg); 0 in the paper.
    pub payload_mass: f64,
    /// m_i: mass of each strut, a slender rod (kg).
    pub strut_mass: f64,
    /// m_qi: mass of each slider (kg).
    pub slider_mass: f64,
    /// I_M: motor rotor inertia (kg m²).
    pub motor_inertia: f64,
    /// I_C: coupling inertia (kg m²).
    pub coupling_inertia: f64,
    /// I_L: leadscrew inertia (kg m²).
    pub leadscrew_inertia: f64,
    /// p: leadscrew lead, slider travel per motor turn (m).
    pub lead: f64,
    /// g: gravity, acting along −z (m/s²).
    pub gravity: f64,
}

impl Default for Robot {
    fn default() -> Self {
        Self {
            platform_radius: 0.070,
            base_radius: 0.370,
            strut_length: 0.450,
            slider_offset: 0.070,
            platform_mass: 3.5,
            payload_mass: 0.0,
            strut_mass: 0.72,
            slider_mass: 1.377,
            motor_inertia: 1.4e-4,
            coupling_inertia: 1.3e-5,
            leadscrew_inertia: 1.1e-4,
            lead: 0.010,
            gravity: 9.807,
        }
    }
}

/// A parameter that cannot describe a machine.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ParamError {
    #[error("robot parameter `{name}` must be {rule}, got {value}")]
    Invalid {
        name: &'static str,
        rule: &'static str,
        value: f64,
    },
}

fn check(name: &'static str, value: f64, positive: bool) -> Result<(), ParamError> {
    let ok = value.is_finite() && if positive { value > 0.0 } else { value >= 0.0 };
    if ok {
        Ok(())
    } else {
        Err(ParamError::Invalid {
            name,
            rule: if positive {
                "finite and > 0"
            } else {
                "finite and ≥ 0"
            },
            value,
        })
    }
}

impl Robot {
    /// ρ = S − d − s: horizontal distance from the platform centre to a strut's
    /// lower end when the platform is centred.
    pub fn rho(&self) -> f64 {
        self.base_radius - self.slider_offset - self.platform_radius
    }

    /// Motor + coupling + leadscrew inertia on one axis (kg m²).
    pub fn rotor_inertia(&self) -> f64 {
        self.motor_inertia + self.coupling_inertia + self.leadscrew_inertia
    }

    /// Checks every parameter; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError> {
        check("platform_radius", self.platform_radius, true)?;
        check("base_radius", self.base_radius, true)?;
        check("strut_length", self.strut_length, true)?;
        check("slider_offset", self.slider_offset, false)?;
        check("platform_mass", self.platform_mass, false)?;
        check("payload_mass", self.payload_mass, false)?;
        check("strut_mass", self.strut_mass, false)?;
        check("slider_mass", self.slider_mass, false)?;
        check("motor_inertia", self.motor_inertia, false)?;
        check("coupling_inertia", self.coupling_inertia, false)?;
        check("leadscrew_inertia", self.leadscrew_inertia, false)?;
        check("lead", self.lead, true)?;
        check("gravity", self.gravity, false)?;
        check(
            "base_radius - slider_offset - platform_radius",
            self.rho(),
            true,
        )
    }

    /// The derived constants the kinematics and dynamics need, in precision `T`.
    /// Computed once (at configuration time on a drive), never on the control path.
    pub fn model<T: Real>(&self) -> Model<T> {
        let rho = self.rho();
        let u = GUIDEWAY_ANGLES_DEG.map(|a| {
            let (s, co) = libm::sincos(a * PI / 180.0);
            Vector3::new(c(rho * co), c(rho * s), T::zero())
        });
        let ratio = 2.0 * PI / self.lead;
        Model {
            rho_u: u,
            l: c(self.strut_length),
            l2: c(self.strut_length * self.strut_length),
            platform_mass: c(self.platform_mass + self.payload_mass),
            strut_mass: c(self.strut_mass),
            slider_mass: c(self.slider_mass),
            rotor_inertia: c(self.rotor_inertia()),
            ratio: c(ratio),
            inv_ratio: c(1.0 / ratio),
            gravity: c(self.gravity),
        }
    }
}

/// Constants derived from a [`Robot`] in working precision `T`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Model<T: Real> {
    /// ρ·u_i: horizontal offset of strut i's lower end from the platform centre
    /// projection, with u_i the unit vector of guideway i.
    pub rho_u: [Vector3<T>; 3],
    /// Strut length l and its square.
    pub l: T,
    pub l2: T,
    /// Platform plus payload (kg).
    pub platform_mass: T,
    pub strut_mass: T,
    pub slider_mass: T,
    /// I_M + I_C + I_L (kg m²).
    pub rotor_inertia: T,
    /// 2π/p: motor angle per metre of slider travel (rad/m), and its inverse.
    pub ratio: T,
    pub inv_ratio: T,
    pub gravity: T,
}

/// Joint-space motion limits (paper Table 3). Defaults are the paper's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct Limits {
    /// Joint velocity bound (m/s).
    pub velocity: f64,
    /// Joint acceleration bound (m/s²).
    pub acceleration: f64,
    /// Joint jerk bound (m/s³).
    pub jerk: f64,
    /// Motor torque bound (N·m).
    pub torque: f64,
    /// Upper bound on the total time (s).
    pub total_time: f64,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            velocity: 0.5,
            acceleration: 1.2,
            jerk: 5.0,
            torque: 10.0,
            total_time: 5.0,
        }
    }
}

/// A limit that is not a finite positive number.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("limit `{name}` must be finite and > 0, got {value}")]
pub struct LimitError {
    pub name: &'static str,
    pub value: f64,
}

impl Limits {
    pub fn validate(&self) -> Result<(), LimitError> {
        for (name, value) in [
            ("velocity", self.velocity),
            ("acceleration", self.acceleration),
            ("jerk", self.jerk),
            ("torque", self.torque),
            ("total_time", self.total_time),
        ] {
            if !(value.is_finite() && value > 0.0) {
                return Err(LimitError { name, value });
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn paper_rho_and_reflected_inertia() {
        let r = Robot::default();
        assert!((r.rho() - 0.23).abs() < 1e-12);
        // README of the paper: reflected rotor inertia ≈ 104 kg per axis.
        let reflected = r.rotor_inertia() * (2.0 * PI / r.lead).powi(2);
        assert!((reflected - 104.0).abs() < 1.0, "{reflected}");
        assert!(r.validate().is_ok());
    }

    #[test]
    fn bad_parameters_are_named() {
        let r = Robot {
            lead: 0.0,
            ..Robot::default()
        };
        assert_eq!(
            r.validate().unwrap_err().to_string(),
            "robot parameter `lead` must be finite and > 0, got 0"
        );
        let l = Limits {
            jerk: f64::NAN,
            ..Limits::default()
        };
        assert_eq!(l.validate().unwrap_err().name, "jerk");
    }
}
