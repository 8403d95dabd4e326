//! `triquint.Plan`: a planned trajectory (the CLI's plan file), evaluated
//! into numpy arrays, checked, saved and loaded.

use std::path::PathBuf;

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyType};
use triquint_shared::kinematics::KinematicsError;
use triquint_shared::plan::{JointState, Plan, SampleError, eval};
use triquint_shared::{dynamics, kinematics};

use crate::arrays::{array, floats, rows_array};
use crate::errors::{guard, load_error};
use crate::robot::PyRobot;

/// Joint positions `q` (m), velocities `v` (m/s), accelerations `a`
/// (m/s²) and jerks `jerk` (m/s³) at the times asked for: each of shape
/// (3,) for one time, (m, 3) for m times.
#[pyclass(name = "State", module = "triquint", frozen, get_all)]
pub struct PyState {
    pub q: Py<PyAny>,
    pub v: Py<PyAny>,
    pub a: Py<PyAny>,
    pub jerk: Py<PyAny>,
}

#[pymethods]
impl PyState {
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!(
            "State(q={}, v={}, a={}, jerk={})",
            self.q.bind(py).repr()?,
            self.v.bind(py).repr()?,
            self.a.bind(py).repr()?,
            self.jerk.bind(py).repr()?
        ))
    }
}

/// An evenly spaced sampling of a plan: times `t` (n,) (s), 0, dt, 2 dt, …
/// and the end time exactly; joint `q`, `v`, `a`, `jerk` (n, 3) as in
/// `State`; motor `torque` (n, 3) (N·m) by the inverse dynamics; and the
/// `platform` position (n, 3) (m) by forward kinematics.
#[pyclass(name = "Samples", module = "triquint", frozen, get_all)]
pub struct PySamples {
    pub t: Py<PyAny>,
    pub q: Py<PyAny>,
    pub v: Py<PyAny>,
    pub a: Py<PyAny>,
    pub jerk: Py<PyAny>,
    pub torque: Py<PyAny>,
    pub platform: Py<PyAny>,
}

#[pymethods]
impl PySamples {
    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        self.t.bind(py).len()
    }
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!("Samples(n={})", self.t.bind(py).len()?))
    }
}

/// The segments of a plan: start times `t0` (k,) and `durations` (k,) (s),
/// and `coeffs` (k, 3, 6): joint j of segment i is
/// q_j(t0[i] + u) = Σ_p coeffs[i, j, p] u^p for u in [0, durations[i]]
/// (ascending powers of segment-local time, metres and seconds).
#[pyclass(name = "Segments", module = "triquint", frozen, get_all)]
pub struct PySegments {
    pub t0: Py<PyAny>,
    pub durations: Py<PyAny>,
    pub coeffs: Py<PyAny>,
}

#[pymethods]
impl PySegments {
    fn __len__(&self, py: Python<'_>) -> PyResult<usize> {
        self.durations.bind(py).len()
    }
    fn __repr__(&self, py: Python<'_>) -> PyResult<String> {
        Ok(format!("Segments(k={})", self.durations.bind(py).len()?))
    }
}

/// A planned trajectory: the CLI's plan file (`triquint-plan/3`), so a plan
/// made here goes to `triquint check`, `report`, `simulate` and `upload`,
/// and a plan from `triquint plan` loads here. Everything is SI (m, m/s,
/// m/s², m/s³, N·m, s). Make one with `triquint.plan`, `Plan.load` or
/// `Plan.from_json`. Plans compare equal when their files do, and pickle.
#[pyclass(name = "Plan", module = "triquint", frozen, eq)]
#[derive(Clone, PartialEq)]
pub struct PyPlan {
    pub plan: Plan,
}

fn states_arrays<'py>(
    py: Python<'py>,
    states: &[JointState],
    many: bool,
) -> PyResult<[Bound<'py, PyAny>; 4]> {
    let col = |f: fn(&JointState) -> [f64; 3]| -> Vec<[f64; 3]> { states.iter().map(f).collect() };
    Ok([
        rows_array(py, &col(|s| s.q), many)?,
        rows_array(py, &col(|s| s.v), many)?,
        rows_array(py, &col(|s| s.a), many)?,
        rows_array(py, &col(|s| s.jerk), many)?,
    ])
}

fn pretty(plan: &Plan) -> PyResult<String> {
    serde_json::to_string_pretty(plan)
        .map_err(|e| PyValueError::new_err(format!("cannot encode the plan: {e}")))
}

struct Sampled {
    t: Vec<f64>,
    states: Vec<JointState>,
    torque: Vec<[f64; 3]>,
    platform: Vec<[f64; 3]>,
}

/// Why a plan cannot be sampled: the step, or a pose the model cannot take.
#[derive(Debug, thiserror::Error)]
enum SampleFailure {
    #[error(transparent)]
    Step(#[from] SampleError),
    #[error("at t = {t} s: {source}")]
    Pose {
        t: f64,
        #[source]
        source: KinematicsError,
    },
}

fn sample(plan: &Plan, dt: f64) -> Result<Sampled, SampleFailure> {
    let samples = plan.sample(dt)?;
    let model = plan.robot.model::<f64>();
    let n = samples.len();
    let mut out = Sampled {
        t: Vec::with_capacity(n),
        states: Vec::with_capacity(n),
        torque: Vec::with_capacity(n),
        platform: Vec::with_capacity(n),
    };
    for (t, s) in samples {
        let pose = |source| SampleFailure::Pose { t, source };
        let tau = dynamics::state_torque(&model, s).map_err(pose)?;
        let r = kinematics::platform_position(&model, s.q).map_err(pose)?;
        out.t.push(t);
        out.states.push(s);
        out.torque.push(tau.into());
        out.platform.push(r.into());
    }
    Ok(out)
}

#[pymethods]
impl PyPlan {
    /// Total duration (s): the sum of the segments' durations.
    #[getter]
    fn duration(&self) -> f64 {
        self.plan.duration()
    }

    /// The plan file's `format` (`triquint.PLAN_FORMAT`).
    #[getter]
    fn format(&self) -> &str {
        &self.plan.format
    }

    /// 'min-max-jerk' or 'min-time'.
    #[getter]
    fn objective(&self) -> &'static str {
        crate::objective_name(self.plan.objective)
    }

    /// The robot the plan was made for.
    #[getter]
    fn robot(&self) -> PyRobot {
        PyRobot::from(&self.plan.robot)
    }

    /// The job's limits: velocity (m/s), acceleration (m/s²), jerk (m/s³),
    /// torque (N·m), total_time (s, an upper bound).
    #[getter]
    fn limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        crate::limits_dict(py, &self.plan.limits)
    }

    /// The input shaper the plan was shaped with, as a dict (type,
    /// frequency_hz, damping, duration_s: the time it adds), or None.
    #[getter]
    fn shaper<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(s) = &self.plan.shaping else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("type", s.shaper.shaper.name())?;
        d.set_item("frequency_hz", s.shaper.frequency_hz)?;
        d.set_item("damping", s.shaper.damping)?;
        d.set_item(
            "duration_s",
            self.plan.total_time_s - s.unshaped.total_time_s,
        )?;
        Ok(Some(d))
    }

    /// Via-points (n, 3), metres.
    #[getter]
    fn via_points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_array(py, &self.plan.via_points_m, true)
    }

    /// Joint positions q (k + 1, 3), metres, at the knots (the segment
    /// boundaries): the via-points' IK, with points on the straight lines
    /// between them for paths of fewer than five via-points.
    #[getter]
    fn knots<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_array(py, &self.plan.knots_m, true)
    }

    /// Indices into `knots` of the knots whose time and joint position the
    /// planner chose (a min-time job with `knots = "free"`); empty otherwise.
    #[getter]
    fn free_knots(&self) -> Vec<usize> {
        self.plan.free_knots.clone()
    }

    /// The platform's largest distance from the straight segment between
    /// the via-points it travels between: a dict of 'max' (m, sampled),
    /// 'at' (s, where), 'bound' (m, at most this anywhere: a Lipschitz bound
    /// between samples), 'step' (s, between samples) and 'limit' (m, the
    /// job's `max_deviation_mm` the plan records and `check` proves, or None).
    #[getter]
    fn path_deviation<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = triquint_planner::stats::recorded_deviation(&self.plan)
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let out = PyDict::new(py);
        out.set_item("max", d.max_m)?;
        out.set_item("at", d.at_s)?;
        out.set_item("bound", d.bound_m)?;
        out.set_item("step", d.step_s)?;
        out.set_item("limit", d.limit_m)?;
        Ok(out)
    }

    /// The segments: `t0`, `durations` (k,) and `coeffs` (k, 3, 6).
    #[getter]
    fn segments(&self, py: Python<'_>) -> PyResult<PySegments> {
        let k = self.plan.segments.len();
        let t0: Vec<f64> = self.plan.segments.iter().map(|s| s.t0_s).collect();
        let h: Vec<f64> = self.plan.segments.iter().map(|s| s.duration_s).collect();
        let c: Vec<f64> = self
            .plan
            .segments
            .iter()
            .flat_map(|s| s.coeffs.iter().flatten().copied())
            .collect();
        Ok(PySegments {
            t0: array(py, &t0, &[k])?.unbind(),
            durations: array(py, &h, &[k])?.unbind(),
            coeffs: array(py, &c, &[k, 3, 6])?.unbind(),
        })
    }

    /// Exact continuous-time maxima per joint, from the plan file: a dict of
    /// 'velocity' (m/s), 'acceleration' (m/s²), 'jerk' (m/s³), 'torque' (N·m)
    /// to arrays of shape (3,).
    #[getter]
    fn max_abs<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let m = &self.plan.max_abs;
        let d = PyDict::new(py);
        d.set_item("velocity", rows_array(py, &[m.velocity], false)?)?;
        d.set_item("acceleration", rows_array(py, &[m.acceleration], false)?)?;
        d.set_item("jerk", rows_array(py, &[m.jerk], false)?)?;
        d.set_item("torque", rows_array(py, &[m.torque], false)?)?;
        Ok(d)
    }

    /// How the solver got there: seconds, starts, lp_solves.
    #[getter]
    fn solver<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let s = &self.plan.solver;
        let d = PyDict::new(py);
        d.set_item("seconds", s.seconds)?;
        d.set_item("starts", s.starts)?;
        d.set_item("lp_solves", s.lp_solves)?;
        Ok(d)
    }

    /// at(t) -> State
    ///
    /// Joint position, velocity, acceleration and jerk at plan time `t` (s):
    /// a number gives arrays of shape (3,), an array of shape (m,) gives
    /// (m, 3). Before 0 and after the end the joints rest at the start or end
    /// position (zero velocity, acceleration, jerk). NaN is a ValueError.
    fn at(&self, py: Python<'_>, t: &Bound<'_, PyAny>) -> PyResult<PyState> {
        let times = floats(t, "t")?;
        let many = match times.shape.len() {
            0 => false,
            1 => true,
            _ => {
                return Err(PyValueError::new_err(format!(
                    "t must be a number or an array of shape (m,), got shape {}",
                    crate::arrays::shape_text(&times.shape)
                )));
            }
        };
        // The plan's duration summed once, not at every time asked.
        let duration = eval::duration(&self.plan.segments);
        let states = guard(py, || {
            times
                .data
                .iter()
                .map(|&t| {
                    eval::at_within(&self.plan.segments, duration, t).ok_or_else(|| {
                        PyValueError::new_err(if t.is_nan() {
                            "t is NaN".to_string()
                        } else {
                            "the plan has no segments".to_string()
                        })
                    })
                })
                .collect::<PyResult<Vec<_>>>()
        })?;
        let [q, v, a, jerk] = states_arrays(py, &states, many)?;
        Ok(PyState {
            q: q.unbind(),
            v: v.unbind(),
            a: a.unbind(),
            jerk: jerk.unbind(),
        })
    }

    /// sample(dt) -> Samples
    ///
    /// Samples at t = 0, dt, 2 dt, … and at the end time exactly: times,
    /// joint motion, motor torque and platform position (see `Samples`).
    /// `dt` (s) must be finite and positive (at most 2**24 samples).
    fn sample(&self, py: Python<'_>, dt: f64) -> PyResult<PySamples> {
        let plan = &self.plan;
        let s = py
            .detach(|| std::panic::catch_unwind(|| sample(plan, dt)))
            .map_err(|p| crate::errors::internal_error(py, p.as_ref()))?
            .map_err(|e| PyValueError::new_err(e.to_string()))?;
        let [q, v, a, jerk] = states_arrays(py, &s.states, true)?;
        Ok(PySamples {
            t: array(py, &s.t, &[s.t.len()])?.unbind(),
            q: q.unbind(),
            v: v.unbind(),
            a: a.unbind(),
            jerk: jerk.unbind(),
            torque: rows_array(py, &s.torque, true)?.unbind(),
            platform: rows_array(py, &s.platform, true)?.unbind(),
        })
    }

    /// check() -> list[dict]
    ///
    /// The independent verification of `triquint check`: interpolation, C3
    /// continuity, rest at both ends, every limit in continuous time. One
    /// dict per check: {'what': str, 'value': float, 'bound': float,
    /// 'ok': bool}. A plan that is not usable raises PlanFileError.
    fn check<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let plan = &self.plan;
        let rows = py
            .detach(|| std::panic::catch_unwind(|| triquint_planner::check(plan)))
            .map_err(|p| crate::errors::internal_error(py, p.as_ref()))?
            .map_err(|e| load_error(py, &e, None))?;
        let list = PyList::empty(py);
        for r in rows {
            let d = PyDict::new(py);
            d.set_item("what", r.what)?;
            d.set_item("value", r.value)?;
            d.set_item("bound", r.bound)?;
            d.set_item("ok", r.ok)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// to_json() -> str
    ///
    /// The plan file's text (`triquint-plan/3` JSON, as `triquint plan`
    /// writes it).
    fn to_json(&self) -> PyResult<String> {
        pretty(&self.plan)
    }

    /// from_json(text) -> Plan
    ///
    /// A plan from plan-file text, validated as every `triquint` command
    /// validates it; PlanFileError otherwise.
    #[classmethod]
    fn from_json(_cls: &Bound<'_, PyType>, py: Python<'_>, text: &str) -> PyResult<Self> {
        let plan = guard(py, || {
            triquint_planner::files::parse_plan(text).map_err(|e| load_error(py, &e, None))
        })?;
        Ok(Self { plan })
    }

    /// load(path) -> Plan
    ///
    /// Reads a plan file (OSError if it cannot be read, PlanFileError if it
    /// is not a usable plan).
    #[classmethod]
    fn load(_cls: &Bound<'_, PyType>, py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let text =
            triquint_planner::read_text(&path, triquint_planner::MAX_PLAN_BYTES, "a plan file")?;
        let origin = path.display().to_string();
        let plan = guard(py, || {
            triquint_planner::files::parse_plan(&text)
                .map_err(|e| load_error(py, &e, Some(&origin)))
        })?;
        Ok(Self { plan })
    }

    /// save(path)
    ///
    /// Writes the plan file (the text of `to_json()` and a newline), as
    /// `triquint plan -o` does: through an exclusive temporary file renamed
    /// into place, so a failure leaves no partial file. OSError if `path` is
    /// not a regular file (a device, FIFO, folder or symbolic link) or
    /// cannot be written.
    fn save(&self, path: PathBuf) -> PyResult<()> {
        let text = pretty(&self.plan)? + "\n";
        triquint_cli_common::output::replace_file(&path, text.as_bytes(), &[])?;
        Ok(())
    }

    fn __reduce__<'py>(&self, py: Python<'py>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let from_json = py.get_type::<PyPlan>().getattr("from_json")?;
        Ok((from_json, (pretty(&self.plan)?,)))
    }

    fn __repr__(&self) -> String {
        let max = |v: [f64; 3]| v.iter().fold(0.0f64, |a, b| a.max(*b));
        format!(
            "Plan({}, {} segments, duration {:.6} s, max |jerk| {:.6} m/s³, format {:?})",
            crate::objective_name(self.plan.objective),
            self.plan.segments.len(),
            self.plan.duration(),
            max(self.plan.max_abs.jerk),
            self.plan.format
        )
    }
}
