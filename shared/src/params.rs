//! Machine parameters (paper Table 1) and motion limits (paper Table 3), SI units.

use core::fmt::{Debug, Display, LowerExp};

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use crate::{Real, c};

/// Angles of the three guideways around the base centre (paper Fig. 3).
pub const GUIDEWAY_ANGLES_DEG: [f64; 3] = [0.0, 120.0, 240.0];

/// (cos, sin) of [`GUIDEWAY_ANGLES_DEG`] as `libm::sincos(a·π/180)` gives
/// them in f64 (a test checks every bit): constants, so a model in f32
/// needs no trigonometry and no f64 code.
pub const GUIDEWAY_COS_SIN: [(f64, f64); 3] = [
    (1.0, 0.0),
    (-0.4999999999999998, 0.8660254037844387),
    (-0.5000000000000004, -0.8660254037844385),
];

/// Geometry and inertia of a vertical 3-PUU machine in f64 (the planner,
/// plan files). Defaults are the paper's Table 1.
pub type Robot = RobotParams<f64>;

/// Geometry and inertia of a vertical 3-PUU machine in precision `T`: f64 as
/// [`Robot`] on the host; f32 on a drive, straight from the configuration's
/// wire values (so a drive's set-up links no double-precision code).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(
    deny_unknown_fields,
    default,
    bound(
        serialize = "T: Serialize",
        deserialize = "T: Deserialize<'de>, RobotParams<T>: Default"
    )
)]
pub struct RobotParams<T> {
    /// s: platform circumradius (m).
    pub platform_radius: T,
    /// S: base circumradius, guideway axes (m).
    pub base_radius: T,
    /// l: strut length (m).
    pub strut_length: T,
    /// d: slider offset toward the centre (m).
    pub slider_offset: T,
    /// m_p: platform mass (kg).
    pub platform_mass: T,
    /// Extra mass carried by the platform (kg); 0 in the paper.
    pub payload_mass: T,
    /// m_i: mass of each strut, a slender rod (kg).
    pub strut_mass: T,
    /// m_qi: mass of each slider (kg).
    pub slider_mass: T,
    /// I_M: motor rotor inertia (kg m²).
    pub motor_inertia: T,
    /// I_C: coupling inertia (kg m²).
    pub coupling_inertia: T,
    /// I_L: leadscrew inertia (kg m²).
    pub leadscrew_inertia: T,
    /// p: leadscrew lead, slider travel per motor turn (m).
    pub lead: T,
    /// g: gravity, acting along −z (m/s²).
    pub gravity: T,
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

/// A parameter that cannot describe a machine (the value in the parameters' precision).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum ParamError<T: Debug + Display + LowerExp = f64> {
    #[error("robot parameter `{name}` must be {rule}, got {}", Short(value))]
    Invalid {
        name: &'static str,
        rule: &'static str,
        value: T,
    },
}

/// A number for a one-line message: as written, or in scientific notation
/// when that is long (`1e300` displays as 301 digits).
pub(crate) struct Short<T>(pub(crate) T);

impl<T: Display + LowerExp> Display for Short<T> {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        /// Counts what `Display` would write, without writing it.
        struct Len(usize);
        impl core::fmt::Write for Len {
            fn write_str(&mut self, s: &str) -> core::fmt::Result {
                self.0 += s.len();
                Ok(())
            }
        }
        let mut len = Len(0);
        core::fmt::write(&mut len, format_args!("{}", self.0))?;
        if len.0 > 12 {
            write!(f, "{:e}", self.0)
        } else {
            write!(f, "{}", self.0)
        }
    }
}

/// The magnitudes a parameter may have (SI): like the limits' 1e-6..1e6,
/// so that an absurd machine (`lead = 1e300`) is bad input, not a plan
/// that no limit can meet.
const PARAM_MAX: f64 = 1e6;
const PARAM_MIN_POSITIVE: f64 = 1e-6;

fn check<T: Real + Display + LowerExp>(
    name: &'static str,
    value: T,
    positive: bool,
) -> Result<(), ParamError<T>> {
    let ok = value.is_finite()
        && value <= c::<T>(PARAM_MAX)
        && if positive {
            value >= c::<T>(PARAM_MIN_POSITIVE)
        } else {
            value >= T::zero()
        };
    if ok {
        Ok(())
    } else {
        Err(ParamError::Invalid {
            name,
            rule: if positive {
                "in 1e-6..1e6"
            } else {
                "in 0..1e6"
            },
            value,
        })
    }
}

impl<T: Real + Display + LowerExp> RobotParams<T> {
    /// ρ = S − d − s: horizontal distance from the platform centre to a strut's
    /// lower end when the platform is centred.
    pub fn rho(&self) -> T {
        self.base_radius - self.slider_offset - self.platform_radius
    }

    /// Motor + coupling + leadscrew inertia on one axis (kg m²).
    pub fn rotor_inertia(&self) -> T {
        self.motor_inertia + self.coupling_inertia + self.leadscrew_inertia
    }

    /// Checks every parameter; the error names the first bad one.
    pub fn validate(&self) -> Result<(), ParamError<T>> {
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

    /// The derived constants the kinematics and dynamics need, computed in
    /// the parameters' own precision `T` (f32 on a drive: no f64 code).
    /// Computed once (at configuration time on a drive), never on the control path.
    pub fn native_model(&self) -> Model<T> {
        let rho = self.rho();
        let one = T::one();
        let ratio = T::two_pi() / self.lead;
        Model {
            // Constants converted at compile time (f32: no f64 code is linked).
            rho_u: GUIDEWAY_COS_SIN
                .map(|(co, s)| Vector3::new(rho * c::<T>(co), rho * c::<T>(s), T::zero())),
            l: self.strut_length,
            l2: self.strut_length * self.strut_length,
            platform_mass: self.platform_mass + self.payload_mass,
            strut_mass: self.strut_mass,
            slider_mass: self.slider_mass,
            rotor_inertia: self.rotor_inertia(),
            ratio,
            inv_ratio: one / ratio,
            gravity: self.gravity,
        }
    }
}

impl Robot {
    /// The first parameter that differs from `other`'s (bit for bit): its
    /// name and both values.
    pub fn first_difference(&self, other: &Robot) -> Option<(&'static str, f64, f64)> {
        let fields = |r: &Robot| {
            [
                ("platform_radius", r.platform_radius),
                ("base_radius", r.base_radius),
                ("strut_length", r.strut_length),
                ("slider_offset", r.slider_offset),
                ("platform_mass", r.platform_mass),
                ("payload_mass", r.payload_mass),
                ("strut_mass", r.strut_mass),
                ("slider_mass", r.slider_mass),
                ("motor_inertia", r.motor_inertia),
                ("coupling_inertia", r.coupling_inertia),
                ("leadscrew_inertia", r.leadscrew_inertia),
                ("lead", r.lead),
                ("gravity", r.gravity),
            ]
        };
        fields(self)
            .into_iter()
            .zip(fields(other))
            .find(|((_, x), (_, y))| x.to_bits() != y.to_bits())
            .map(|((k, x), (_, y))| (k, x, y))
    }

    /// The model computed in f64 and delivered in precision `U`.
    pub fn model<U: Real>(&self) -> Model<U> {
        let m = self.native_model();
        Model {
            rho_u: m.rho_u.map(|v| v.map(c)),
            l: c(m.l),
            l2: c(m.l2),
            platform_mass: c(m.platform_mass),
            strut_mass: c(m.strut_mass),
            slider_mass: c(m.slider_mass),
            rotor_inertia: c(m.rotor_inertia),
            ratio: c(m.ratio),
            inv_ratio: c(m.inv_ratio),
            gravity: c(m.gravity),
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
#[error("limit `{name}` must be finite and > 0, got {}", Short(value))]
pub struct LimitError {
    pub name: &'static str,
    pub value: f64,
}

impl Limits {
    /// The four motion limits by name (velocity, acceleration, jerk, torque).
    pub fn named(&self) -> [(&'static str, f64); 4] {
        [
            ("velocity", self.velocity),
            ("acceleration", self.acceleration),
            ("jerk", self.jerk),
            ("torque", self.torque),
        ]
    }

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

/// Slider travel: per axis, the lowest and highest joint position (m) a
/// motion may reach. A limit like velocity or jerk: `ik` and `fk` refuse a
/// pose outside it, the planner keeps every slider inside it in continuous
/// time, `check` proves it.
///
/// The default is the paper's machine: its two cases move the sliders
/// between 82.2 mm (Case II, P9, q3) and 402.8 mm (Case I, P10, q2) (the
/// decoded Tables 5 and 8); the travel is 50–415 mm, that span with room
/// for the quintics' excursions between knots, and its top is the default
/// homing switch (0.42 m, above the travel) less its 5 mm back-off, so a
/// plan never reaches the switch.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Travel {
    /// Lowest joint position per axis (m).
    pub min: [f64; 3],
    /// Highest joint position per axis (m).
    pub max: [f64; 3],
}

impl Default for Travel {
    fn default() -> Self {
        Self {
            min: [0.050; 3],
            max: [0.415; 3],
        }
    }
}

/// A joint position outside the travel (axis 0-based; messages count from 1).
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error(
    "slider {} at {} mm is {} its travel {} {} mm",
    axis + 1,
    Short(micrometres(*position_m)),
    if *below { "below" } else { "above" },
    if *below { "min" } else { "max" },
    Short(micrometres(*limit_m))
)]
pub struct OutsideTravel {
    pub axis: usize,
    pub position_m: f64,
    pub limit_m: f64,
    /// Below the minimum (else above the maximum).
    pub below: bool,
}

/// A position in metres as millimetres rounded to the micrometre.
fn micrometres(x_m: f64) -> f64 {
    let um = x_m * 1e6;
    let r = libm::round(um);
    if r.is_finite() { r / 1e3 } else { um / 1e3 }
}

impl Travel {
    /// Every bound finite, |bound| ≤ 1e6 m and min < max per axis.
    pub fn validate(&self) -> Result<(), LimitError> {
        for a in 0..3 {
            for (name, v) in [("travel.min", self.min[a]), ("travel.max", self.max[a])] {
                if !(v.is_finite() && v.abs() <= PARAM_MAX) {
                    return Err(LimitError { name, value: v });
                }
            }
            if self.min[a] >= self.max[a] {
                return Err(LimitError {
                    name: "travel.max (must be above travel.min)",
                    value: self.max[a],
                });
            }
        }
        Ok(())
    }

    /// The first axis of `q` outside the travel (NaN counts as outside).
    pub fn outside(&self, q: &[f64; 3]) -> Option<OutsideTravel> {
        (0..3).find_map(|axis| {
            let p = q[axis];
            if p.is_nan() || p < self.min[axis] {
                Some(OutsideTravel {
                    axis,
                    position_m: p,
                    limit_m: self.min[axis],
                    below: true,
                })
            } else if p > self.max[axis] {
                Some(OutsideTravel {
                    axis,
                    position_m: p,
                    limit_m: self.max[axis],
                    below: false,
                })
            } else {
                None
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::f64::consts::PI;
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
    fn guideway_constants_are_libm_sincos_bit_for_bit() {
        for (a, (co, s)) in GUIDEWAY_ANGLES_DEG.iter().zip(GUIDEWAY_COS_SIN) {
            let (ls, lc) = libm::sincos(a * PI / 180.0);
            assert_eq!(
                (co.to_bits(), s.to_bits()),
                (lc.to_bits(), ls.to_bits()),
                "{a}°: {lc:?} {ls:?}"
            );
        }
        // The f32 model from f32 parameters equals the f64 model within f32 rounding.
        let m64 = Robot::default().model::<f64>();
        // The drive's path: the wire's f32 values, straight into the model.
        let cfg = crate::protocol::config::DriveConfig::new(
            &Robot::default(),
            &Limits::default(),
            0,
            &crate::protocol::config::DriveSettings::default(),
            0.5,
            0.2,
        );
        let r32: RobotParams<f32> = cfg.robot();
        let m32 = r32.native_model();
        for i in 0..3 {
            for k in 0..3 {
                assert!((m32.rho_u[i][k] as f64 - m64.rho_u[i][k]).abs() < 1e-7);
            }
        }
        assert!((m32.ratio as f64 / m64.ratio - 1.0).abs() < 1e-6);
        assert!((m32.rotor_inertia as f64 / m64.rotor_inertia - 1.0).abs() < 1e-6);
    }

    #[test]
    fn bad_parameters_are_named() {
        let r = Robot {
            lead: 0.0,
            ..Robot::default()
        };
        assert_eq!(
            r.validate().unwrap_err().to_string(),
            "robot parameter `lead` must be in 1e-6..1e6, got 0"
        );
        // Absurd magnitudes are bad parameters, named in a short message.
        for (r, says) in [
            (
                Robot {
                    lead: 1e300,
                    ..Robot::default()
                },
                "robot parameter `lead` must be in 1e-6..1e6, got 1e300",
            ),
            (
                Robot {
                    platform_mass: 1e250,
                    ..Robot::default()
                },
                "robot parameter `platform_mass` must be in 0..1e6, got 1e250",
            ),
            (
                Robot {
                    strut_length: 1e-300,
                    ..Robot::default()
                },
                "robot parameter `strut_length` must be in 1e-6..1e6, got 1e-300",
            ),
        ] {
            assert_eq!(r.validate().unwrap_err().to_string(), says);
        }
        let l = Limits {
            jerk: -1e250,
            ..Limits::default()
        };
        assert_eq!(
            l.validate().unwrap_err().to_string(),
            "limit `jerk` must be finite and > 0, got -1e250"
        );
        let t = Travel::default();
        assert_eq!(t.validate(), Ok(()));
        assert_eq!(t.outside(&[0.2, 0.3, 0.4]), None);
        assert_eq!(
            t.outside(&[0.2, -0.25, 0.4]).unwrap().to_string(),
            "slider 2 at -250 mm is below its travel min 50 mm"
        );
        assert_eq!(t.outside(&[0.2, 0.3, f64::NAN]).map(|o| o.axis), Some(2));
        let l = Limits {
            jerk: f64::NAN,
            ..Limits::default()
        };
        assert_eq!(l.validate().unwrap_err().name, "jerk");
    }
}
