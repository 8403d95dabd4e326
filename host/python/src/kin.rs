//! `ik`, `fk` and `torque`: the kinematics and inverse dynamics of
//! `triquint-shared`, on one point or on arrays of points.

use nalgebra::Vector3;
use pyo3::exceptions::PyTypeError;
use pyo3::prelude::*;
use triquint_shared::dynamics;
use triquint_shared::kinematics::Pose;
use triquint_shared::readable::readable;

use crate::arrays::{Floats, floats, rows_array};
use crate::errors::{guard, invalid_job, outside_instance};
use crate::robot::{PyRobot, robot_or_default};
use crate::units::Units;

/// One triple (x, y, z given) or an array-like of shape (3,) or (n, 3).
fn triples(
    x: &Bound<'_, PyAny>,
    y: Option<f64>,
    z: Option<f64>,
    what: &str,
) -> PyResult<(Vec<[f64; 3]>, bool)> {
    match (y, z) {
        (Some(y), Some(z)) => {
            let x: f64 = x.extract().map_err(|_| {
                PyTypeError::new_err(format!(
                    "{what}: with three arguments each must be a number"
                ))
            })?;
            Ok((vec![[x, y, z]], false))
        }
        (None, None) => {
            let a = floats(x, what)?;
            let many = a.triples(what)?;
            Ok((a.rows3(), many))
        }
        _ => Err(PyTypeError::new_err(format!(
            "{what}: give three numbers or one array of shape (3,) or (n, 3)"
        ))),
    }
}

fn finite(py: Python<'_>, rows: &[[f64; 3]], field: &str) -> PyResult<()> {
    for (i, p) in rows.iter().enumerate() {
        if p.iter().any(|v| !v.is_finite()) {
            return Err(invalid_job(
                py,
                field,
                &format!(
                    "row {} ({}, {}, {}) is not finite",
                    i + 1,
                    readable(p[0]),
                    readable(p[1]),
                    readable(p[2])
                ),
            ));
        }
    }
    Ok(())
}

fn outside(
    py: Python<'_>,
    what: &str,
    index: usize,
    kind: &str,
    p_m: [f64; 3],
    units: Units,
    reason: String,
) -> PyErr {
    let s = 1.0 / units.scale();
    let msg = format!(
        "{what} {} ({}, {}, {}) {}: {reason}",
        index + 1,
        readable(p_m[0] * s),
        readable(p_m[1] * s),
        readable(p_m[2] * s),
        match kind {
            "position" => format!("{} is outside the workspace", units.name()),
            _ => format!("{} have no valid pose", units.name()),
        }
    );
    match outside_instance(py, &msg, index, kind, p_m, units, &reason) {
        Ok(inst) => PyErr::from_value(inst),
        Err(e) => e,
    }
}

/// ik(x, y, z, *, units='mm', robot=None) -> ndarray
///
/// Slider positions (q1, q2, q3) for platform positions, by inverse
/// kinematics: `ik(x, y, z)` or `ik(points)` with points of shape (3,) or
/// (n, 3), giving shape (3,) or (n, 3). In and out in millimetres like
/// `triquint ik`, or metres with `units="m"`. A position the robot cannot
/// reach raises OutsideWorkspaceError (`index`, `point`); NaN raises
/// InvalidJobError.
#[pyfunction]
#[pyo3(signature = (x, y = None, z = None, *, units = "mm", robot = None))]
pub fn ik<'py>(
    py: Python<'py>,
    x: &Bound<'py, PyAny>,
    y: Option<f64>,
    z: Option<f64>,
    units: &str,
    robot: Option<Bound<'py, PyRobot>>,
) -> PyResult<Bound<'py, PyAny>> {
    let units = Units::parse(units)?;
    let (rows, many) = triples(x, y, z, "points")?;
    finite(py, &rows, "points")?;
    let model = robot_or_default(robot.as_ref()).model::<f64>();
    let s = units.scale();
    let out = guard(py, || {
        rows.iter()
            .enumerate()
            .map(|(i, p)| {
                let r = Vector3::from(*p) * s;
                Pose::from_cartesian(&model, r)
                    .map(|pose| (pose.q / s).into())
                    .map_err(|e| {
                        outside(py, "point", i, "position", r.into(), units, e.to_string())
                    })
            })
            .collect::<PyResult<Vec<[f64; 3]>>>()
    })?;
    rows_array(py, &out, many)
}

/// fk(q1, q2, q3, *, units='mm', robot=None) -> ndarray
///
/// Platform positions (x, y, z) for slider positions, by the closed-form
/// forward kinematics: `fk(q1, q2, q3)` or `fk(qs)` with qs of shape (3,)
/// or (n, 3), giving (3,) or (n, 3). Millimetres in and out like
/// `triquint fk`, metres with `units="m"`. Joints with no valid pose raise
/// OutsideWorkspaceError (`kind` 'joints'); NaN raises InvalidJobError.
#[pyfunction]
#[pyo3(signature = (q1, q2 = None, q3 = None, *, units = "mm", robot = None))]
pub fn fk<'py>(
    py: Python<'py>,
    q1: &Bound<'py, PyAny>,
    q2: Option<f64>,
    q3: Option<f64>,
    units: &str,
    robot: Option<Bound<'py, PyRobot>>,
) -> PyResult<Bound<'py, PyAny>> {
    let units = Units::parse(units)?;
    let (rows, many) = triples(q1, q2, q3, "joints")?;
    finite(py, &rows, "joints")?;
    let model = robot_or_default(robot.as_ref()).model::<f64>();
    let s = units.scale();
    let out = guard(py, || {
        rows.iter()
            .enumerate()
            .map(|(i, q)| {
                let q = Vector3::from(*q) * s;
                Pose::from_joints(&model, q)
                    .map(|pose| (pose.r / s).into())
                    .map_err(|e| outside(py, "joints", i, "joints", q.into(), units, e.to_string()))
            })
            .collect::<PyResult<Vec<[f64; 3]>>>()
    })?;
    rows_array(py, &out, many)
}

fn same_shape(a: &Floats, b: &Floats, c: &Floats) -> PyResult<bool> {
    let many = a.triples("q")?;
    b.triples("qd")?;
    c.triples("qdd")?;
    if a.shape != b.shape || a.shape != c.shape {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "q, qd and qdd must have the same shape, got {}, {} and {}",
            crate::arrays::shape_text(&a.shape),
            crate::arrays::shape_text(&b.shape),
            crate::arrays::shape_text(&c.shape)
        )));
    }
    Ok(many)
}

/// torque(q, qd, qdd, *, robot=None) -> ndarray
///
/// Motor torques (N·m) by inverse dynamics (virtual work) for joint
/// positions q (m), velocities qd (m/s) and accelerations qdd (m/s²), SI
/// like the plan file: each of shape (3,) or all (n, 3), giving (3,) or
/// (n, 3). Positive torque drives a slider up. Joints with no valid pose
/// raise OutsideWorkspaceError; NaN raises InvalidJobError.
#[pyfunction]
#[pyo3(signature = (q, qd, qdd, *, robot = None))]
pub fn torque<'py>(
    py: Python<'py>,
    q: &Bound<'py, PyAny>,
    qd: &Bound<'py, PyAny>,
    qdd: &Bound<'py, PyAny>,
    robot: Option<Bound<'py, PyRobot>>,
) -> PyResult<Bound<'py, PyAny>> {
    let (q, qd, qdd) = (floats(q, "q")?, floats(qd, "qd")?, floats(qdd, "qdd")?);
    let many = same_shape(&q, &qd, &qdd)?;
    let (q, qd, qdd) = (q.rows3(), qd.rows3(), qdd.rows3());
    finite(py, &q, "q")?;
    finite(py, &qd, "qd")?;
    finite(py, &qdd, "qdd")?;
    let model = robot_or_default(robot.as_ref()).model::<f64>();
    let out = guard(py, || {
        (0..q.len())
            .map(|i| {
                let v = |a: [f64; 3]| Vector3::from(a);
                dynamics::torque(&model, &v(q[i]), &v(qd[i]), &v(qdd[i]))
                    .map(Into::into)
                    .map_err(|e| {
                        outside(
                            py,
                            "joints",
                            i,
                            "joints",
                            q[i],
                            Units::Metres,
                            e.to_string(),
                        )
                    })
            })
            .collect::<PyResult<Vec<[f64; 3]>>>()
    })?;
    rows_array(py, &out, many)
}
