//! `triquint move-to X Y Z --iface IFACE`: a minimum-time, minimum-jerk
//! point-to-point move from where the drives report the machine is to the
//! given platform position (mm), within the limits, run through `upload`.
//! This is how a machine is brought to a plan's start.

use std::time::Duration;

use clap::Args;
use nalgebra::Vector3;
use triquint_link::{Listener, SocketCanPort};
use triquint_planner::{Job, Objective, Options, Plan, plan};
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::config::HomingSettings;
use triquint_shared::{Limits, Robot};

use crate::cli::finite;
use crate::cli::home::configure;
use crate::cli::keys::Keys;
use crate::cli::listen::{listen, open};
use crate::cli::upload::{BusArgs, check_bus_args, report, run_plan};
use crate::exit::{CliError, CliResult, plan_error};

#[derive(Args, Debug)]
pub struct MoveToArgs {
    /// Platform x (mm).
    #[arg(allow_hyphen_values = true)]
    pub x: String,
    /// Platform y (mm).
    #[arg(allow_hyphen_values = true)]
    pub y: String,
    /// Platform z (mm).
    #[arg(allow_hyphen_values = true)]
    pub z: String,
    #[command(flatten)]
    pub bus: BusArgs,
    /// Print the upload summary as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Joint positions (m) from every drive's Telemetry within `wait`, and
/// whether each is homed.
fn listen_positions(
    port: &mut SocketCanPort,
    ids: [u8; 3],
    wait: Duration,
) -> CliResult<([Option<f64>; 3], [bool; 3])> {
    let mut l = Listener::new(ids);
    listen(port, &mut l, wait, true)?;
    Ok((
        l.nodes.0.map(|v| v.position.map(f64::from)),
        l.nodes.0.map(|v| v.homed && v.sync_seen_at.is_some()),
    ))
}

pub fn run(args: &MoveToArgs, robot: &Robot, homing: &HomingSettings) -> CliResult {
    let target_mm = Vector3::new(
        finite("X", &args.x)?,
        finite("Y", &args.y)?,
        finite("Z", &args.z)?,
    );
    let target = target_mm / 1000.0;
    let m = robot.model::<f64>();
    Pose::from_cartesian(&m, target).map_err(|e| {
        CliError::bad_input(format!(
            "target ({}, {}, {}) mm is not reachable: {e}",
            triquint_shared::readable::readable(target_mm.x),
            triquint_shared::readable::readable(target_mm.y),
            triquint_shared::readable::readable(target_mm.z)
        ))
    })?;
    check_bus_args(&args.bus)?;
    let q0 = reported_joints(robot, homing, &args.bus)?;
    let Some(p) = plan_move(robot, q0, target)? else {
        println!("already within 1 µm of the target on every axis");
        return Ok(());
    };
    let mut keys = Keys::open(1000);
    let summary = run_plan(&p, &args.bus, homing, false, keys.as_mut())?;
    drop(keys);
    report(&summary, &args.bus, args.json)
}

/// Where the drives on `bus` report the joints (m), configuring them first
/// if they do not report a position; refused when one is not homed.
pub fn reported_joints(
    robot: &Robot,
    homing: &HomingSettings,
    bus: &BusArgs,
) -> CliResult<Vector3<f64>> {
    let ids = bus.ids()?;
    let mut port = open(&bus.iface)?;
    let (mut q, mut homed) = listen_positions(&mut port, ids, Duration::from_millis(300))?;
    if q.iter().any(Option::is_none) {
        configure(robot, homing, bus)?;
        (q, homed) = listen_positions(&mut port, ids, Duration::from_secs_f64(bus.timeout))?;
    }
    drop(port);
    if let Some(i) = homed.iter().position(|h| !h) {
        let n = crate::cli::listen::nodes_arg(ids);
        return Err(CliError::refused(format!(
            "{}: node {} is not homed (its position is unknown): run `triquint home --iface {}{n}` first",
            bus.iface, ids[i], bus.iface
        )));
    }
    match q {
        [Some(a), Some(b), Some(c)] => Ok(Vector3::new(a, b, c)),
        _ => {
            let node = q
                .iter()
                .position(Option::is_none)
                .map_or(ids[0], |i| ids[i]);
            Err(CliError::device(format!(
                "{}: node {node}: no position (Telemetry) within {} s",
                bus.iface, bus.timeout
            )))
        }
    }
}

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
    eprintln!(
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
    eprintln!(
        "planned {} segments, {:.3} s",
        p.segments.len(),
        p.total_time_s
    );
    Ok(Some(p))
}
