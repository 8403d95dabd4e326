//! Names of a plan's knots, the same in every chart and table: a knot at
//! the user's via-point k is `Pk` (as on the path plot), and the knots the
//! planner inserted on the straight line after it are `Pk.1`, `Pk.2`, ….

use nalgebra::Vector3;
use triquint_shared::kinematics::Pose;
use triquint_shared::plan::Plan;

/// How close a knot's joints must be to a via-point's to be it (m), as the
/// plan loader requires of every via-point.
const SAME_POINT_M: f64 = 1e-9;

/// One label per knot, in order.
pub fn knot_labels(plan: &Plan) -> Vec<String> {
    let knots = knot_count(plan);
    // Knots are joint positions, via-points Cartesian.
    let model = plan.robot.model::<f64>();
    let vias: Option<Vec<Vector3<f64>>> = plan
        .via_points_m
        .iter()
        .map(|p| {
            Pose::from_cartesian(&model, Vector3::from(*p))
                .ok()
                .map(|pose| pose.q)
        })
        .collect();
    let vias = match vias {
        Some(v) if plan.knots_m.len() == knots && !v.is_empty() => v,
        _ => return (1..=knots).map(|k| format!("P{k}")).collect(),
    };
    let mut labels = Vec::with_capacity(knots);
    let (mut next, mut inserted) = (0usize, 0usize);
    for knot in &plan.knots_m {
        let at_via = vias
            .get(next)
            .is_some_and(|v| (0..3).all(|a| (v[a] - knot[a]).abs() <= SAME_POINT_M));
        if at_via || next == 0 {
            next += 1;
            inserted = 0;
            labels.push(format!("P{next}"));
        } else {
            inserted += 1;
            labels.push(format!("P{next}.{inserted}"));
        }
    }
    labels
}

fn knot_count(plan: &Plan) -> usize {
    plan.segments.len() + usize::from(!plan.segments.is_empty())
}
