//! `triquint.Machine`: the machine file (docs/machine.md), read by the
//! same function as the CLI's `--machine`.

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};
use triquint_cli_common::machine_file::{parse_machine, read_machine};
use triquint_shared::machine::Machine;

use crate::errors::invalid_job;
use crate::robot::PyRobot;

/// A machine: robot, homing, axes, travel and ceilings (docs/machine.md).
///
///     Machine()                              # the paper's machine
///     Machine.from_toml("machine.toml")      # a machine file
///     triquint.plan(points, machine=m)       # planned for it
///
/// A refused file raises InvalidJobError with `field` 'machine' and the
/// CLI's one-line message (line, key, accepted range).
#[pyclass(name = "Machine", module = "triquint", frozen)]
#[derive(Clone, Debug)]
pub struct PyMachine {
    pub machine: Machine,
}

#[pymethods]
impl PyMachine {
    #[new]
    fn new() -> Self {
        Self {
            machine: Machine::default(),
        }
    }

    /// from_toml(path) -> Machine
    #[classmethod]
    fn from_toml(_cls: &Bound<'_, PyType>, py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        read_machine(Some(&path))
            .map(|machine| Self { machine })
            .map_err(|e| invalid_job(py, "machine", &e.to_string()))
    }

    /// from_text(text) -> Machine: a machine file's contents.
    #[classmethod]
    fn from_text(_cls: &Bound<'_, PyType>, py: Python<'_>, text: &str) -> PyResult<Self> {
        parse_machine(text)
            .map(|machine| Self { machine })
            .map_err(|e| invalid_job(py, "machine", &e.to_string()))
    }

    #[getter]
    fn robot(&self) -> PyRobot {
        PyRobot::from(&self.machine.robot)
    }

    /// {'min': [m, m, m], 'max': [m, m, m]}: the sliders' travel.
    #[getter]
    fn travel<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = self.machine.travel();
        let d = PyDict::new(py);
        d.set_item("min", t.min.to_vec())?;
        d.set_item("max", t.max.to_vec())?;
        Ok(d)
    }

    /// velocity, acceleration, jerk, torque: what no plan may exceed
    /// (torque lowered to the weakest axis's Kt × current limit).
    #[getter]
    fn ceilings<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = self.machine.effective_ceilings();
        let d = PyDict::new(py);
        d.set_item("velocity", c.velocity)?;
        d.set_item("acceleration", c.acceleration)?;
        d.set_item("jerk", c.jerk)?;
        d.set_item("torque", c.torque)?;
        Ok(d)
    }

    /// Encoder counts per metre of slider travel, per axis (signed).
    #[getter]
    fn counts_per_metre(&self) -> Vec<f64> {
        (0..3).map(|a| self.machine.counts_per_metre(a)).collect()
    }

    fn __repr__(&self) -> String {
        let t = self.machine.travel();
        format!(
            "Machine(lead={} m, travel {:?}..{:?} m)",
            self.machine.robot.lead, t.min, t.max
        )
    }
}
