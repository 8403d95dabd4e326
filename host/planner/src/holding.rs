//! The torque that holds the platform still at a point: every plan starts
//! and ends at rest, where each motor carries the static load of gravity
//! alone, so a torque limit below it at the first or last via-point is
//! infeasible whatever the timing, and is refused before planning.

use nalgebra::Vector3;
use triquint_shared::Model;
use triquint_shared::dynamics::torque;
use triquint_shared::kinematics::Pose;

use crate::error::PlanError;

/// The motor that needs the most torque to hold the platform still at
/// `p` (m), and that torque (N·m, magnitude). `None` where `p` has no
/// pose (refused elsewhere, with the reason).
pub(crate) fn holding_torque(model: &Model<f64>, p: [f64; 3]) -> Option<(usize, f64)> {
    let q = Pose::from_cartesian(model, Vector3::from(p)).ok()?.q;
    let tau = torque(model, &q, &Vector3::zeros(), &Vector3::zeros()).ok()?;
    (0..3)
        .map(|i| (i, tau[i].abs()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
}

/// Refuses a torque limit below the holding torque at the path's ends.
pub(crate) fn check_holding(
    model: &Model<f64>,
    points_m: &[[f64; 3]],
    limit_nm: f64,
) -> Result<(), PlanError> {
    let last = points_m.len().saturating_sub(1);
    for index in [0, last] {
        let Some(p) = points_m.get(index) else {
            continue;
        };
        if let Some((axis, holding_nm)) = holding_torque(model, *p)
            && holding_nm > limit_nm
        {
            return Err(PlanError::BelowHoldingTorque {
                index,
                axis,
                holding_nm,
                limit_nm,
            });
        }
    }
    Ok(())
}
