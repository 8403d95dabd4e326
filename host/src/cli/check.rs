//! `triquint check PLAN.json`: independent re-verification of a plan.

use std::path::PathBuf;

use clap::Args;
use triquint_cli_common::outln;

use crate::cli::load_plan;
use crate::exit::{CliError, CliResult};

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Plan file written by `triquint plan`.
    pub plan: PathBuf,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

pub fn run(args: &CheckArgs) -> CliResult {
    let plan = load_plan(&args.plan)?;
    args.machine.check_plan(&plan, &args.plan)?;
    let rows = triquint_planner::check(&plan).map_err(|e| {
        CliError::bad_input(format!("{}: not a valid plan: {e}", args.plan.display()))
    })?;
    outln!("{:<42} {:>14} {:>14}  result", "check", "value", "bound")?;
    for r in &rows {
        outln!(
            "{:<42} {:>14.6e} {:>14.6e}  {}",
            r.what,
            r.value,
            r.bound,
            if r.ok { "ok" } else { "VIOLATED" }
        )?;
    }
    let failed = rows.iter().filter(|r| !r.ok).count();
    if failed > 0 {
        return Err(CliError::violation(format!(
            "{}: {failed} of {} checks failed",
            args.plan.display(),
            rows.len()
        )));
    }
    outln!("all {} checks hold", rows.len())?;
    Ok(())
}
