//! The point-to-point move of `move-to` and `upload --approach`.

use nalgebra::Vector3;
use triquint_planner::{Job, Objective, Options, Plan, plan};
use triquint_shared::Travel;
use triquint_shared::kinematics::Pose;
use triquint_shared::machine::Machine;

use crate::ops::error::{OpError, OpResult};

/// The minimum-time, minimum-jerk move within the default limits (held to
/// the machine's ceilings) from
/// joints `q0` (m) to the platform at `target` (m); `None` when every axis
/// is within 1 µm of it already.
///
/// The target must lie inside the travel. The start may not: homing leaves
/// a slider between the travel's end and its switch, so the move's travel
/// is widened to take in where the sliders are, and the move only heads
/// back inside.
pub fn plan_move(
    machine: &Machine,
    q0: Vector3<f64>,
    target: Vector3<f64>,
) -> OpResult<Option<Plan>> {
    let m = machine.robot.model::<f64>();
    let start = Pose::from_joints(&m, q0).map_err(|source| OpError::NoPose {
        q: q0.into(),
        source,
    })?;
    let goal = Pose::from_cartesian(&m, target).map_err(OpError::Unreachable)?;
    triquint_cli_common::errln!(
        "at ({:.3}, {:.3}, {:.3}) mm, moving to ({:.3}, {:.3}, {:.3}) mm",
        start.r.x * 1e3,
        start.r.y * 1e3,
        start.r.z * 1e3,
        target.x * 1e3,
        target.y * 1e3,
        target.z * 1e3
    );
    let travel = machine.travel();
    if let Some(source) = travel.outside(&goal.q.into()) {
        return Err(OpError::OutsideTravel {
            target_mm: (target * 1e3).into(),
            source,
        });
    }
    if (goal.q - q0).amax() < 1e-6 {
        return Ok(None);
    }
    let job = Job::builder()
        .objective(Objective::MinTime)
        .machine(machine)
        .limits(crate::ops::configure::machine_limits(machine))
        .travel(travel_from(&travel, q0))
        .points_m([start.r.into(), target.into()])
        .build()?;
    let opts = Options {
        starts: 3,
        ..Options::default()
    };
    let p = plan(&job, &opts)?;
    triquint_cli_common::errln!(
        "planned {} segments, {:.3} s",
        p.segments.len(),
        p.total_time_s
    );
    Ok(Some(p))
}

/// `travel` widened per axis to take in the joints `q0` (m), with room for
/// the rounding of the forward and inverse kinematics the start goes through.
fn travel_from(travel: &Travel, q0: Vector3<f64>) -> Travel {
    const ROUNDING_M: f64 = 1e-9;
    Travel {
        min: std::array::from_fn(|a| travel.min[a].min(q0[a] - ROUNDING_M)),
        max: std::array::from_fn(|a| travel.max[a].max(q0[a] + ROUNDING_M)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where homing leaves the sliders: above the travel's end, below the
    /// switch.
    const HOMED_M: f64 = 0.4163;

    #[test]
    fn a_move_from_the_homing_rest_heads_back_inside_the_travel() {
        let machine = Machine::default();
        let travel = Travel::default();
        assert!(HOMED_M > travel.max[0]);
        let q0 = Vector3::repeat(HOMED_M);
        let p = plan_move(&machine, q0, Vector3::new(-0.09, 0.09, 0.68))
            .expect("planned")
            .expect("a move");
        let end = p.segments.last().unwrap().quintic().end();
        assert!(travel.outside(&end.q.into()).is_none());
    }

    #[test]
    fn a_target_outside_the_travel_is_bad_input() {
        let machine = Machine::default();
        let e = plan_move(&machine, Vector3::repeat(0.3), Vector3::new(0.0, 0.0, 0.1)).unwrap_err();
        assert!(e.to_string().contains("outside the travel"), "{e}");
    }

    #[test]
    fn the_widened_travel_takes_in_the_start_and_nothing_else() {
        let t = travel_from(&Travel::default(), Vector3::new(0.4163, 0.2, 0.04));
        assert_eq!(t.max, [0.4163 + 1e-9, 0.415, 0.415]);
        assert_eq!(t.min, [0.05, 0.05, 0.04 - 1e-9]);
    }
}
