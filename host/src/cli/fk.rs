//! `triquint fk Q1 Q2 Q3`: platform position for slider positions (mm).

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
pub struct FkArgs {
    /// Slider 1 height (mm).
    pub q1: String,
    /// Slider 2 height (mm).
    pub q2: String,
    /// Slider 3 height (mm).
    pub q3: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

pub fn run(args: &FkArgs, machine: &Machine) -> CliResult {
    let robot = &machine.robot;
    let q_mm = Vector3::new(
        finite("Q1", &args.q1)?,
        finite("Q2", &args.q2)?,
        finite("Q3", &args.q3)?,
    );
    let q_m: [f64; 3] = (q_mm / 1000.0).into();
    if let Some(o) = machine.travel().outside(&q_m) {
        return Err(CliError::bad_input(format!(
            "joints ({}, {}, {}) mm are outside the travel: {o}",
            readable(q_mm.x),
            readable(q_mm.y),
            readable(q_mm.z)
        )));
    }
    let pose = Pose::from_joints(&robot.model::<f64>(), q_mm / 1000.0).map_err(|e| {
        CliError::bad_input(format!(
            "joints ({}, {}, {}) mm have no valid pose: {e}",
            readable(q_mm.x),
            readable(q_mm.y),
            readable(q_mm.z)
        ))
    })?;
    let r_mm = pose.r * 1000.0;
    if args.json {
        outln!(
            "{}",
            json!({"joints_mm": q_mm.as_slice(), "position_mm": r_mm.as_slice()})
        )?;
    } else {
        outln!(
            "joints (mm)    {}",
            fmt_triple(["q1", "q2", "q3"], &q_mm, 3)
        )?;
        outln!(
            "position (mm)  {}",
            fmt_triple(["x ", "y ", "z "], &r_mm, 3)
        )?;
    }
    Ok(())
}
