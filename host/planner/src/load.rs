//! The one plan loader: what every tool reading a plan file relies on,
//! beyond what serde checks. Every plan the planner writes passes it.

use nalgebra::Vector3;
use triquint_shared::kinematics::Pose;
use triquint_shared::plan::{
    MAX_SEGMENTS, PLAN_FORMAT, PLAN_FORMAT_1, PLAN_FORMAT_2, PLAN_FORMAT_BOUNDED,
    PLAN_FORMAT_FREE_KNOTS, PLAN_FORMAT_SHAPED, Plan,
};
use triquint_shared::protocol::segment::MAX_DURATION_US;
use triquint_shared::readable::readable;

use crate::job::{LIMIT_RANGE, MAX_DEVIATION_MM};
use crate::shaper::Impulses;

/// Why a text is not a usable plan.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LoadError {
    /// Not plan JSON: the parser's message, with line and column.
    #[error("{0}")]
    Json(String),
    /// Another format or version than this library reads.
    #[error(
        "format is `{found}`, expected `{PLAN_FORMAT}` (or `{PLAN_FORMAT_FREE_KNOTS}`, `{PLAN_FORMAT_SHAPED}`, `{PLAN_FORMAT_BOUNDED}`, `{PLAN_FORMAT_2}`, `{PLAN_FORMAT_1}`)"
    )]
    Format { found: String },
    /// Plan JSON whose contents do not fit together.
    #[error("{0}")]
    Invalid(String),
}

/// Parses and validates plan JSON.
///
/// ```
/// let e = triquint_planner::files::parse_plan("{\"format\": 3}").unwrap_err();
/// assert!(e.to_string().contains("line 1"));
/// ```
pub fn parse_plan(text: &str) -> Result<Plan, LoadError> {
    // The format tag first, so another version is named as such.
    if let Ok(v) = serde_json::from_str::<serde_json::Value>(text)
        && let Some(f) = v.get("format").and_then(|f| f.as_str())
    {
        // What each format records of the machine; an earlier format
        // gets the default machine's values for what it lacks.
        let records: &[&str] = match f {
            PLAN_FORMAT | PLAN_FORMAT_FREE_KNOTS => &["travel", "ceilings"],
            PLAN_FORMAT_SHAPED => &["travel", "ceilings", "shaping"],
            PLAN_FORMAT_BOUNDED => &["travel", "ceilings", "max_deviation_m"],
            PLAN_FORMAT_2 => &["travel"],
            PLAN_FORMAT_1 => &[],
            _ => return Err(LoadError::Format { found: one_line(f) }),
        };
        if let Some(missing) = records.iter().find(|k| v.get(**k).is_none()) {
            return Err(LoadError::Invalid(format!(
                "a `{f}` plan records its `{missing}`; this one has none"
            )));
        }
    }
    let plan: Plan =
        serde_json::from_str(text).map_err(|e| LoadError::Json(one_line(&e.to_string())))?;
    validate_plan(&plan)?;
    Ok(plan)
}

/// `msg` with its control characters escaped: the parser quotes keys and
/// values of the input, which may hold a line break, and an error is one line.
fn one_line(msg: &str) -> String {
    msg.chars()
        .map(|c| {
            if c.is_control() {
                c.escape_default().to_string()
            } else {
                c.to_string()
            }
        })
        .collect()
}

/// The structural rules of a plan: format; robot and limits valid; 1 to
/// [`MAX_SEGMENTS`] segments; knots = segments + 1 = intervals + 1; each segment's start time and duration
/// consistent, its duration whole microseconds of 1 µs..60 s (what the wire
/// carries); finite numbers; the via-points are knots, in order, first and
/// last included.
pub fn validate_plan(plan: &Plan) -> Result<(), LoadError> {
    let bad = |m: String| Err(LoadError::Invalid(m));
    if !known_format(&plan.format) {
        return Err(LoadError::Format {
            found: one_line(&plan.format),
        });
    }
    plan.robot
        .validate()
        .map_err(|e| LoadError::Invalid(format!("robot: {e}")))?;
    plan.limits
        .validate()
        .map_err(|e| LoadError::Invalid(format!("limits: {e}")))?;
    plan.travel
        .validate()
        .map_err(|e| LoadError::Invalid(e.to_string()))?;
    // The range a job's limits are held to, and the ceilings with them: a
    // plan whose limits no job could have is refused, not checked against
    // absurd bounds.
    let (lo, hi) = LIMIT_RANGE;
    for (what, named) in [
        ("limits", plan.limits.named()),
        ("ceilings", plan.ceilings.named()),
    ] {
        for (name, value) in named {
            if !(lo..=hi).contains(&value) {
                return bad(format!(
                    "{what}: `{name}` is {}, not in {}..{}",
                    readable(value),
                    readable(lo),
                    readable(hi)
                ));
            }
        }
    }
    let n = plan.segments.len();
    if n == 0 {
        return bad("no segments".into());
    }
    if n > MAX_SEGMENTS {
        return bad(format!(
            "{n} segments: a plan has at most {MAX_SEGMENTS} (the drives number them in 16 bits)"
        ));
    }
    if plan.intervals_s.len() != n || plan.knots_m.len() != n + 1 {
        return bad(format!(
            "{n} segments need {n} intervals and {} knots, found {} and {}",
            n + 1,
            plan.intervals_s.len(),
            plan.knots_m.len()
        ));
    }
    let finite = |p: &[f64; 3]| p.iter().all(|x| x.is_finite());
    if !plan.via_points_m.iter().all(finite) || !plan.knots_m.iter().all(finite) {
        return bad("a via-point or knot is not finite".into());
    }
    let mut t = 0.0;
    for (i, (s, h)) in plan.segments.iter().zip(&plan.intervals_s).enumerate() {
        let us = s.duration_s * 1e6;
        if !(us.is_finite() && us >= 0.5 && us <= MAX_DURATION_US as f64 + 0.5) {
            return bad(format!(
                "segment {} lasts {} s, not 1 µs to 60 s",
                i + 1,
                triquint_shared::readable::readable(s.duration_s)
            ));
        }
        if (us - us.round()).abs() > 1e-3 {
            return bad(format!(
                "segment {} lasts {} s, not a whole number of microseconds",
                i + 1,
                s.duration_s
            ));
        }
        if (s.duration_s - h).abs() > 1e-9 || (s.t0_s - t).abs() > 1e-6 {
            return bad(format!(
                "segment {} starts at {} s for {} s, but the intervals say {} s for {} s",
                i + 1,
                exact(s.t0_s),
                exact(s.duration_s),
                exact(t),
                exact(*h)
            ));
        }
        if s.coeffs.iter().flatten().any(|c| !c.is_finite()) {
            return bad(format!("segment {} has a non-finite coefficient", i + 1));
        }
        t += h;
    }
    if !plan.total_time_s.is_finite() || (plan.total_time_s - t).abs() > 1e-6 {
        return bad(format!(
            "total_time_s is {}, the intervals add up to {} s",
            exact(plan.total_time_s),
            exact(t)
        ));
    }
    via_points_are_knots(plan)?;
    free_knots_valid(plan)?;
    bound_valid(plan)?;
    shaping_valid(plan)
}

/// A deviation bound only in format 6, and there always, in the range a
/// job's `path.max_deviation_mm` is held to.
fn bound_valid(plan: &Plan) -> Result<(), LoadError> {
    let bounded = plan.format == PLAN_FORMAT_BOUNDED;
    match plan.max_deviation_m {
        None if bounded => Err(LoadError::Invalid(format!(
            "a `{PLAN_FORMAT_BOUNDED}` plan records its `max_deviation_m`; this one has none"
        ))),
        Some(_) if !bounded => Err(LoadError::Invalid(format!(
            "a `{}` plan has no `max_deviation_m` (only `{PLAN_FORMAT_BOUNDED}` records one)",
            one_line(&plan.format)
        ))),
        Some(m) => {
            let (lo, hi) = MAX_DEVIATION_MM;
            if (lo..=hi).contains(&(m * 1e3)) {
                Ok(())
            } else {
                Err(LoadError::Invalid(format!(
                    "max_deviation_m is {}, not in {}..{} m",
                    exact(m),
                    readable(lo * 1e-3),
                    readable(hi * 1e-3)
                )))
            }
        }
        None => Ok(()),
    }
}

/// A shaping record only in format 5, with a shaper the planner makes and
/// an unshaped plan that is a plan by every rule here; that the shaped plan
/// is its convolution is `check`'s to prove.
fn shaping_valid(plan: &Plan) -> Result<(), LoadError> {
    let shaped = plan.format == PLAN_FORMAT_SHAPED;
    let Some(record) = &plan.shaping else {
        return if shaped {
            Err(LoadError::Invalid(format!(
                "a `{PLAN_FORMAT_SHAPED}` plan records its `shaping`; this one has none"
            )))
        } else {
            Ok(())
        };
    };
    if !shaped {
        return Err(LoadError::Invalid(format!(
            "a `{}` plan has no `shaping` (only `{PLAN_FORMAT_SHAPED}` records one)",
            one_line(&plan.format)
        )));
    }
    let impulses = Impulses::for_spec(&record.shaper)
        .map_err(|e| LoadError::Invalid(format!("shaping: {e}")))?;
    if let Some(s) = record.unshaped.retimed
        && (!s.is_finite() || s < 1.0)
    {
        return Err(LoadError::Invalid(format!(
            "shaping.unshaped: `retimed` is {}, not a slow-down (a finite factor ≥ 1)",
            exact(s)
        )));
    }
    let base = unshaped(plan).ok_or_else(|| LoadError::Invalid("shaping: no record".into()))?;
    validate_plan(&base).map_err(|e| LoadError::Invalid(format!("shaping.unshaped: {e}")))?;
    let want = base.limits.total_time + impulses.duration_s();
    if (plan.limits.total_time - want).abs() > 1e-9 * want.max(1.0) {
        return Err(LoadError::Invalid(format!(
            "limits: `total_time` is {}, the unshaped plan's {} plus the shaper's {} s",
            exact(plan.limits.total_time),
            exact(base.limits.total_time),
            exact(impulses.duration_s())
        )));
    }
    Ok(())
}

/// The unshaped plan a shaped plan records (format 3, or 4 with free
/// knots), with the shaped plan's robot, limits but the total time, travel
/// and ceilings; `None` for a plan that is not shaped.
pub(crate) fn unshaped(plan: &Plan) -> Option<Plan> {
    let r = &plan.shaping.as_ref()?.unshaped;
    let mut base = plan.clone();
    base.format = if r.free_knots.is_empty() {
        PLAN_FORMAT
    } else {
        PLAN_FORMAT_FREE_KNOTS
    }
    .to_string();
    base.limits.total_time = r.total_time_limit_s;
    base.via_points_m = r.via_points_m.clone();
    base.knots_m = r.knots_m.clone();
    base.free_knots = r.free_knots.clone();
    base.intervals_s = r.intervals_s.clone();
    base.total_time_s = r.total_time_s;
    base.segments = r.segments.clone();
    base.max_abs = r.max_abs.clone();
    base.shaping = None;
    Some(base)
}

/// The formats this loader reads.
fn known_format(f: &str) -> bool {
    [
        PLAN_FORMAT,
        PLAN_FORMAT_FREE_KNOTS,
        PLAN_FORMAT_SHAPED,
        PLAN_FORMAT_BOUNDED,
        PLAN_FORMAT_2,
        PLAN_FORMAT_1,
    ]
    .contains(&f)
}

/// Free knots only in format 4 (and there at least one) and 6 (any):
/// interior knots, in increasing order.
fn free_knots_valid(plan: &Plan) -> Result<(), LoadError> {
    let free = &plan.free_knots;
    let bad = |m: String| Err(LoadError::Invalid(m));
    if plan.format != PLAN_FORMAT_BOUNDED
        && (plan.format == PLAN_FORMAT_FREE_KNOTS) == free.is_empty()
    {
        return bad(format!(
            "a `{}` plan {} free knots",
            plan.format,
            if free.is_empty() { "needs" } else { "has no" }
        ));
    }
    let last = plan.knots_m.len() - 1;
    if let Some(k) = free.iter().find(|&&k| k == 0 || k >= last) {
        return bad(format!(
            "free knot {k} is not an interior knot (1..{})",
            last - 1
        ));
    }
    if free.windows(2).any(|w| w[0] >= w[1]) {
        return bad("free knots are not in increasing order".to_string());
    }
    Ok(())
}

/// `x` with every digit that tells it apart (the checks compare to 1e-9),
/// but in scientific notation when huge or tiny, so that a number of the
/// file (`1e250`) keeps the message one short line.
fn exact(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

fn via_points_are_knots(plan: &Plan) -> Result<(), LoadError> {
    let model = plan.robot.model::<f64>();
    let pts = &plan.via_points_m;
    if pts.len() < 2 {
        return Err(LoadError::Invalid(format!(
            "{} via-points, at least 2 needed",
            pts.len()
        )));
    }
    let mut next = 0;
    for (i, p) in pts.iter().enumerate() {
        let q = Pose::from_cartesian(&model, Vector3::from(*p))
            .map_err(|e| LoadError::Invalid(format!("via-point {}: {e}", i + 1)))?
            .q;
        let dist = |k: usize| {
            (0..3)
                .map(|j| (plan.knots_m[k][j] - q[j]).abs())
                .fold(0.0, f64::max)
        };
        let last = plan.knots_m.len() - 1;
        let found = match i {
            0 => (dist(0) <= 1e-9).then_some(0),
            _ if i == pts.len() - 1 => (dist(last) <= 1e-9 && next <= last).then_some(last),
            _ => (next..=last).find(|&k| dist(k) <= 1e-9),
        };
        match found {
            Some(k) => next = k + 1,
            None => {
                return Err(LoadError::Invalid(format!(
                    "via-point {} is not a knot after the previous via-point's{}",
                    i + 1,
                    if i == 0 || i == pts.len() - 1 {
                        " (the first and last via-points must be the first and last knots)"
                    } else {
                        ""
                    }
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use triquint_shared::plan::{MaxAbs, Objective, Segment, SolverStats};
    use triquint_shared::{Limits, Robot};

    /// A structurally valid plan of `n` 1 ms segments at rest at one point.
    fn resting(n: usize) -> Plan {
        let robot = Robot::default();
        let p = [0.0, 0.0, 0.6];
        let q: [f64; 3] = Pose::from_cartesian(&robot.model::<f64>(), Vector3::from(p))
            .unwrap()
            .q
            .into();
        let mut t = 0.0;
        let segments = (0..n)
            .map(|_| {
                let s = Segment {
                    t0_s: t,
                    duration_s: 1e-3,
                    coeffs: q.map(|x| [x, 0.0, 0.0, 0.0, 0.0, 0.0]),
                };
                t += 1e-3;
                s
            })
            .collect();
        Plan {
            format: PLAN_FORMAT.into(),
            objective: Objective::MinMaxJerk,
            robot,
            limits: Limits::default(),
            travel: Default::default(),
            ceilings: Default::default(),
            via_points_m: vec![p, p],
            knots_m: vec![q; n + 1],
            free_knots: Vec::new(),
            max_deviation_m: None,
            intervals_s: vec![1e-3; n],
            total_time_s: t,
            segments,
            max_abs: MaxAbs::default(),
            solver: SolverStats::default(),
            shaping: None,
        }
    }

    #[test]
    fn huge_numbers_keep_messages_short() {
        let mut p = resting(4);
        p.total_time_s = 1e250;
        let e = validate_plan(&p).unwrap_err().to_string();
        assert_eq!(e, "total_time_s is 1e250, the intervals add up to 0.004 s");
        p.total_time_s = 0.004;
        p.segments[1].t0_s = -1e250;
        let e = validate_plan(&p).unwrap_err().to_string();
        assert!(e.contains("starts at -1e250 s for 0.001 s"), "{e}");
        assert!(e.len() < 120, "{e}");
    }

    #[test]
    fn more_segments_than_the_wire_numbers_are_refused() {
        assert_eq!(validate_plan(&resting(MAX_SEGMENTS)), Ok(()));
        let e = validate_plan(&resting(MAX_SEGMENTS + 1)).unwrap_err();
        assert_eq!(
            e.to_string(),
            "65536 segments: a plan has at most 65535 (the drives number them in 16 bits)"
        );
    }
}
