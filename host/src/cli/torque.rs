//! `triquint torque --q .. --qd .. --qdd ..`: inverse-dynamics motor torques.

use clap::Args;
use serde_json::json;
use triquint_cli_common::outln;
use triquint_shared::dynamics;
use triquint_shared::machine::Machine;

use super::{fmt_triple, parse_triple};
use crate::exit::{CliError, CliResult};

#[derive(Args, Debug)]
#[command(allow_negative_numbers = true)]
pub struct TorqueArgs {
    /// Joint positions Q1,Q2,Q3 (m).
    #[arg(long, allow_hyphen_values = true)]
    pub q: String,
    /// Joint velocities V1,V2,V3 (m/s).
    #[arg(long, allow_hyphen_values = true)]
    pub qd: String,
    /// Joint accelerations A1,A2,A3 (m/s²).
    #[arg(long, allow_hyphen_values = true)]
    pub qdd: String,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

pub fn run(args: &TorqueArgs, machine: &Machine) -> CliResult {
    let robot = &machine.robot;
    let q = parse_triple("--q", &args.q)?;
    // `ik` prints millimetres; a pose pasted from it is far outside the
    // travel in metres, and said so rather than computed.
    if let Some(o) = machine.travel().outside(&q.into()) {
        let hint = if q.iter().any(|x| x.abs() > 10.0) {
            " (--q is in metres; `triquint ik` prints millimetres: divide by 1000)"
        } else {
            ""
        };
        return Err(CliError::bad_input(format!(
            "--q {}: outside the travel: {o}{hint}",
            args.q
        )));
    }
    let qd = parse_triple("--qd", &args.qd)?;
    let qdd = parse_triple("--qdd", &args.qdd)?;
    let tau = dynamics::torque(&robot.model::<f64>(), &q, &qd, &qdd)
        .map_err(|e| CliError::bad_input(format!("--q {}: {e}", args.q)))?;
    if args.json {
        outln!("{}", json!({"torque_nm": tau.as_slice()}))?;
    } else {
        outln!("torque (N·m)   {}", fmt_triple(["τ1", "τ2", "τ3"], &tau, 6))?;
    }
    Ok(())
}
