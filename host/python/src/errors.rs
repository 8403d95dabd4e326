//! The exception hierarchy (`TriquintError` and its subclasses, with data
//! fields), the conversion of every planner error into it, and the guard
//! that keeps a Rust panic from reaching Python as a `PanicException`.

use std::any::Any;
use std::panic::{AssertUnwindSafe, catch_unwind};

use pyo3::exceptions::{PyException, PyValueError};
use pyo3::prelude::*;
use pyo3::sync::PyOnceLock;
use pyo3::types::{PyDict, PyTuple, PyType};
use triquint_planner::files::LoadError;
use triquint_planner::{CancelReason, Limit, PlanError, PointKind};

use crate::units::Units;

/// The exception types, made once per interpreter (several bases each,
/// which `create_exception!` cannot do).
pub struct Errors {
    pub base: Py<PyType>,
    pub invalid_job: Py<PyType>,
    pub job_file: Py<PyType>,
    pub outside: Py<PyType>,
    pub infeasible: Py<PyType>,
    pub unstreamable: Py<PyType>,
    pub cancelled: Py<PyType>,
    pub solver: Py<PyType>,
    pub plan_file: Py<PyType>,
    pub internal: Py<PyType>,
}

static ERRORS: PyOnceLock<Errors> = PyOnceLock::new();

fn make_type(
    py: Python<'_>,
    name: &str,
    bases: &[&Bound<'_, PyType>],
    doc: &str,
) -> PyResult<Py<PyType>> {
    let dict = PyDict::new(py);
    dict.set_item("__doc__", doc)?;
    dict.set_item("__module__", "triquint")?;
    let bases = PyTuple::new(py, bases)?;
    let ty = py.get_type::<PyType>().call1((name, bases, dict))?;
    Ok(ty.cast_into::<PyType>()?.unbind())
}

/// The exception types (made on first use).
pub fn errors(py: Python<'_>) -> PyResult<&Errors> {
    ERRORS.get_or_try_init(py, || {
        let exception = py.get_type::<PyException>();
        let value_error = py.get_type::<PyValueError>();
        let base = make_type(
            py,
            "TriquintError",
            &[&exception],
            "Base class of every error triquint raises.",
        )?;
        let b = base.bind(py).clone();
        Ok(Errors {
            invalid_job: make_type(
                py,
                "InvalidJobError",
                &[&b, &value_error],
                "A malformed job: `field` names it as in a job file (`limits.jerk`, \
                 `path.points`, `robot.lead`, `objective`), `reason` says what is wrong. \
                 Also a ValueError. NaN input raises it.",
            )?,
            job_file: make_type(
                py,
                "JobFileError",
                &[&b, &value_error],
                "A job file that cannot be read or parsed: `origin` (its path), \
                 `line` (1-based, or None), `reason`.",
            )?,
            outside: make_type(
                py,
                "OutsideWorkspaceError",
                &[&b, &value_error],
                "A point the robot cannot reach. `index` (0-based), `point` (x, y, z in \
                 the caller's units: those of the call, millimetres for job files; for \
                 `fk` and `torque` the joint positions), `kind` ('via-point', 'knot', \
                 'position' or 'joints'), `position_m` (SI), `reason`.",
            )?,
            infeasible: make_type(
                py,
                "InfeasibleError",
                &[&b],
                "A valid job that no plan satisfies. `limit` ('velocity', \
                 'acceleration', 'jerk', 'torque' or 'total_time') binds; \
                 `limit_value` is its value and `reached` its value in the planner's \
                 closest plan (SI; when the total time is too short, the shortest plan \
                 time-scaled to it); `shortest_total_time` (s) is the shortest total \
                 time that meets every limit, or None. Also 'max_deviation_mm' (mm), \
                 and 'travel' (mm: a slider's travel limit and how far the closest \
                 plan takes it, with `segment` and `axis`, 0-based).",
            )?,
            unstreamable: make_type(
                py,
                "UnstreamableError",
                &[&b],
                "A plan that meets every limit but would not stream to the default \
                 drives (docs/protocol.md, Streamability): segments `first` to `last` \
                 (0-based, a queue's worth less one) last `run_s` s together, less than \
                 the `need_s` s that drives queueing `capacity` segments must hold \
                 ahead. Fewer points or a longer total time stream.",
            )?,
            cancelled: make_type(
                py,
                "CancelledError",
                &[&b],
                "Planning stopped before it finished: the progress callable returned \
                 False (`reason` 'observer') or a time budget ran out ('time-budget'). \
                 Ctrl-C raises KeyboardInterrupt instead.",
            )?,
            solver: make_type(
                py,
                "SolverError",
                &[&b],
                "The numerical solver failed on a valid job: a bug or a numerically \
                 extreme job, worth a report.",
            )?,
            plan_file: make_type(
                py,
                "PlanFileError",
                &[&b, &value_error],
                "Text that is not a usable plan file: `kind` is 'json' (not plan JSON), \
                 'format' (another format version) or 'invalid' (contents that do not \
                 fit together).",
            )?,
            internal: make_type(
                py,
                "InternalError",
                &[&b],
                "A defect inside triquint (a Rust panic, caught before it reached \
                 Python). Please report it.",
            )?,
            base,
        })
    })
}

/// An instance of `ty` with message `msg`, to set fields on.
pub fn new_error<'py>(py: Python<'py>, ty: &Py<PyType>, msg: &str) -> PyResult<Bound<'py, PyAny>> {
    ty.bind(py).call1((msg,))
}

fn triple(p: [f64; 3], scale: f64) -> (f64, f64, f64) {
    (p[0] * scale, p[1] * scale, p[2] * scale)
}

/// The Python exception of a planner error; points in `units`.
pub fn plan_error(py: Python<'_>, e: PlanError, units: Units) -> PyErr {
    match build_plan_error(py, &e, units) {
        Ok(err) => err,
        Err(err) => err,
    }
}

fn build_plan_error(py: Python<'_>, e: &PlanError, units: Units) -> PyResult<PyErr> {
    let errs = errors(py)?;
    let msg = e.to_string();
    let inst = match e {
        PlanError::InvalidJob { field, reason } => {
            let inst = new_error(py, &errs.invalid_job, &msg)?;
            inst.setattr("field", field)?;
            inst.setattr("reason", reason)?;
            inst
        }
        PlanError::JobFile {
            origin,
            line,
            reason,
        } => {
            let inst = new_error(py, &errs.job_file, &msg)?;
            inst.setattr("origin", origin)?;
            inst.setattr("line", *line)?;
            inst.setattr("reason", reason)?;
            inst
        }
        PlanError::OutsideWorkspace {
            point,
            index,
            position_m,
            reason,
        } => {
            let kind = match point {
                PointKind::ViaPoint => "via-point",
                PointKind::Knot => "knot",
                _ => "point",
            };
            outside_instance(py, &msg, *index, kind, *position_m, units, reason)?
        }
        PlanError::OutsideTravel {
            point,
            index,
            position_m,
            ..
        } => {
            // A point the robot reaches, but beyond a slider's travel: the
            // same error for Python, its reason the whole message.
            let kind = match point {
                PointKind::ViaPoint => "via-point",
                PointKind::Knot => "knot",
                _ => "point",
            };
            outside_instance(py, &msg, *index, kind, *position_m, units, &msg)?
        }
        PlanError::Infeasible {
            limit,
            limit_value,
            reached,
            shortest_total_time,
        } => {
            let inst = new_error(py, &errs.infeasible, &msg)?;
            inst.setattr("limit", limit.name())?;
            inst.setattr("unit", limit.unit())?;
            inst.setattr("limit_value", *limit_value)?;
            inst.setattr("reached", *reached)?;
            inst.setattr("shortest_total_time", *shortest_total_time)?;
            inst
        }
        PlanError::BelowHoldingTorque {
            holding_nm,
            limit_nm,
            ..
        } => {
            // Infeasible at any total time: the torque limit binds at rest.
            let inst = new_error(py, &errs.infeasible, &msg)?;
            inst.setattr("limit", Limit::Torque.name())?;
            inst.setattr("unit", Limit::Torque.unit())?;
            inst.setattr("limit_value", *limit_nm)?;
            inst.setattr("reached", *holding_nm)?;
            inst.setattr("shortest_total_time", None::<f64>)?;
            inst
        }
        PlanError::Deviation {
            limit_m, bound_m, ..
        } => {
            let inst = new_error(py, &errs.infeasible, &msg)?;
            inst.setattr("limit", "max_deviation_mm")?;
            inst.setattr("unit", "mm")?;
            inst.setattr("limit_value", limit_m * 1e3)?;
            inst.setattr("reached", bound_m * 1e3)?;
            inst.setattr("shortest_total_time", py.None())?;
            inst
        }
        PlanError::LeavesTravel {
            segment,
            axis,
            joint_m,
            limit_m,
        } => {
            let inst = new_error(py, &errs.infeasible, &msg)?;
            inst.setattr("limit", "travel")?;
            inst.setattr("unit", "mm")?;
            inst.setattr("limit_value", limit_m * 1e3)?;
            inst.setattr("reached", joint_m * 1e3)?;
            inst.setattr("shortest_total_time", py.None())?;
            inst.setattr("segment", *segment)?;
            inst.setattr("axis", *axis)?;
            inst
        }
        PlanError::Unstreamable {
            first,
            last,
            run_s,
            need_s,
            capacity,
            ..
        } => {
            let inst = new_error(py, &errs.unstreamable, &msg)?;
            inst.setattr("first", *first)?;
            inst.setattr("last", *last)?;
            inst.setattr("run_s", *run_s)?;
            inst.setattr("need_s", *need_s)?;
            inst.setattr("capacity", *capacity)?;
            inst
        }
        PlanError::Cancelled { reason } => {
            let inst = new_error(py, &errs.cancelled, &msg)?;
            let reason = match reason {
                CancelReason::Observer => "observer",
                CancelReason::TimeBudget => "time-budget",
                _ => "other",
            };
            inst.setattr("reason", reason)?;
            inst
        }
        PlanError::Solver(_) => new_error(py, &errs.solver, &msg)?,
        // Against the machine: a field of the job, as InvalidJobError.
        PlanError::OtherMachine { key, .. } => {
            let inst = new_error(py, &errs.invalid_job, &msg)?;
            inst.setattr("field", format!("robot.{key}"))?;
            inst.setattr("reason", &msg)?;
            inst
        }
        PlanError::AboveCeiling { limit, .. } => {
            let inst = new_error(py, &errs.invalid_job, &msg)?;
            inst.setattr("field", format!("limits.{limit}"))?;
            inst.setattr("reason", &msg)?;
            inst
        }
        // A variant added to the planner after this map: the base class
        // until it gets its own (tests/test_errors.py names every one).
        _ => new_error(py, &errs.base, &msg)?,
    };
    Ok(PyErr::from_value(inst))
}

/// An `OutsideWorkspaceError` instance.
pub fn outside_instance<'py>(
    py: Python<'py>,
    msg: &str,
    index: usize,
    kind: &str,
    position_m: [f64; 3],
    units: Units,
    reason: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let inst = new_error(py, &errors(py)?.outside, msg)?;
    inst.setattr("index", index)?;
    inst.setattr("kind", kind)?;
    inst.setattr("point", triple(position_m, 1.0 / units.scale()))?;
    inst.setattr("position_m", triple(position_m, 1.0))?;
    inst.setattr("reason", reason)?;
    Ok(inst)
}

/// An `InvalidJobError` for `field`.
pub fn invalid_job(py: Python<'_>, field: &str, reason: &str) -> PyErr {
    plan_error(
        py,
        PlanError::InvalidJob {
            field: field.into(),
            reason: reason.into(),
        },
        Units::Millimetres,
    )
}

/// The Python exception of a plan-file error.
pub fn load_error(py: Python<'_>, e: &LoadError, origin: Option<&str>) -> PyErr {
    let kind = match e {
        LoadError::Json(_) => "json",
        LoadError::Format { .. } => "format",
        _ => "invalid",
    };
    let msg = match origin {
        Some(o) => format!("{o}: {e}"),
        None => e.to_string(),
    };
    let built = (|| -> PyResult<PyErr> {
        let inst = new_error(py, &errors(py)?.plan_file, &msg)?;
        inst.setattr("kind", kind)?;
        Ok(PyErr::from_value(inst))
    })();
    built.unwrap_or_else(|e| e)
}

fn panic_message(payload: &(dyn Any + Send)) -> String {
    if let Some(s) = payload.downcast_ref::<&str>() {
        (*s).to_string()
    } else if let Some(s) = payload.downcast_ref::<String>() {
        s.clone()
    } else {
        "a Rust panic".to_string()
    }
}

/// The `InternalError` for a caught panic.
pub fn internal_error(py: Python<'_>, payload: &(dyn Any + Send)) -> PyErr {
    let msg = format!(
        "internal error in triquint (please report it): {}",
        panic_message(payload)
    );
    match errors(py).and_then(|e| new_error(py, &e.internal, &msg)) {
        Ok(inst) => PyErr::from_value(inst),
        Err(e) => e,
    }
}

/// Runs `f`, turning a Rust panic into `InternalError` (pyo3 would raise
/// `PanicException`, a BaseException that `except Exception` misses).
pub fn guard<T>(py: Python<'_>, f: impl FnOnce() -> PyResult<T>) -> PyResult<T> {
    match catch_unwind(AssertUnwindSafe(f)) {
        Ok(r) => r,
        Err(payload) => Err(internal_error(py, payload.as_ref())),
    }
}
