//! The point-to-point move of `move-to` and `upload --approach`.

use nalgebra::Vector3;
use triquint_planner::{Job, Objective, Options, Plan, plan};
use triquint_shared::kinematics::Pose;
use triquint_shared::{Limits, Robot};

use crate::exit::{CliError, CliResult, plan_error};

/// The minimum-time, minimum-jerk move within the default limits from
/// joints `q0` (m) to the platform at `target` (m); `None` when every axis
/// is within 1 µm of it already.
pub fn plan_move(robot: &Robot, q0: Vector3<f64>, target: Vector3<f64>) -> CliResult<Option<Plan>> {
    let m = robot.model::<f64>();
    let start = Pose::from_joints(&m, q0).map_err(|e| {
        CliError::device(format!(
            "the drives report joints {:?} m, which have no valid pose: {e}",
            q0.as_slice()
        ))
    })?;
    let goal = Pose::from_cartesian(&m, target).map_err(|e| CliError::bad_input(e.to_string()))?;
    triquint_cli_common::errln!(
        "at ({:.3}, {:.3}, {:.3}) mm, moving to ({:.3}, {:.3}, {:.3}) mm",
        start.r.x * 1e3,
        start.r.y * 1e3,
        start.r.z * 1e3,
        target.x * 1e3,
        target.y * 1e3,
        target.z * 1e3
    );
    if (goal.q - q0).amax() < 1e-6 {
        return Ok(None);
    }
    let job = Job::builder()
        .objective(Objective::MinTime)
        .robot(robot.clone())
        .limits(Limits::default())
        .points_m([start.r.into(), target.into()])
        .build()
        .map_err(plan_error)?;
    let opts = Options {
        starts: 3,
        ..Options::default()
    };
    let p = plan(&job, &opts).map_err(plan_error)?;
    triquint_cli_common::errln!(
        "planned {} segments, {:.3} s",
        p.segments.len(),
        p.total_time_s
    );
    Ok(Some(p))
}
