//! `triquint move-to X Y Z --iface IFACE`: a minimum-time, minimum-jerk
//! point-to-point move from where the drives report the machine is to the
//! given platform position (mm), within the limits, run through `upload`.
//! This is how a machine is brought to a plan's start.

use std::time::{Duration, Instant, SystemTime};

use clap::Args;
use nalgebra::Vector3;
use triquint_link::{DriveConfigs, Session, SessionOptions, SocketCanPort, open_host};
use triquint_planner::{Job, Objective, Options, plan};
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{Msg, decode};
use triquint_shared::{Limits, Robot};

use crate::cli::finite;
use crate::cli::upload::{BusArgs, report, run_plan};
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

/// Joint positions (m) from every node's Telemetry within `wait`.
fn listen_positions(port: &mut SocketCanPort, wait: Duration) -> CliResult<[Option<f64>; 3]> {
    let t0 = Instant::now();
    let mut q = [None; 3];
    while t0.elapsed() < wait && q.iter().any(Option::is_none) {
        match port.recv().map_err(CliError::device)? {
            Some(rx) => {
                if let Ok((Msg::Telemetry(t), node @ 1..=3)) = decode(&rx.frame) {
                    q[node as usize - 1] = Some(t.position as f64);
                }
            }
            None => std::thread::sleep(Duration::from_millis(1)),
        }
    }
    Ok(q)
}

/// Configures unconfigured drives (they report positions only once configured)
/// with stop times for the limits themselves.
fn configure(robot: &Robot, limits: &Limits, bus: &BusArgs) -> CliResult {
    let settings = DriveSettings {
        control_rate: bus.rate,
        ..DriveSettings::default()
    };
    let configs = DriveConfigs::for_limits(robot, limits, &settings).nodes;
    let opts = SessionOptions {
        fd: bus.fd,
        response_timeout_us: (bus.timeout * 1e6) as u64,
        ..SessionOptions::default()
    };
    let mut session = Session::configure(configs, opts);
    let mut port = open_host(&bus.iface, bus.fd).map_err(CliError::device)?;
    loop {
        match session.poll(&mut port) {
            Ok(Some(_)) => return Ok(()),
            Ok(None) => std::thread::sleep(Duration::from_millis(1)),
            Err(e) => {
                return Err(CliError::device(format!(
                    "{}: configuring the drives: {e}",
                    bus.iface
                )));
            }
        }
    }
}

pub fn run(args: &MoveToArgs, robot: &Robot) -> CliResult {
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
            triquint_planner::readable(target_mm.x),
            triquint_planner::readable(target_mm.y),
            triquint_planner::readable(target_mm.z)
        ))
    })?;
    let limits = Limits::default();
    let mut port = SocketCanPort::open(&args.bus.iface, true, false, SystemTime::now())
        .map_err(CliError::device)?;
    let mut q = listen_positions(&mut port, Duration::from_millis(300))?;
    if q.iter().any(Option::is_none) {
        configure(robot, &limits, &args.bus)?;
        q = listen_positions(&mut port, Duration::from_secs_f64(args.bus.timeout))?;
    }
    drop(port);
    let q0 = match q {
        [Some(a), Some(b), Some(c)] => Vector3::new(a, b, c),
        _ => {
            let node = q.iter().position(Option::is_none).map_or(1, |i| i + 1);
            return Err(CliError::device(format!(
                "{}: node {node}: no position (Telemetry) within {} s",
                args.bus.iface, args.bus.timeout
            )));
        }
    };
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
        target_mm.x,
        target_mm.y,
        target_mm.z
    );
    if (goal.q - q0).amax() < 1e-6 {
        println!("already within 1 µm of the target on every axis");
        return Ok(());
    }
    let job = Job::builder()
        .objective(Objective::MinTime)
        .robot(robot.clone())
        .limits(limits)
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
    let summary = run_plan(&p, &args.bus)?;
    report(&summary, &args.bus, args.json)
}
