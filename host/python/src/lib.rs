//! The `triquint` Python module: the planner of `triquint-planner` and the
//! kinematics and dynamics of `triquint-shared`, with numpy arrays.
//!
//! Units as in the CLI: Cartesian inputs in millimetres unless `units="m"`;
//! everything a `Plan` returns is SI. Every entry point runs under a guard
//! that turns a Rust panic into `triquint.InternalError`; planning releases
//! the GIL and polls Python's signal handlers through the planner's observer.

mod arrays;
mod errors;
mod job;
mod kin;
mod machine;
mod plan;
mod robot;
mod units;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use triquint_shared::Limits;
use triquint_shared::plan::{Objective, PLAN_FORMAT};

pub(crate) fn objective_name(o: Objective) -> &'static str {
    match o {
        Objective::MinMaxJerk => "min-max-jerk",
        Objective::MinTime => "min-time",
    }
}

pub(crate) fn limits_dict<'py>(py: Python<'py>, l: &Limits) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("velocity", l.velocity)?;
    d.set_item("acceleration", l.acceleration)?;
    d.set_item("jerk", l.jerk)?;
    d.set_item("torque", l.torque)?;
    d.set_item("total_time", l.total_time)?;
    Ok(d)
}

/// Raises a Rust panic inside the guard every entry point uses; the caller
/// sees `InternalError`, never `PanicException`. For the tests.
#[pyfunction]
fn _raise_rust_panic(py: Python<'_>) -> PyResult<()> {
    errors::guard(py, || -> PyResult<()> {
        panic!("deliberate panic (test hook)")
    })
}

/// Plan, evaluate and check minimum-jerk trajectories of the triquint 3-PUU
/// translational parallel robot.
///
/// Cartesian inputs are in millimetres unless `units="m"`; everything a
/// `Plan` returns is SI (m, m/s, m/s², m/s³, N·m, s), like the plan file.
///
///     import triquint
///     p = triquint.plan([[-90, 90, 680], [-90, 90, 640], [90, -90, 680]])
///     p.duration, p.max_abs["jerk"], p.at(1.0).q, p.sample(0.01).torque
///
/// Functions: plan, ik, fk, torque. Classes: Job, Plan, Robot, State,
/// Samples, Segments, Progress. Errors: TriquintError and its subclasses.
#[pymodule]
fn triquint(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("PLAN_FORMAT", PLAN_FORMAT)?;
    m.add_function(wrap_pyfunction!(job::plan, m)?)?;
    m.add_function(wrap_pyfunction!(kin::ik, m)?)?;
    m.add_function(wrap_pyfunction!(kin::fk, m)?)?;
    m.add_function(wrap_pyfunction!(kin::torque, m)?)?;
    m.add_function(wrap_pyfunction!(_raise_rust_panic, m)?)?;
    m.add_class::<job::PyJob>()?;
    m.add_class::<job::PyProgress>()?;
    m.add_class::<plan::PyPlan>()?;
    m.add_class::<plan::PyState>()?;
    m.add_class::<plan::PySamples>()?;
    m.add_class::<plan::PySegments>()?;
    m.add_class::<robot::PyRobot>()?;
    m.add_class::<machine::PyMachine>()?;
    let e = errors::errors(py)?;
    m.add("TriquintError", e.base.bind(py))?;
    m.add("InvalidJobError", e.invalid_job.bind(py))?;
    m.add("JobFileError", e.job_file.bind(py))?;
    m.add("OutsideWorkspaceError", e.outside.bind(py))?;
    m.add("InfeasibleError", e.infeasible.bind(py))?;
    m.add("UnstreamableError", e.unstreamable.bind(py))?;
    m.add("CancelledError", e.cancelled.bind(py))?;
    m.add("SolverError", e.solver.bind(py))?;
    m.add("PlanFileError", e.plan_file.bind(py))?;
    m.add("InternalError", e.internal.bind(py))?;
    m.add("__all__", PUBLIC.to_vec())?;
    Ok(())
}

/// What `from triquint import *` gives (the package re-exports these).
const PUBLIC: &[&str] = &[
    "__version__",
    "PLAN_FORMAT",
    "plan",
    "ik",
    "fk",
    "torque",
    "Job",
    "Machine",
    "Plan",
    "Progress",
    "Robot",
    "Samples",
    "Segments",
    "State",
    "TriquintError",
    "InvalidJobError",
    "JobFileError",
    "OutsideWorkspaceError",
    "InfeasibleError",
    "UnstreamableError",
    "CancelledError",
    "SolverError",
    "PlanFileError",
    "InternalError",
];
