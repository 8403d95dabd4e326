//! `triquint ik X Y Z`: slider positions for a platform position (mm).

use clap::Args;
use nalgebra::Vector3;
use serde_json::json;
use triquint_cli_common::outln;
use triquint_shared::kinematics::Pose;
use triquint_shared::machine::Machine;
use triquint_shared::readable::readable;

use super::{finite, fmt_triple};
use crate::exit::{CliError, CliResult};

#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct IkArgs {
    /// Platform x (mm).
    pub x: String,
    /// Platform y (mm).
    pub y: String,
    /// Platform z (mm).
    pub z: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

pub fn run(args: &IkArgs, machine: &Machine) -> CliResult {
    let robot = &machine.robot;
    let r_mm = Vector3::new(
        finite("X", &args.x)?,
        finite("Y", &args.y)?,
        finite("Z", &args.z)?,
    );
    let pose = Pose::from_cartesian(&robot.model::<f64>(), r_mm / 1000.0).map_err(|e| {
        CliError::bad_input(format!(
            "position ({}, {}, {}) mm is outside the workspace: {e}",
            readable(r_mm.x),
            readable(r_mm.y),
            readable(r_mm.z)
        ))
    })?;
    // A pose whose sliders stand outside their travel is no answer.
    if let Some(o) = machine.travel().outside(&pose.q.into()) {
        return Err(CliError::bad_input(format!(
            "position ({}, {}, {}) mm is outside the travel: {o}",
            readable(r_mm.x),
            readable(r_mm.y),
            readable(r_mm.z)
        )));
    }
    let q_mm = pose.q * 1000.0;
    if args.json {
        outln!(
            "{}",
            json!({"position_mm": r_mm.as_slice(), "joints_mm": q_mm.as_slice()})
        )?;
    } else {
        outln!(
            "position (mm)  {}",
            fmt_triple(["x ", "y ", "z "], &r_mm, 3)
        )?;
        outln!(
            "joints (mm)    {}",
            fmt_triple(["q1", "q2", "q3"], &q_mm, 3)
        )?;
    }
    Ok(())
}
