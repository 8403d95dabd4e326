//! `triquint report PLAN.json [--plot DIR]`: tables and plots of a plan.

use clap::Args;

use crate::exit::{CliError, CliResult};

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Plan file written by `triquint plan`.
    pub plan: std::path::PathBuf,
    /// Directory for SVG plots.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<std::path::PathBuf>,
}

pub fn run(_args: &ReportArgs) -> CliResult {
    Err(CliError::bad_input("report is not built yet"))
}
