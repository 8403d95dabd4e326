//! `triquint.Robot`: the machine's geometry and inertia (SI units), the
//! paper's Table 1 by default.

use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};
use triquint_shared::Robot;

use crate::errors::{guard, invalid_job};

/// Geometry and inertia of the 3-PUU machine, SI units; the defaults are
/// the paper's Table 1. Every field is a keyword of the constructor:
///
///     Robot(payload_mass=0.5)           # the paper's machine with 0.5 kg on the platform
///
/// platform_radius s (m), base_radius S (m), strut_length l (m),
/// slider_offset d (m), platform_mass m_p (kg), payload_mass (kg),
/// strut_mass m_i (kg), slider_mass m_qi (kg), motor_inertia I_M (kg m²),
/// coupling_inertia I_C (kg m²), leadscrew_inertia I_L (kg m²), lead p
/// (slider travel per motor turn, m), gravity g (m/s², along -z).
/// A value that cannot describe a machine raises InvalidJobError with
/// `field` 'robot.<name>'. Robots compare equal field by field and pickle.
#[pyclass(name = "Robot", module = "triquint", frozen, eq, get_all)]
#[derive(Clone, Debug, PartialEq)]
pub struct PyRobot {
    pub platform_radius: f64,
    pub base_radius: f64,
    pub strut_length: f64,
    pub slider_offset: f64,
    pub platform_mass: f64,
    pub payload_mass: f64,
    pub strut_mass: f64,
    pub slider_mass: f64,
    pub motor_inertia: f64,
    pub coupling_inertia: f64,
    pub leadscrew_inertia: f64,
    pub lead: f64,
    pub gravity: f64,
}

impl From<&Robot> for PyRobot {
    fn from(r: &Robot) -> Self {
        Self {
            platform_radius: r.platform_radius,
            base_radius: r.base_radius,
            strut_length: r.strut_length,
            slider_offset: r.slider_offset,
            platform_mass: r.platform_mass,
            payload_mass: r.payload_mass,
            strut_mass: r.strut_mass,
            slider_mass: r.slider_mass,
            motor_inertia: r.motor_inertia,
            coupling_inertia: r.coupling_inertia,
            leadscrew_inertia: r.leadscrew_inertia,
            lead: r.lead,
            gravity: r.gravity,
        }
    }
}

impl PyRobot {
    pub fn robot(&self) -> Robot {
        Robot {
            platform_radius: self.platform_radius,
            base_radius: self.base_radius,
            strut_length: self.strut_length,
            slider_offset: self.slider_offset,
            platform_mass: self.platform_mass,
            payload_mass: self.payload_mass,
            strut_mass: self.strut_mass,
            slider_mass: self.slider_mass,
            motor_inertia: self.motor_inertia,
            coupling_inertia: self.coupling_inertia,
            leadscrew_inertia: self.leadscrew_inertia,
            lead: self.lead,
            gravity: self.gravity,
        }
    }

    fn fields(&self) -> [(&'static str, f64); 13] {
        [
            ("platform_radius", self.platform_radius),
            ("base_radius", self.base_radius),
            ("strut_length", self.strut_length),
            ("slider_offset", self.slider_offset),
            ("platform_mass", self.platform_mass),
            ("payload_mass", self.payload_mass),
            ("strut_mass", self.strut_mass),
            ("slider_mass", self.slider_mass),
            ("motor_inertia", self.motor_inertia),
            ("coupling_inertia", self.coupling_inertia),
            ("leadscrew_inertia", self.leadscrew_inertia),
            ("lead", self.lead),
            ("gravity", self.gravity),
        ]
    }
}

/// The robot a call uses: the given one, or the paper's.
pub fn robot_or_default(robot: Option<&Bound<'_, PyRobot>>) -> Robot {
    robot.map_or_else(Robot::default, |r| r.get().robot())
}

#[pymethods]
impl PyRobot {
    #[new]
    #[pyo3(signature = (*, platform_radius = 0.070, base_radius = 0.370, strut_length = 0.450,
        slider_offset = 0.070, platform_mass = 3.5, payload_mass = 0.0, strut_mass = 0.72,
        slider_mass = 1.377, motor_inertia = 1.4e-4, coupling_inertia = 1.3e-5,
        leadscrew_inertia = 1.1e-4, lead = 0.010, gravity = 9.807))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        platform_radius: f64,
        base_radius: f64,
        strut_length: f64,
        slider_offset: f64,
        platform_mass: f64,
        payload_mass: f64,
        strut_mass: f64,
        slider_mass: f64,
        motor_inertia: f64,
        coupling_inertia: f64,
        leadscrew_inertia: f64,
        lead: f64,
        gravity: f64,
    ) -> PyResult<Self> {
        let r = Self {
            platform_radius,
            base_radius,
            strut_length,
            slider_offset,
            platform_mass,
            payload_mass,
            strut_mass,
            slider_mass,
            motor_inertia,
            coupling_inertia,
            leadscrew_inertia,
            lead,
            gravity,
        };
        guard(py, || {
            r.robot().validate().map_err(|e| {
                let triquint_shared::params::ParamError::Invalid { name, .. } = e;
                invalid_job(py, &format!("robot.{name}"), &e.to_string())
            })
        })?;
        Ok(r)
    }

    /// The fields as a dict (SI units), the constructor's keywords.
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (k, v) in self.fields() {
            d.set_item(k, v)?;
        }
        Ok(d)
    }

    /// A robot from a dict of fields (missing ones take the defaults).
    #[classmethod]
    fn from_dict<'py>(
        cls: &Bound<'py, PyType>,
        fields: &Bound<'py, PyDict>,
    ) -> PyResult<Bound<'py, PyAny>> {
        if fields
            .keys()
            .iter()
            .any(|k| !k.is_instance_of::<pyo3::types::PyString>())
        {
            return Err(PyTypeError::new_err(
                "Robot.from_dict: keys must be strings",
            ));
        }
        cls.call((), Some(fields))
    }

    fn __reduce__<'py>(
        &self,
        py: Python<'py>,
    ) -> PyResult<(Bound<'py, PyAny>, (Bound<'py, PyDict>,))> {
        let from_dict = py.get_type::<PyRobot>().getattr("from_dict")?;
        Ok((from_dict, (self.to_dict(py)?,)))
    }

    fn __repr__(&self) -> String {
        let body: Vec<String> = self
            .fields()
            .iter()
            .map(|(k, v)| format!("{k}={v:?}"))
            .collect();
        format!("Robot({})", body.join(", "))
    }
}
