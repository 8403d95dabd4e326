//! Length units of Cartesian inputs (and of the points in errors).

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Units {
    Millimetres,
    Metres,
}

impl Units {
    /// "mm" or "m".
    pub fn parse(s: &str) -> PyResult<Self> {
        match s {
            "mm" => Ok(Units::Millimetres),
            "m" => Ok(Units::Metres),
            _ => Err(PyValueError::new_err(format!(
                "units must be \"mm\" or \"m\", got {s:?}"
            ))),
        }
    }

    /// Metres per unit.
    pub fn scale(self) -> f64 {
        match self {
            Units::Millimetres => 1e-3,
            Units::Metres => 1.0,
        }
    }

    pub fn name(self) -> &'static str {
        match self {
            Units::Millimetres => "mm",
            Units::Metres => "m",
        }
    }
}
