//! A planning job: what to plan, validated when it is built.
//!
//! ```
//! use triquint_planner::{Job, Objective};
//!
//! let job = Job::builder()
//!     .objective(Objective::MinTime)
//!     .points_mm([[-90.0, 90.0, 680.0], [-86.0, 83.66, 597.66]])
//!     .build()?;
//! assert_eq!(job.points_m().len(), 2);
//! # Ok::<(), triquint_planner::PlanError>(())
//! ```

use nalgebra::Vector3;
use triquint_shared::kinematics::Pose;
use triquint_shared::machine::{Ceilings, Machine};
use triquint_shared::plan::Objective;
use triquint_shared::plan::shaping::ShaperSpec;
use triquint_shared::protocol::segment::MAX_DURATION_US;
use triquint_shared::{Limits, Model, Robot, Travel};

use crate::error::{PlanError, PointKind};
use crate::holding::check_holding;
use triquint_shared::readable::readable;

/// Most via-points a job may have: the search's time grows about linearly
/// with the points (minutes at 1 000 on two cores) and its memory linearly
/// too; a longer path is split into jobs. Refused at once, before any work.
pub const MAX_POINTS: usize = 2_000;
/// Range of every motion limit (SI units): what the drives' f32 configuration
/// holds with room to spare.
pub const LIMIT_RANGE: (f64, f64) = (1e-6, 1e6);
/// Longest segment the wire carries (s).
pub const MAX_SEGMENT_S: f64 = MAX_DURATION_US as f64 * 1e-6;
/// Shortest interval the planner uses (s).
pub const MIN_SEGMENT_S: f64 = 1e-3;
/// Range of `knots.segments`, the segment count of a free-knot move: the
/// fewest a C3 quintic at rest at both ends with a free jerk takes (four
/// knots), and more than any time-optimal shape needs (its phases take 7,
/// 11 or 15).
pub const KNOT_SEGMENTS: (usize, usize) = (3, 64);
/// Range of `path.max_deviation_mm` (mm): down to a micrometre, which the
/// certificate's floating point still resolves.
pub const MAX_DEVIATION_MM: (f64, f64) = (1e-3, 1e3);
/// Where a job does not say `knots`, does a point-to-point min-time move
/// get free knots? The one switch of the default; `move-to` follows it.
/// A free plan that would not stream or check falls back to the fixed
/// knots (docs/planner.md, Free knots).
pub const FREE_KNOTS_BY_DEFAULT: bool = true;

/// How the planner places the knots between the via-points.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum KnotPlacement {
    /// The via-points, with straight-line points at fixed fractions when
    /// there are fewer than five ([`Job::knots_m`]); the planner chooses the
    /// times and the knots' velocities and accelerations.
    #[default]
    Fixed,
    /// Min-time between two via-points: the planner also chooses the
    /// interior knots' number, times and joint positions, on the straight
    /// line in joint space (the path leaves the Cartesian segment; the plan
    /// reports by how much). Min-max-jerk (any via-points): a knot added
    /// inside every segment, its time and joint position chosen to lower
    /// the max jerk, kept only where it does.
    Free,
}

/// A valid job: reachable via-points (and knots), limits in range.
/// Build one with [`Job::builder`] or read one with `Job::from_toml`.
#[derive(Clone, Debug, PartialEq)]
pub struct Job {
    objective: Objective,
    robot: Robot,
    limits: Limits,
    travel: Travel,
    ceilings: Ceilings,
    points_m: Vec<[f64; 3]>,
    knots: KnotPlacement,
    /// What the job asked (None: the default), so that a builder made from
    /// the job follows the default again where the job did.
    knots_asked: Option<KnotPlacement>,
    knot_segments: Option<usize>,
    max_deviation_m: Option<f64>,
    shaper: Option<ShaperSpec>,
}

/// Builds a [`Job`]; [`JobBuilder::build`] validates it. Defaults: min-max
/// jerk, the paper's robot (Table 1), limits (Table 3), and the default
/// machine's travel and ceilings ([`Machine::default`]), no points.
#[derive(Clone, Debug, Default)]
pub struct JobBuilder {
    objective: Objective,
    robot: Option<Robot>,
    limits: Limits,
    travel: Travel,
    ceilings: Ceilings,
    /// The machine's robot, which a robot given with the job must equal.
    machine_robot: Option<Robot>,
    points_m: Vec<[f64; 3]>,
    /// None: the default ([`FREE_KNOTS_BY_DEFAULT`]).
    knots: Option<KnotPlacement>,
    knot_segments: Option<usize>,
    max_deviation_mm: Option<f64>,
    shaper: Option<ShaperSpec>,
}

impl JobBuilder {
    pub fn objective(mut self, objective: Objective) -> Self {
        self.objective = objective;
        self
    }
    pub fn robot(mut self, robot: Robot) -> Self {
        self.robot = Some(robot);
        self
    }
    /// Plans for `machine`: its robot (a robot given with the job must
    /// equal it), its travel and its ceilings, which the limits may not exceed.
    pub fn machine(mut self, machine: &Machine) -> Self {
        self.machine_robot = Some(machine.robot.clone());
        self.travel = machine.travel();
        self.ceilings = machine.effective_ceilings();
        self
    }
    /// The sliders' travel: every via-point and knot, and the whole motion
    /// between them, stays inside it.
    pub fn travel(mut self, travel: Travel) -> Self {
        self.travel = travel;
        self
    }
    pub fn limits(mut self, limits: Limits) -> Self {
        self.limits = limits;
        self
    }
    /// The upper bound on the total time (s).
    pub fn total_time(mut self, seconds: f64) -> Self {
        self.limits.total_time = seconds;
        self
    }
    /// How the knots are placed. By default fixed, or free for a
    /// point-to-point min-time move when [`FREE_KNOTS_BY_DEFAULT`] is set.
    pub fn knots(mut self, knots: KnotPlacement) -> Self {
        self.knots = Some(knots);
        self
    }
    /// The segment count of a free-knot move (`knots.segments`), in
    /// [`KNOT_SEGMENTS`]; automatic (7, 11 or 15 by which limits bind) by
    /// default.
    pub fn knot_segments(mut self, segments: usize) -> Self {
        self.knot_segments = Some(segments);
        self
    }
    /// The most the platform may leave the straight segment between two
    /// via-points (mm, `path.max_deviation_mm`), which the planner meets
    /// and `check_deviation` proves.
    pub fn max_deviation_mm(mut self, mm: f64) -> Self {
        self.max_deviation_mm = Some(mm);
        self
    }
    /// The input shaper the plan is convolved with (none by default).
    pub fn shaper(mut self, shaper: Option<ShaperSpec>) -> Self {
        self.shaper = shaper;
        self
    }
    /// Replaces the via-points, in metres.
    pub fn points_m(mut self, points: impl IntoIterator<Item = [f64; 3]>) -> Self {
        self.points_m = points.into_iter().collect();
        self
    }
    /// Replaces the via-points, in millimetres.
    pub fn points_mm(self, points: impl IntoIterator<Item = [f64; 3]>) -> Self {
        self.points_m(points.into_iter().map(|p| p.map(|x| x * 1e-3)))
    }

    /// Validates the job: limits finite and in [`LIMIT_RANGE`], total time
    /// at most [`MAX_SEGMENT_S`] per segment, at least two via-points, each
    /// finite, reachable and apart from the one before, and every knot added
    /// between them reachable.
    pub fn build(self) -> Result<Job, PlanError> {
        let robot = match (self.robot, self.machine_robot) {
            (Some(job), Some(machine)) => {
                if let Some((key, j, m)) = job.first_difference(&machine) {
                    return Err(PlanError::OtherMachine {
                        key,
                        job: j,
                        machine: m,
                    });
                }
                job
            }
            (Some(r), None) | (None, Some(r)) => r,
            (None, None) => Robot::default(),
        };
        robot.validate().map_err(|e| {
            let triquint_shared::params::ParamError::Invalid { name, .. } = e;
            PlanError::invalid(&format!("robot.{name}"), e.to_string())
        })?;
        let l = &self.limits;
        for (name, value) in l.named() {
            let (lo, hi) = LIMIT_RANGE;
            if !(value.is_finite() && (lo..=hi).contains(&value)) {
                return Err(PlanError::invalid(
                    &format!("limits.{name}"),
                    out_of_range(value, "", lo, hi),
                ));
            }
        }
        for ((name, value), (_, ceiling)) in l.named().into_iter().zip(self.ceilings.named()) {
            // NaN ceilings are refused by the machine's validation.
            if value > ceiling {
                return Err(PlanError::AboveCeiling {
                    limit: name,
                    value,
                    ceiling,
                });
            }
        }
        self.travel
            .validate()
            .map_err(|e| PlanError::invalid(e.name, e.to_string()))?;
        let pts = &self.points_m;
        if pts.len() < 2 {
            return Err(PlanError::invalid(
                "path.points",
                format!("needs at least 2 points, got {}", pts.len()),
            ));
        }
        if pts.len() > MAX_POINTS {
            return Err(PlanError::invalid(
                "path.points",
                format!(
                    "{} points: the planner takes at most {MAX_POINTS} (split the path into jobs)",
                    pts.len()
                ),
            ));
        }
        let model = robot.model::<f64>();
        for (i, p) in pts.iter().enumerate() {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(PlanError::invalid(
                    "path.points",
                    format!(
                        "point {} ({}, {}, {}) is not finite",
                        i + 1,
                        readable(p[0]),
                        readable(p[1]),
                        readable(p[2])
                    ),
                ));
            }
            reachable(&model, &self.travel, *p, PointKind::ViaPoint, i)?;
            if i > 0 && (Vector3::from(*p) - Vector3::from(pts[i - 1])).norm() < 1e-9 {
                return Err(PlanError::invalid(
                    "path.points",
                    format!(
                        "point {} repeats point {i}: consecutive via-points must differ",
                        i + 1
                    ),
                ));
            }
        }
        if let Some(spec) = &self.shaper {
            crate::shaper::Impulses::for_spec(spec)?;
        }
        check_holding(&model, pts, l.torque)?;
        let point_to_point = self.objective == Objective::MinTime && pts.len() == 2;
        let knots = match self.knots {
            Some(k) => k,
            None if FREE_KNOTS_BY_DEFAULT && point_to_point => KnotPlacement::Free,
            None => KnotPlacement::Fixed,
        };
        let min_time = self.objective == Objective::MinTime;
        if knots == KnotPlacement::Free && min_time && !point_to_point {
            return Err(PlanError::invalid(
                "knots",
                "free knots for min-time need exactly 2 via-points (min-max-jerk takes any)",
            ));
        }
        if let Some(n) = self.knot_segments {
            let (lo, hi) = KNOT_SEGMENTS;
            if !min_time {
                return Err(PlanError::invalid(
                    "knots.segments",
                    "a segment count needs objective = \"min-time\" (min-max-jerk adds a knot a segment)",
                ));
            }
            if knots != KnotPlacement::Free {
                return Err(PlanError::invalid(
                    "knots.segments",
                    "a segment count needs placement = \"free\" (fixed knots are the via-points)",
                ));
            }
            if !(lo..=hi).contains(&n) {
                return Err(PlanError::invalid(
                    "knots.segments",
                    format!("{n} is outside {lo}..{hi}"),
                ));
            }
        }
        if let Some(mm) = self.max_deviation_mm {
            let (lo, hi) = MAX_DEVIATION_MM;
            if !(mm.is_finite() && (lo..=hi).contains(&mm)) {
                return Err(PlanError::invalid(
                    "path.max_deviation_mm",
                    out_of_range(mm, " mm", lo, hi),
                ));
            }
        }
        let knot_pts = knot_points(pts);
        for (i, k) in knot_pts.iter().enumerate() {
            reachable(&model, &self.travel, *k, PointKind::Knot, i)?;
        }
        let t = l.total_time;
        let segments = (knot_pts.len() - 1) as f64;
        let longest = MAX_SEGMENT_S * segments;
        if !(t.is_finite() && t >= MIN_SEGMENT_S * segments && t <= longest) {
            return Err(PlanError::invalid(
                "limits.total_time",
                format!(
                    "{} ({} segments of {} ms to {} s)",
                    out_of_range(t, " s", MIN_SEGMENT_S * segments, longest),
                    segments,
                    readable(MIN_SEGMENT_S * 1e3),
                    readable(MAX_SEGMENT_S)
                ),
            ));
        }
        Ok(Job {
            objective: self.objective,
            robot,
            limits: self.limits,
            travel: self.travel,
            ceilings: self.ceilings,
            points_m: self.points_m,
            knots,
            knots_asked: self.knots,
            knot_segments: self.knot_segments,
            max_deviation_m: self.max_deviation_mm.map(|mm| mm * 1e-3),
            shaper: self.shaper,
        })
    }
}

/// `p` has a pose, and its sliders are inside the travel.
fn reachable(
    model: &Model<f64>,
    travel: &Travel,
    p: [f64; 3],
    point: PointKind,
    index: usize,
) -> Result<(), PlanError> {
    let pose =
        Pose::from_cartesian(model, Vector3::from(p)).map_err(|e| PlanError::OutsideWorkspace {
            point,
            index,
            position_m: p,
            reason: e.to_string(),
        })?;
    match travel.outside(&pose.q.into()) {
        None => Ok(()),
        Some(o) => Err(PlanError::OutsideTravel {
            point,
            index,
            position_m: p,
            axis: o.axis,
            joint_m: o.position_m,
            limit_m: o.limit_m,
        }),
    }
}

impl Job {
    pub fn builder() -> JobBuilder {
        JobBuilder::default()
    }
    /// A builder holding this job, to change and build again.
    pub fn to_builder(&self) -> JobBuilder {
        JobBuilder {
            objective: self.objective,
            robot: Some(self.robot.clone()),
            limits: self.limits.clone(),
            travel: self.travel.clone(),
            ceilings: self.ceilings.clone(),
            machine_robot: None,
            points_m: self.points_m.clone(),
            knots: self.knots_asked,
            knot_segments: self.knot_segments,
            max_deviation_mm: self.max_deviation_m.map(|m| m * 1e3),
            shaper: self.shaper,
        }
    }
    pub fn objective(&self) -> Objective {
        self.objective
    }
    pub fn robot(&self) -> &Robot {
        &self.robot
    }
    pub fn limits(&self) -> &Limits {
        &self.limits
    }
    pub fn travel(&self) -> &Travel {
        &self.travel
    }
    /// What the limits were held to.
    pub fn ceilings(&self) -> &Ceilings {
        &self.ceilings
    }
    /// Via-points in metres.
    pub fn points_m(&self) -> &[[f64; 3]] {
        &self.points_m
    }
    /// How the knots are placed.
    pub fn knot_placement(&self) -> KnotPlacement {
        self.knots
    }
    /// The segment count asked of a free-knot move, if any.
    pub fn knot_segments(&self) -> Option<usize> {
        self.knot_segments
    }
    /// The bound on the platform's distance from the straight segments
    /// between the via-points (m), if any.
    pub fn max_deviation_m(&self) -> Option<f64> {
        self.max_deviation_m
    }
    /// The input shaper, if the plan is to be shaped.
    pub fn shaper(&self) -> Option<&ShaperSpec> {
        self.shaper.as_ref()
    }
    /// The fixed knots the planner interpolates: the via-points, with points on
    /// the straight lines between them when there are fewer than five.
    pub fn knots_m(&self) -> Vec<[f64; 3]> {
        knot_points(&self.points_m)
    }
}

/// Knots of a path: the via-points, with straight-line points added between
/// them when there are fewer than five (a C3 quintic spline at rest at both
/// ends needs n ≥ 4 knots, and one more leaves the jerk a free variable).
pub(crate) fn knot_points(points: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let n = points.len();
    if !(2..5).contains(&n) {
        return points.to_vec();
    }
    let pieces = 4usize.div_ceil(n - 1);
    let mut out = Vec::new();
    for w in points.windows(2) {
        let (a, b) = (Vector3::from(w[0]), Vector3::from(w[1]));
        for i in 0..pieces {
            out.push((a + (b - a) * (i as f64 / pieces as f64)).into());
        }
    }
    out.push(points[n - 1]);
    out
}

/// "-5 is outside 1e-6..1e6", or "NaN is not a finite number (1e-6..1e6)":
/// a finite number out of range is not "not a number".
fn out_of_range(value: f64, unit: &str, lo: f64, hi: f64) -> String {
    let (v, lo, hi) = (readable(value), readable(lo), readable(hi));
    if value.is_finite() {
        format!("{v}{unit} is outside {lo}..{hi}{unit}")
    } else {
        format!("{v} is not a finite number ({lo}..{hi}{unit})")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(b: JobBuilder) -> PlanError {
        b.build().unwrap_err()
    }

    #[test]
    fn a_limit_out_of_range_is_outside_it_not_not_a_number() {
        let two = [[-90.0, 90.0, 680.0], [-90.0, 90.0, 660.0]];
        let mut limits = Limits {
            jerk: -5.0,
            ..Limits::default()
        };
        let e = err(Job::builder().points_mm(two).limits(limits.clone()));
        assert_eq!(
            e.to_string(),
            "limits.jerk: -5 is outside 1e-6..1e6",
            "{e:?}"
        );
        limits.jerk = f64::NAN;
        let e = err(Job::builder().points_mm(two).limits(limits));
        assert_eq!(
            e.to_string(),
            "limits.jerk: NaN is not a finite number (1e-6..1e6)"
        );
        let e = err(Job::builder().points_mm(two).total_time(1e4));
        assert!(
            e.to_string()
                .starts_with("limits.total_time: 10000 s is outside "),
            "{e}"
        );
    }

    #[test]
    fn a_point_outside_the_travel_names_the_point_and_the_slider() {
        // Was planned: z 100 mm puts every slider far below any guideway.
        let e = err(Job::builder().points_mm([
            [0.0, 0.0, 600.0],
            [0.0, 0.0, 500.0],
            [0.0, 0.0, 100.0],
        ]));
        assert!(
            matches!(
                e,
                PlanError::OutsideTravel {
                    point: PointKind::ViaPoint,
                    index: 2,
                    axis: 0,
                    limit_m: 0.05,
                    ..
                }
            ),
            "{e:?}"
        );
        assert!(
            e.to_string()
                .starts_with("point 3 (0, 0, 100) mm is outside the travel: slider 1 at -286.78"),
            "{e}"
        );
        // A narrower travel of the machine's own refuses what the default takes.
        let job = Job::builder().points_mm([[0.0, 0.0, 600.0], [0.0, 0.0, 620.0]]);
        assert!(job.clone().build().is_ok());
        let travel = Travel {
            max: [0.415, 0.22, 0.415],
            ..Travel::default()
        };
        let e = err(job.clone().travel(travel));
        assert!(
            matches!(e, PlanError::OutsideTravel { axis: 1, .. }),
            "{e:?}"
        );
        let bad = Travel {
            min: [0.3; 3],
            max: [0.2; 3],
        };
        assert!(matches!(err(job.travel(bad)), PlanError::InvalidJob { .. }));
    }

    #[test]
    fn errors_name_the_field_or_the_point() {
        let ok = Job::builder().points_mm([[0.0, 0.0, 600.0], [10.0, 0.0, 600.0]]);
        assert!(ok.clone().build().is_ok());
        let e = err(ok
            .clone()
            .points_mm([[0.0, 0.0, 600.0], [900.0, 0.0, 600.0]]));
        assert!(
            matches!(
                e,
                PlanError::OutsideWorkspace {
                    point: PointKind::ViaPoint,
                    index: 1,
                    ..
                }
            ),
            "{e:?}"
        );
        assert!(e.to_string().starts_with("point 2 (900, 0, 600) mm"), "{e}");
        let e = err(ok.clone().total_time(1e300));
        assert!(matches!(&e, PlanError::InvalidJob { field, .. } if field == "limits.total_time"));
        assert!(e.to_string().contains("1e300"), "{e}");
        assert!(e.to_string().len() < 120, "{e}");
        let mut l = Limits {
            jerk: -1.0,
            ..Limits::default()
        };
        let e = err(ok.clone().limits(l.clone()));
        assert!(matches!(&e, PlanError::InvalidJob { field, .. } if field == "limits.jerk"));
        l.jerk = f64::NAN;
        assert!(err(ok.clone().limits(l)).to_string().contains("NaN"));
        let e = err(ok.clone().points_mm([[0.0, 0.0, 600.0]]));
        assert!(e.to_string().contains("at least 2"));
        let e = err(ok.clone().points_mm([[0.0, 0.0, 600.0], [0.0, 0.0, 600.0]]));
        assert!(e.to_string().contains("repeats"));
        let e = err(ok.points_m([[0.0, 0.0, f64::NAN], [0.0, 0.0, 0.6]]));
        assert!(e.to_string().contains("not finite"));
    }
}
