//! A torque limit below what holds the platform still at the path's ends is
//! refused up front, naming the point, the motor and the holding torque.

use triquint_planner::{Job, Objective, Options, PlanError, plan};
use triquint_shared::dynamics::state_torque;

fn job(torque: f64) -> Result<Job, PlanError> {
    let limits = triquint_planner::Limits {
        torque,
        ..Default::default()
    };
    Job::builder()
        .objective(Objective::MinTime)
        .limits(limits)
        .points_mm([[-90.0, 90.0, 680.0], [60.0, -40.0, 560.0]])
        .build()
}

/// The largest |torque| of any motor at rest at the plan's start and end,
/// from the plan itself (not from the planner's check).
fn at_rest(p: &triquint_planner::Plan) -> [(usize, f64); 2] {
    let model = p.robot.model::<f64>();
    [0.0, p.duration()].map(|t| {
        let tau = state_torque(&model, p.at(t).unwrap()).unwrap();
        (0..3)
            .map(|i| (i, tau[i].abs()))
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .unwrap()
    })
}

#[test]
fn a_limit_below_the_holding_torque_names_it() {
    let p = plan(&job(10.0).unwrap(), &Options::default()).unwrap();
    let ends = at_rest(&p);
    let holding = ends[0].1.max(ends[1].1);
    let limit = 0.99 * holding;
    // The first end, in path order, that needs more than the limit.
    let end = if ends[0].1 > limit { 0 } else { 1 };
    let (axis, holding) = ends[end];
    match job(limit) {
        Err(e @ PlanError::BelowHoldingTorque { .. }) => {
            let PlanError::BelowHoldingTorque {
                index,
                axis: a,
                holding_nm,
                limit_nm,
            } = e
            else {
                unreachable!()
            };
            assert_eq!(index, end, "the first end that needs more");
            assert_eq!(a, axis);
            assert!(
                (holding_nm - holding).abs() <= 1e-9 * holding,
                "{holding_nm} vs {holding}"
            );
            assert_eq!(limit_nm, limit);
            let msg = e.to_string();
            assert!(msg.contains("hold the platform still"), "{msg}");
            assert!(msg.contains("motor ") && !msg.contains(" inf "), "{msg}");
        }
        other => panic!("expected BelowHoldingTorque, got {other:?}"),
    }
    // Just above the larger holding torque the job builds.
    assert!(job(1.01 * ends[0].1.max(ends[1].1)).is_ok());
}
