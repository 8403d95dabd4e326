//! `triquint report PLAN.json [--plot DIR] [--json]`: tables and plots of a plan.

use clap::Args;

use crate::cli::{check_plot_folder, load_plan};
use triquint_cli_common::output::write_outputs;
use triquint_cli_common::{out, outln};

use crate::exit::{CliError, CliResult};
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
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

pub fn run(args: &ReportArgs) -> CliResult {
    check_plot_folder(args.plot.as_deref())?;
    let plan = load_plan(&args.plan)?;
    args.machine.check_plan(&plan, &args.plan)?;
    let bad = |e: ReportError| CliError::bad_input(format!("{}: {e}", args.plan.display()));
    let stats = plan_stats(&plan).map_err(|e| bad(e.into()))?;
    // Plots first, so a failure leaves no half-printed report; all of them
    // or none.
    let mut written = Vec::new();
    if let Some(dir) = &args.plot {
        let plots: Vec<_> = plots::plots(&plan, &stats)
            .map_err(bad)?
            .into_iter()
            .map(|(name, svg)| (dir.join(name), svg))
            .collect();
        let files: Vec<_> = plots
            .iter()
            .map(|(p, svg)| (p.as_path(), svg.as_bytes()))
            .collect();
        write_outputs(&files, &[&args.plan])?;
        written = plots.into_iter().map(|(p, _)| p).collect();
    }
    if args.json {
        let text = serde_json::to_string_pretty(&stats)
            .map_err(|e| CliError::bad_input(format!("statistics to JSON: {e}")))?;
        outln!("{text}")?;
    } else {
        outln!("{}", tables::intervals_table(&plan, &stats))?;
        outln!("{}", tables::joint_table(&plan, &stats))?;
        out!("{}", tables::recorded_check(&plan, &stats))?;
        let d = &stats.path_deviation;
        outln!(
            "path: at most {:.3} mm from the straight segments between via-points \
             ({:.3} mm sampled every {:.2} ms, the largest at t = {:.4} s)",
            d.bound_m * 1e3,
            d.max_m * 1e3,
            d.step_s * 1e3,
            d.at_s
        )?;
        if let Some(limit) = d.limit_m {
            outln!(
                "path bound: {:.3} mm (the job's path.max_deviation_mm, which `check` proves)",
                limit * 1e3
            )?;
        }
    }
    for path in written {
        triquint_cli_common::errln!("wrote {}", path.display());
    }
    Ok(())
}
