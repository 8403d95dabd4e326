//! `triquint report PLAN.json [--plot DIR] [--json]`: tables and plots of a plan.

use clap::Args;

use crate::cli::load_plan;
use crate::exit::{CliError, CliResult, write_atomic};
use crate::report::{ReportError, plan_stats, plots, tables};

#[derive(Args, Debug)]
pub struct ReportArgs {
    /// Plan file written by `triquint plan`.
    pub plan: std::path::PathBuf,
    /// Directory for SVG plots (created if missing).
    #[arg(long, value_name = "DIR")]
    pub plot: Option<std::path::PathBuf>,
    /// Print the statistics as JSON instead of tables.
    #[arg(long)]
    pub json: bool,
}

pub fn run(args: &ReportArgs) -> CliResult {
    let plan = load_plan(&args.plan)?;
    let bad = |e: ReportError| CliError::bad_input(format!("{}: {e}", args.plan.display()));
    let stats = plan_stats(&plan).map_err(|e| bad(e.into()))?;
    // Plots first, so a failure leaves no half-printed report.
    let mut written = Vec::new();
    if let Some(dir) = &args.plot {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::bad_input(format!("{}: {e}", dir.display())))?;
        for (name, svg) in plots::plots(&plan, &stats).map_err(bad)? {
            let path = dir.join(name);
            write_atomic(&path, svg.as_bytes())?;
            written.push(path);
        }
    }
    if args.json {
        let text = serde_json::to_string_pretty(&stats)
            .map_err(|e| CliError::bad_input(format!("statistics to JSON: {e}")))?;
        println!("{text}");
    } else {
        println!("{}", tables::intervals_table(&plan, &stats));
        println!("{}", tables::joint_table(&plan, &stats));
        print!("{}", tables::recorded_check(&plan, &stats));
    }
    for path in written {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
