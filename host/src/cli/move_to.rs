//! `triquint move-to X Y Z --iface IFACE`: a minimum-time, minimum-jerk
//! point-to-point move from where the drives report the machine is to the
//! given platform position (mm), within the limits, run through `upload`.
//! This is how a machine is brought to a plan's start.

use clap::Args;
use nalgebra::Vector3;
use triquint_cli_common::outln;
use triquint_shared::kinematics::Pose;
use triquint_shared::machine::Machine;

use crate::cli::bus_args::BusArgs;
use crate::cli::finite;
use crate::cli::terminal_watch::TerminalWatch;
use crate::cli::upload_summary;
use crate::exit::{CliError, CliResult};
use crate::ops::joints::reported_joints;
use crate::ops::plan_move::plan_move;
use crate::ops::run::run_plan;

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
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

pub fn run(args: &MoveToArgs, machine: &Machine) -> CliResult {
    let target_mm = Vector3::new(
        finite("X", &args.x)?,
        finite("Y", &args.y)?,
        finite("Z", &args.z)?,
    );
    let target = target_mm / 1000.0;
    let m = machine.robot.model::<f64>();
    Pose::from_cartesian(&m, target).map_err(|e| {
        CliError::bad_input(format!(
            "target ({}, {}, {}) mm is not reachable: {e}",
            triquint_shared::readable::readable(target_mm.x),
            triquint_shared::readable::readable(target_mm.y),
            triquint_shared::readable::readable(target_mm.z)
        ))
    })?;
    let bus = &args.bus.bus(machine)?;
    let q0 = reported_joints(machine, bus)?;
    let Some(p) = plan_move(machine, q0, target)? else {
        outln!("already within 1 µm of the target on every axis")?;
        return Ok(());
    };
    let mut watch = TerminalWatch::open();
    let summary = run_plan(&p, bus, machine, false, &mut watch)?;
    drop(watch);
    upload_summary::show(&summary, bus, args.json)
}
