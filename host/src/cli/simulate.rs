//! `triquint simulate PLAN.json`: runs a plan on the in-process virtual hardware.

use clap::Args;

use crate::exit::{CliError, CliResult};

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Plan file written by `triquint plan`.
    pub plan: std::path::PathBuf,
}

pub fn run(_args: &SimulateArgs) -> CliResult {
    Err(CliError::device(
        "the in-process simulation is not built yet",
    ))
}
