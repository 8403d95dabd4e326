//! Streamability as a constraint of the planner: every plan it writes
//! streams to the default drives without underrun (docs/protocol.md,
//! "Streamability"; the rule is `shared::protocol::streaming`, for the
//! default drive settings, queue capacity and the stop ramp the host
//! configures for the plan). Stages that choose knots (free knots, input
//! shaping) call [`shortfall`] to prefer fewer, longer segments; the last
//! stage refuses a plan that breaks it with [`PlanError::Unstreamable`].

use triquint_shared::plan::{Plan, WireError};
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::streaming::{QUEUE_CAPACITY, Shortfall, StreamRule};

use crate::error::PlanError;

/// The shortest run of `plan`'s segments against the rule on the default
/// drives: `Ok(None)` when the queue holds the plan whole (no stop-ramp
/// sizing then) or no rule applies, `Err` when its wire segments cannot
/// be made.
fn shortest_run(plan: &Plan) -> Result<Option<Shortfall>, WireError> {
    if plan.segments.len() <= QUEUE_CAPACITY {
        return Ok(None);
    }
    let Some(rule) = StreamRule::for_plan(plan, &DriveSettings::default(), QUEUE_CAPACITY) else {
        return Ok(None);
    };
    let durations: Vec<u32> = plan
        .wire_segments()?
        .iter()
        .map(|w| w.duration_us)
        .collect();
    Ok(rule.shortest_run(&durations))
}

/// The first shortest run of `plan`'s segments too short to stream on the
/// default drives, if any. A plan the queue holds whole always streams.
pub(crate) fn shortfall(plan: &Plan) -> Option<Shortfall> {
    shortest_run(plan)
        .ok()
        .flatten()
        .filter(|s| s.run_us < s.need_us)
}

/// Whether `plan` streams with every run of segments at least `margin_us`
/// longer than the rule needs (a plan the queue holds whole always does).
pub(crate) fn streams_with_margin(plan: &Plan, margin_us: u64) -> bool {
    shortest_run(plan)
        .is_ok_and(|r| r.is_none_or(|s| s.run_us >= s.need_us.saturating_add(margin_us)))
}

/// `plan` if it streams, else the verdict naming the run that does not.
pub(crate) fn streams(plan: &Plan) -> Result<(), PlanError> {
    match shortfall(plan) {
        None => Ok(()),
        Some(s) => Err(PlanError::Unstreamable {
            first: s.first,
            last: s.last,
            run_s: s.run_us as f64 * 1e-6,
            need_s: s.need_us as f64 * 1e-6,
            capacity: QUEUE_CAPACITY,
            shaper: plan.shaping.as_ref().map(|s| s.shaper),
        }),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Job, Objective, Options, plan};

    /// 20 points 2 mm apart, as fast as the limits allow: 19 segments of a
    /// few tens of ms, far less than a queue's worth of look-ahead.
    #[test]
    fn many_short_segments_are_refused_naming_the_run_that_does_not_stream() {
        let pts: Vec<[f64; 3]> = (0..20).map(|i| [2.0 * i as f64, 0.0, 600.0]).collect();
        let job = Job::builder()
            .objective(Objective::MinTime)
            .points_mm(pts)
            .build()
            .unwrap();
        match plan(&job, &Options::default()) {
            Err(e @ PlanError::Unstreamable { .. }) => {
                let PlanError::Unstreamable {
                    first,
                    last,
                    run_s,
                    need_s,
                    capacity,
                    shaper,
                } = e
                else {
                    unreachable!()
                };
                assert_eq!(capacity, QUEUE_CAPACITY);
                assert_eq!(shaper, None);
                assert_eq!(last + 1 - first, QUEUE_CAPACITY - 1);
                assert!(last + 1 < 19 && run_s > 0.0 && run_s < need_s, "{e}");
                assert!(e.to_string().starts_with("unstreamable: segments "), "{e}");
            }
            other => panic!("not refused: {other:?}"),
        }
    }

    /// The same points over a longer total time stream, and the plan's
    /// shortest run holds what the rule needs.
    #[test]
    fn the_same_points_slower_stream() {
        let pts: Vec<[f64; 3]> = (0..20).map(|i| [2.0 * i as f64, 0.0, 600.0]).collect();
        let job = Job::builder()
            .points_mm(pts)
            .total_time(40.0)
            .build()
            .unwrap();
        let p = plan(&job, &Options::default()).unwrap();
        assert_eq!(p.segments.len(), 19);
        assert!(shortfall(&p).is_none());
        assert!(streams(&p).is_ok());
    }
}
