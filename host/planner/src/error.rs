//! The one error type of the planner: every way a job can fail to plan, with
//! the data a program needs to act on it (which field, which point, which
//! limit, the shortest feasible time), and a one-line message for people.

use triquint_shared::plan::shaping::ShaperSpec;
use triquint_shared::readable::readable;

/// A limit of a job (`[limits]` in a job file).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum Limit {
    /// Joint velocity (m/s).
    Velocity,
    /// Joint acceleration (m/s²).
    Acceleration,
    /// Joint jerk (m/s³).
    Jerk,
    /// Motor torque (N·m).
    Torque,
    /// Upper bound on the total time (s).
    TotalTime,
}

impl Limit {
    /// The key of the limit in a job file.
    pub fn name(self) -> &'static str {
        match self {
            Limit::Velocity => "velocity",
            Limit::Acceleration => "acceleration",
            Limit::Jerk => "jerk",
            Limit::Torque => "torque",
            Limit::TotalTime => "total_time",
        }
    }

    /// The SI unit of the limit.
    pub fn unit(self) -> &'static str {
        match self {
            Limit::Velocity => "m/s",
            Limit::Acceleration => "m/s²",
            Limit::Jerk => "m/s³",
            Limit::Torque => "N·m",
            Limit::TotalTime => "s",
        }
    }
}

/// Which kind of point an error is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum PointKind {
    /// A via-point of the job.
    ViaPoint,
    /// A knot the planner adds on the straight line between two via-points
    /// (jobs of fewer than five via-points).
    Knot,
}

/// Why a plan was cancelled.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
#[non_exhaustive]
pub enum CancelReason {
    /// The observer asked for it.
    Observer,
    /// The time budget of `Options::time_budget` ran out.
    TimeBudget,
}

/// Why a job did not plan. Indices are 0-based; messages count from 1.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PlanError {
    /// The job is malformed: `field` names it as in a job file
    /// (`limits.jerk`, `path.points`, `robot.lead`, `path.file`).
    #[error("{field}: {reason}")]
    InvalidJob { field: String, reason: String },
    /// A job file could not be read or parsed; `line` is 1-based.
    #[error("{origin}{}: {reason}", line.map(|l| format!(":{l}")).unwrap_or_default())]
    JobFile {
        origin: String,
        line: Option<usize>,
        reason: String,
    },
    /// The job's `[robot]` differs from the machine's: the first
    /// parameter that does, in the job and in the machine.
    #[error("robot.{key} is {} in the job and {} in the machine file: the job is for another machine", readable(*job), readable(*machine))]
    OtherMachine {
        key: &'static str,
        job: f64,
        machine: f64,
    },
    /// A limit above the machine's ceiling for it.
    #[error("limits.{limit} = {} is above the machine's ceiling {}", readable(*value), readable(*ceiling))]
    AboveCeiling {
        limit: &'static str,
        value: f64,
        ceiling: f64,
    },
    /// A via-point, or a knot between two via-points, that the robot cannot reach.
    #[error(
        "{} {} ({}, {}, {}) mm is outside the workspace: {reason}",
        match point { PointKind::ViaPoint => "point", PointKind::Knot => "knot" },
        index + 1,
        readable(position_m[0] * 1e3),
        readable(position_m[1] * 1e3),
        readable(position_m[2] * 1e3)
    )]
    OutsideWorkspace {
        point: PointKind,
        index: usize,
        position_m: [f64; 3],
        reason: String,
    },
    /// A via-point, or a knot between two via-points, whose slider `axis`
    /// (0-based) would stand at `joint_m`, beyond its travel limit `limit_m`.
    #[error(
        "{} {} ({}, {}, {}) mm is outside the travel: slider {} at {} mm, limit {} mm",
        match point { PointKind::ViaPoint => "point", PointKind::Knot => "knot" },
        index + 1,
        readable(position_m[0] * 1e3),
        readable(position_m[1] * 1e3),
        readable(position_m[2] * 1e3),
        axis + 1,
        readable(joint_m * 1e3),
        readable(limit_m * 1e3)
    )]
    OutsideTravel {
        point: PointKind,
        index: usize,
        position_m: [f64; 3],
        axis: usize,
        joint_m: f64,
        limit_m: f64,
    },
    /// Every point is inside the travel, but no plan at these knots keeps
    /// the sliders inside it (the planner keeps them inside between knots
    /// as it keeps every other limit): its closest plan leaves it in
    /// segment `segment` (0-based), where slider `axis` reaches `joint_m`,
    /// beyond `limit_m`.
    #[error(
        "infeasible: slider {} reaches {} mm between knots {} and {}, beyond its travel limit {} mm; move the points away from the travel's end",
        axis + 1,
        readable(joint_m * 1e3),
        segment + 1,
        segment + 2,
        readable(limit_m * 1e3)
    )]
    LeavesTravel {
        segment: usize,
        axis: usize,
        joint_m: f64,
        limit_m: f64,
    },
    /// The torque limit is below the torque that holds the platform still
    /// at via-point `index` (0-based; the first or the last, where every
    /// plan is at rest): motor `axis` (0-based) needs `holding_nm` there
    /// against gravity alone, whatever the timing.
    #[error(
        "infeasible: the torque limit {} N·m is below the {} N·m that motor {} needs to hold the platform still at point {}; limits.torque must be at least that",
        readable(*limit_nm),
        readable(*holding_nm),
        axis + 1,
        index + 1
    )]
    BelowHoldingTorque {
        index: usize,
        axis: usize,
        holding_nm: f64,
        limit_nm: f64,
    },
    /// A valid job that no plan satisfies: `limit` binds. `reached` is the
    /// binding quantity's value (above `limit_value`) in the planner's
    /// closest plan: when the total time is shorter than
    /// `shortest_total_time`, the shortest plan time-scaled to it;
    /// `shortest_total_time` is the shortest total time at which every
    /// limit holds, when there is one within reach.
    #[error("{}", infeasible_message(*limit, *limit_value, *reached, *shortest_total_time))]
    Infeasible {
        limit: Limit,
        limit_value: f64,
        reached: f64,
        shortest_total_time: Option<f64>,
    },
    /// The plan meets every limit but would not stream to the default
    /// drives (docs/protocol.md, "Streamability"): segments `first` to
    /// `last` (0-based, a queue's worth less one) last `run_s` together,
    /// less than the `need_s` (look-ahead plus refill delay) that drives
    /// queueing `capacity` segments must hold ahead. Fewer, longer
    /// segments (fewer points, or a longer total time) stream. `shaper`:
    /// the plan is the job's shaped one, which has a knot per impulse for
    /// each of the unshaped plan's.
    #[error(
        "unstreamable: {}segments {}–{} last {} s together, less than the {} s drives queueing {capacity} segments must hold ahead (docs/protocol.md, Streamability); {}",
        shaped_by(shaper),
        first + 1,
        last + 1,
        readable(*run_s),
        readable(*need_s),
        unstreamable_advice(shaper)
    )]
    Unstreamable {
        first: usize,
        last: usize,
        run_s: f64,
        need_s: f64,
        capacity: usize,
        shaper: Option<ShaperSpec>,
    },
    /// The platform would leave the straight segments between the
    /// via-points by more than `path.max_deviation_mm` (`limit_m`): the
    /// closest plan's certified bound `bound_m`, and its largest sampled
    /// distance `reached_m`, at plan time `at_s` (stats::PathDeviation).
    #[error(
        "path.max_deviation_mm: the closest plan leaves the straight path by up to {} mm ({} mm sampled at {} s), above the bound {} mm",
        readable(bound_m * 1e3),
        readable(reached_m * 1e3),
        readable(*at_s),
        readable(limit_m * 1e3)
    )]
    Deviation {
        limit_m: f64,
        bound_m: f64,
        reached_m: f64,
        at_s: f64,
    },
    /// Planning stopped before it finished.
    #[error("{}", match reason {
        CancelReason::Observer => "planning cancelled",
        CancelReason::TimeBudget => "planning ran out of its time budget",
    })]
    Cancelled { reason: CancelReason },
    /// The numerical solver failed on a job it should have solved: a bug or
    /// a numerically extreme job, worth a report.
    #[error("solver failure: {0}")]
    Solver(String),
}

fn infeasible_message(limit: Limit, value: f64, reached: f64, shortest: Option<f64>) -> String {
    let (name, unit) = (limit.name(), limit.unit());
    let mut m = match limit {
        Limit::TotalTime => format!("infeasible: total_time {} s is too short", readable(value)),
        _ => format!(
            "infeasible: the {name} limit {} {unit} binds (reached {} {unit})",
            readable(value),
            readable(reached)
        ),
    };
    match shortest {
        Some(t) => {
            m += &format!(
                "; the shortest total time that meets every limit is {} s",
                readable(t)
            )
        }
        None => m += "; no total time meets every limit",
    }
    m
}

impl PlanError {
    pub(crate) fn invalid(field: &str, reason: impl Into<String>) -> Self {
        PlanError::InvalidJob {
            field: field.to_string(),
            reason: reason.into(),
        }
    }
}

/// "shaped by EI at 25.6 Hz, ζ 0.062: " for a shaped plan.
fn shaped_by(shaper: &Option<ShaperSpec>) -> String {
    shaper.map_or(String::new(), |s| {
        format!(
            "shaped by {} at {} Hz, ζ {}: ",
            s.shaper,
            readable(s.frequency_hz),
            readable(s.damping)
        )
    })
}

/// What makes a plan's segments longer (docs/input-shaping.md).
fn unstreamable_advice(shaper: &Option<ShaperSpec>) -> &'static str {
    match shaper {
        None => "use fewer points or a longer total time",
        Some(_) => {
            "shaping puts a knot per impulse beside each of the plan's: use fewer points, gentler limits or a shaper with fewer impulses (docs/input-shaping.md)"
        }
    }
}
