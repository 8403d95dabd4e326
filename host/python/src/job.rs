//! `triquint.Job`: what to plan (via-points, objective, limits, robot),
//! validated when it is made; and `triquint.plan`.

use std::path::PathBuf;

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyType};
use triquint_planner::shaping::{DEFAULT_DAMPING, Impulses, Shaper, ShaperSpec, UnknownShaper};
use triquint_planner::{Control, Job, KnotPlacement, Options, Progress, Stage, plan_with};
use triquint_shared::Limits;
use triquint_shared::plan::Objective;

use crate::arrays::{floats, rows_array, shape_text};
use crate::errors::{guard, internal_error, invalid_job, plan_error};
use crate::machine::PyMachine;
use crate::plan::PyPlan;
use crate::robot::{PyRobot, robot_or_default};
use crate::units::Units;

/// A planning job: via-points, objective, limits and robot, validated when
/// it is made (the errors name the field or the point). `points` is any
/// (n, 3) array-like of Cartesian platform positions, in millimetres unless
/// `units="m"`; limits are SI and joint-space: velocity (m/s), acceleration
/// (m/s²), jerk (m/s³), torque (N·m), total_time (s, an upper bound; the
/// plan's duration for min-max-jerk). `objective` is 'min-max-jerk' (the
/// smallest maximum |jerk| within total_time) or 'min-time' (the shortest
/// time that meets every limit). `knots` is 'fixed' or 'free' (min-time
/// between two via-points: the planner chooses the knots; min-max-jerk: it
/// adds a knot inside each segment, kept only where the jerk falls);
/// `knot_segments` sets a free-knot move's segment count (3..64), and
/// `max_deviation_mm` bounds the platform's distance from the straight
/// segments between via-points (the planner meets it or raises
/// InfeasibleError with limit 'max_deviation_mm'). `shaper` input-shapes
/// the plan for a resonance, as the job file's `[shaper]` table and
/// `triquint plan --shaper` do: "TYPE:HZ[:DAMPING]" (e.g. "ei:25.6:0.062";
/// zv, mzv, zvd, ei, 2hump_ei) or {"type": "ei", "frequency_hz": 25.6,
/// "damping": 0.062}; damping defaults to 0.1 (docs/input-shaping.md).
/// Defaults: the paper's Table 3 limits and Table 1 robot.
///
/// `Job.from_toml(path)` reads a job file of `triquint plan`.
#[pyclass(name = "Job", module = "triquint", frozen)]
pub struct PyJob {
    pub job: Job,
    pub units: Units,
}

pub fn parse_objective(py: Python<'_>, s: &str) -> PyResult<Objective> {
    match s {
        "min-max-jerk" => Ok(Objective::MinMaxJerk),
        "min-time" => Ok(Objective::MinTime),
        _ => Err(invalid_job(
            py,
            "objective",
            &format!("must be \"min-max-jerk\" or \"min-time\", got {s:?}"),
        )),
    }
}

fn parse_knots(py: Python<'_>, s: &str) -> PyResult<KnotPlacement> {
    match s {
        "fixed" => Ok(KnotPlacement::Fixed),
        "free" => Ok(KnotPlacement::Free),
        _ => Err(invalid_job(
            py,
            "knots",
            &format!("must be \"fixed\" or \"free\", got {s:?}"),
        )),
    }
}

/// The keywords of a job, as `plan()` and `Job()` take them.
pub struct JobArgs<'a, 'py> {
    pub units: Option<&'a str>,
    pub objective: Option<&'a str>,
    pub knots: Option<&'a str>,
    pub knot_segments: Option<usize>,
    pub max_deviation_mm: Option<f64>,
    pub total_time: Option<f64>,
    pub velocity: Option<f64>,
    pub acceleration: Option<f64>,
    pub jerk: Option<f64>,
    pub torque: Option<f64>,
    pub robot: Option<&'a Bound<'py, PyRobot>>,
    pub machine: Option<&'a Bound<'py, PyMachine>>,
    pub shaper: Option<&'a Bound<'py, PyAny>>,
}

impl JobArgs<'_, '_> {
    /// The keywords given (not None), by name.
    pub fn given(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        let mut add = |name, set: bool| {
            if set {
                v.push(name)
            }
        };
        add("units", self.units.is_some());
        add("objective", self.objective.is_some());
        add("knots", self.knots.is_some());
        add("knot_segments", self.knot_segments.is_some());
        add("max_deviation_mm", self.max_deviation_mm.is_some());
        add("total_time", self.total_time.is_some());
        add("velocity", self.velocity.is_some());
        add("acceleration", self.acceleration.is_some());
        add("jerk", self.jerk.is_some());
        add("torque", self.torque.is_some());
        add("robot", self.robot.is_some());
        add("machine", self.machine.is_some());
        add("shaper", self.shaper.is_some());
        v
    }
}

/// A shaper from `"TYPE:HZ[:DAMPING]"` (as `triquint plan --shaper`) or a
/// dict like the job file's `[shaper]` table (`type`, `frequency_hz`,
/// `damping`); `"none"` for none. InvalidJobError (field `shaper`) otherwise.
fn parse_shaper(py: Python<'_>, value: &Bound<'_, PyAny>) -> PyResult<Option<ShaperSpec>> {
    let bad = |why: String| invalid_job(py, "shaper", &why);
    let (name, frequency_hz, damping): (String, f64, Option<f64>) = if let Ok(text) =
        value.extract::<String>()
    {
        if text.eq_ignore_ascii_case("none") {
            return Ok(None);
        }
        let parts: Vec<&str> = text.split(':').collect();
        let number = |p: &str, what: &str| {
            p.trim()
                .parse::<f64>()
                .map_err(|_| bad(format!("the {what} {p:?} is not a number")))
        };
        match parts.as_slice() {
            [t, hz] => (t.to_string(), number(hz, "frequency")?, None),
            [t, hz, z] => (
                t.to_string(),
                number(hz, "frequency")?,
                Some(number(z, "damping")?),
            ),
            _ => {
                return Err(bad(format!(
                    "give \"TYPE:HZ[:DAMPING]\", e.g. \"ei:25.5:0.05\", got {text:?}"
                )));
            }
        }
    } else if let Ok(d) = value.cast::<PyDict>() {
        for key in d.keys() {
            let k: String = key.extract()?;
            if !["type", "frequency_hz", "damping"].contains(&k.as_str()) {
                return Err(bad(format!(
                    "unknown key {k:?} (type, frequency_hz, damping)"
                )));
            }
        }
        let get = |k: &str| d.get_item(k).ok().flatten();
        let name: String = get("type")
            .ok_or_else(|| bad("the dict needs \"type\"".into()))?
            .extract()
            .map_err(|_| bad("\"type\" must be a string".into()))?;
        let frequency_hz: f64 = get("frequency_hz")
            .ok_or_else(|| bad("the dict needs \"frequency_hz\"".into()))?
            .extract()
            .map_err(|_| bad("\"frequency_hz\" must be a number".into()))?;
        let damping = get("damping")
            .map(|v| v.extract::<f64>())
            .transpose()
            .map_err(|_| bad("\"damping\" must be a number".into()))?;
        (name, frequency_hz, damping)
    } else {
        return Err(PyTypeError::new_err(
            "shaper must be \"TYPE:HZ[:DAMPING]\", a dict (type, frequency_hz, damping) or None",
        ));
    };
    let shaper: Shaper = name
        .trim()
        .parse()
        .map_err(|e: UnknownShaper| bad(e.to_string()))?;
    let spec = ShaperSpec {
        shaper,
        frequency_hz,
        damping: damping.unwrap_or(DEFAULT_DAMPING),
    };
    Impulses::for_spec(&spec).map_err(|e| bad(e.to_string()))?;
    Ok(Some(spec))
}

/// A job from points and keywords (defaults for keywords not given).
pub fn make_job(py: Python<'_>, points: &Bound<'_, PyAny>, args: &JobArgs) -> PyResult<PyJob> {
    let units = Units::parse(args.units.unwrap_or("mm"))?;
    let objective = parse_objective(py, args.objective.unwrap_or("min-max-jerk"))?;
    // Not given: the job's default placement.
    let knots = args.knots.map(|k| parse_knots(py, k)).transpose()?;
    let d = Limits::default();
    let limits = Limits {
        velocity: args.velocity.unwrap_or(d.velocity),
        acceleration: args.acceleration.unwrap_or(d.acceleration),
        jerk: args.jerk.unwrap_or(d.jerk),
        torque: args.torque.unwrap_or(d.torque),
        total_time: args.total_time.unwrap_or(d.total_time),
    };
    let pts = floats(points, "points")?;
    match pts.shape.as_slice() {
        [_, 3] => {}
        s => {
            return Err(invalid_job(
                py,
                "path.points",
                &format!("points must have shape (n, 3), got {}", shape_text(s)),
            ));
        }
    }
    let scale = units.scale();
    let rows: Vec<[f64; 3]> = pts.rows3().iter().map(|p| p.map(|x| x * scale)).collect();
    let mut builder = Job::builder();
    if let Some(m) = args.machine {
        builder = builder.machine(&m.get().machine);
    }
    // A robot given with a machine must be the machine's.
    if args.robot.is_some() || args.machine.is_none() {
        builder = builder.robot(robot_or_default(args.robot));
    }
    if let Some(k) = knots {
        builder = builder.knots(k);
    }
    if let Some(n) = args.knot_segments {
        builder = builder.knot_segments(n);
    }
    if let Some(mm) = args.max_deviation_mm {
        builder = builder.max_deviation_mm(mm);
    }
    if let Some(v) = args.shaper {
        builder = builder.shaper(parse_shaper(py, v)?);
    }
    let job = guard(py, || {
        builder
            .objective(objective)
            .limits(limits)
            .points_m(rows)
            .build()
            .map_err(|e| plan_error(py, e, units))
    })?;
    Ok(PyJob { job, units })
}

#[pymethods]
impl PyJob {
    #[new]
    #[pyo3(signature = (points, *, units = None, objective = None, knots = None, knot_segments = None,
        max_deviation_mm = None, total_time = None,
        velocity = None, acceleration = None, jerk = None, torque = None, robot = None,
        machine = None, shaper = None),
        text_signature = "(points, *, units='mm', objective='min-max-jerk', knots='fixed', knot_segments=None, \
            max_deviation_mm=None, total_time=5.0, \
            velocity=0.5, acceleration=1.2, jerk=5.0, torque=10.0, robot=None, machine=None, shaper=None)")]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        points: &Bound<'_, PyAny>,
        units: Option<&str>,
        objective: Option<&str>,
        knots: Option<&str>,
        knot_segments: Option<usize>,
        max_deviation_mm: Option<f64>,
        total_time: Option<f64>,
        velocity: Option<f64>,
        acceleration: Option<f64>,
        jerk: Option<f64>,
        torque: Option<f64>,
        robot: Option<Bound<'_, PyRobot>>,
        machine: Option<Bound<'_, PyMachine>>,
        shaper: Option<Bound<'_, PyAny>>,
    ) -> PyResult<Self> {
        let args = JobArgs {
            units,
            objective,
            knots,
            knot_segments,
            max_deviation_mm,
            total_time,
            velocity,
            acceleration,
            jerk,
            torque,
            robot: robot.as_ref(),
            machine: machine.as_ref(),
            shaper: shaper.as_ref(),
        };
        make_job(py, points, &args)
    }

    /// from_toml(path) -> Job
    ///
    /// Reads a job file of `triquint plan` (TOML: objective, [robot],
    /// [limits], [path] with units and points or a points file relative to
    /// the job file). Errors of the file raise JobFileError with its path and
    /// line; errors of its contents InvalidJobError or OutsideWorkspaceError
    /// (points in millimetres). With `machine`, the job is held to it as
    /// `triquint plan --machine` holds it (its [robot] must be the machine's,
    /// its limits within the ceilings, its points inside the travel).
    #[classmethod]
    #[pyo3(signature = (path, *, machine = None))]
    fn from_toml(
        _cls: &Bound<'_, PyType>,
        py: Python<'_>,
        path: PathBuf,
        machine: Option<Bound<'_, PyMachine>>,
    ) -> PyResult<Self> {
        let machine = machine.map(|m| m.get().machine.clone());
        let job = guard(py, || {
            Job::load_for(&path, machine.as_ref())
                .map(|(job, _)| job)
                .map_err(|e| plan_error(py, e, Units::Millimetres))
        })?;
        Ok(Self {
            job,
            units: Units::Millimetres,
        })
    }

    /// 'min-max-jerk' or 'min-time'.
    #[getter]
    fn objective(&self) -> &'static str {
        crate::objective_name(self.job.objective())
    }

    /// Via-points (n, 3), metres.
    #[getter]
    fn points<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_array(py, self.job.points_m(), true)
    }

    /// 'fixed' or 'free': how the planner places the knots.
    #[getter]
    fn knot_placement(&self) -> &'static str {
        match self.job.knot_placement() {
            KnotPlacement::Fixed => "fixed",
            KnotPlacement::Free => "free",
        }
    }

    /// The knots the planner interpolates (metres): the via-points, with
    /// points on the straight lines between them when there are fewer than five.
    #[getter]
    fn knots<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        rows_array(py, &self.job.knots_m(), true)
    }

    /// velocity, acceleration, jerk, torque, total_time (SI).
    #[getter]
    fn limits<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        crate::limits_dict(py, self.job.limits())
    }

    #[getter]
    fn robot(&self) -> PyRobot {
        PyRobot::from(self.job.robot())
    }

    fn __repr__(&self) -> String {
        let l = self.job.limits();
        format!(
            "Job({}, {} via-points, velocity={}, acceleration={}, jerk={}, torque={}, total_time={})",
            crate::objective_name(self.job.objective()),
            self.job.points_m().len(),
            l.velocity,
            l.acceleration,
            l.jerk,
            l.torque,
            l.total_time
        )
    }
}

/// A snapshot of a running search, given to `plan(..., progress=f)`:
/// `elapsed` (s), `stage` ('searching', 'limits-bind', 'min-time',
/// 'finishing'), `lp_solves` (linear programs so far) and `best_max_jerk`
/// (m/s³, the best of any start so far, or None).
#[pyclass(name = "Progress", module = "triquint", frozen, get_all)]
pub struct PyProgress {
    pub elapsed: f64,
    pub stage: &'static str,
    pub lp_solves: u64,
    pub best_max_jerk: Option<f64>,
}

#[pymethods]
impl PyProgress {
    fn __repr__(&self) -> String {
        format!(
            "Progress(elapsed={:.3}, stage={:?}, lp_solves={}, best_max_jerk={:?})",
            self.elapsed, self.stage, self.lp_solves, self.best_max_jerk
        )
    }
}

impl From<&Progress> for PyProgress {
    fn from(p: &Progress) -> Self {
        Self {
            elapsed: p.elapsed.as_secs_f64(),
            stage: match p.stage {
                Stage::Searching => "searching",
                Stage::LimitsBind => "limits-bind",
                Stage::MinTime => "min-time",
                _ => "finishing",
            },
            lp_solves: p.lp_solves,
            best_max_jerk: p.best_max_jerk,
        }
    }
}

/// plan(points, *, ...) -> Plan
///
/// Plans a globally min-max-jerk (or minimum-time) C3 piecewise-quintic
/// joint trajectory through Cartesian via-points under joint velocity
/// (m/s), acceleration (m/s²), jerk (m/s³), motor torque (N·m) and total
/// time (s) limits, every limit verified in continuous time.
///
/// `points` is an (n, 3) array-like of platform positions in millimetres
/// (`units="m"` for metres), or a `Job`; with a Job only `starts`, `seed`
/// and `progress` may be given (TypeError otherwise). `robot` is a
/// `Robot` (default: the paper's Table 1); `machine` a `Machine`, whose
/// robot, travel and ceilings the job is held to (a `robot` given with it
/// must be its robot). `starts` starting interval sets
/// of the global search (1 to 1000, as the CLI's `--starts`; ValueError
/// otherwise), random ones seeded by `seed`: the same job, starts and seed
/// give the same plan. `progress`, if given, is called about every
/// 25 ms with a `Progress`; returning False cancels (CancelledError), and
/// an exception it raises cancels and propagates.
///
/// The GIL is released while planning; Ctrl-C raises KeyboardInterrupt
/// within a second. Errors: InvalidJobError (field), OutsideWorkspaceError
/// (index, point), InfeasibleError (limit, reached, shortest_total_time),
/// SolverError.
#[pyfunction]
#[pyo3(signature = (points, *, units = None, objective = None, knots = None, knot_segments = None,
        max_deviation_mm = None, total_time = None,
    velocity = None, acceleration = None, jerk = None, torque = None, robot = None,
    machine = None, shaper = None, starts = 8, seed = 1, progress = None),
    text_signature = "(points, *, units='mm', objective='min-max-jerk', knots='fixed', knot_segments=None, \
            max_deviation_mm=None, total_time=5.0, \
        velocity=0.5, acceleration=1.2, jerk=5.0, torque=10.0, robot=None, machine=None, \
        shaper=None, starts=8, seed=1, progress=None)")]
#[allow(clippy::too_many_arguments)]
pub fn plan(
    py: Python<'_>,
    points: &Bound<'_, PyAny>,
    units: Option<&str>,
    objective: Option<&str>,
    knots: Option<&str>,
    knot_segments: Option<usize>,
    max_deviation_mm: Option<f64>,
    total_time: Option<f64>,
    velocity: Option<f64>,
    acceleration: Option<f64>,
    jerk: Option<f64>,
    torque: Option<f64>,
    robot: Option<Bound<'_, PyRobot>>,
    machine: Option<Bound<'_, PyMachine>>,
    shaper: Option<Bound<'_, PyAny>>,
    starts: usize,
    seed: u64,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<PyPlan> {
    let args = JobArgs {
        units,
        objective,
        knots,
        knot_segments,
        max_deviation_mm,
        total_time,
        velocity,
        acceleration,
        jerk,
        torque,
        robot: robot.as_ref(),
        machine: machine.as_ref(),
        shaper: shaper.as_ref(),
    };
    if !(1..=triquint_planner::MAX_STARTS).contains(&starts) {
        return Err(PyValueError::new_err(format!(
            "starts {starts}: must be a whole number 1 to {}",
            triquint_planner::MAX_STARTS
        )));
    }
    if let Some(p) = &progress
        && !p.is_callable()
    {
        return Err(PyTypeError::new_err("progress must be a callable or None"));
    }
    let made;
    let job: &PyJob = match points.cast::<PyJob>() {
        Ok(j) => {
            let given = args.given();
            if !given.is_empty() {
                return Err(PyTypeError::new_err(format!(
                    "plan() with a Job takes only starts, seed and progress; got {} \
                     (set it in the Job)",
                    given.join(", ")
                )));
            }
            j.get()
        }
        Err(_) => {
            made = make_job(py, points, &args)?;
            &made
        }
    };
    let opts = Options {
        starts,
        seed,
        ..Options::default()
    };
    run_plan(py, job, &opts, progress.map(Bound::unbind))
}

/// Plans with the GIL released; the observer re-attaches every 25 ms to
/// run Python's signal handlers (Ctrl-C) and the progress callable.
fn run_plan(
    py: Python<'_>,
    job: &PyJob,
    opts: &Options,
    progress: Option<Py<PyAny>>,
) -> PyResult<PyPlan> {
    let mut pending: Option<PyErr> = None;
    let mut cancelled = false;
    let inner = &job.job;
    let result = py.detach(|| {
        let mut observer = |p: &Progress| -> Control {
            if pending.is_some() || cancelled {
                return Control::Cancel;
            }
            Python::attach(|py| {
                if let Err(e) = py.check_signals() {
                    pending = Some(e);
                    return Control::Cancel;
                }
                if let Some(cb) = &progress {
                    match cb.call1(py, (PyProgress::from(p),)) {
                        Err(e) => {
                            pending = Some(e);
                            return Control::Cancel;
                        }
                        Ok(v) => {
                            if v.bind(py).is(pyo3::types::PyBool::new(py, false)) {
                                cancelled = true;
                                return Control::Cancel;
                            }
                        }
                    }
                }
                Control::Continue
            })
        };
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            plan_with(inner, opts, &mut observer)
        }))
    });
    if let Some(e) = pending {
        return Err(e);
    }
    match result {
        Err(payload) => Err(internal_error(py, payload.as_ref())),
        Ok(Ok(plan)) => Ok(PyPlan { plan }),
        Ok(Err(e)) => Err(plan_error(py, e, job.units)),
    }
}
