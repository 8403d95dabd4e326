//! `triquint plan JOB.toml -o PLAN.json [--plot DIR]`: plans a job.

use std::path::PathBuf;

use clap::Args;

use crate::exit::{CliError, CliResult, write_atomic};
use crate::job::Job;
use crate::planner::{plan, search::SearchOptions};

#[derive(Args, Debug)]
pub struct PlanArgs {
    /// Job file (TOML): objective, robot, limits, path.
    pub job: PathBuf,
    /// Where to write the plan (JSON).
    #[arg(short, long, value_name = "PLAN.json")]
    pub output: PathBuf,
    /// Also write the report's SVG plots into DIR.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Starting interval sets of the global search.
    #[arg(long, default_value_t = SearchOptions::default().starts)]
    pub starts: usize,
    /// Seed of the random starts (same seed, same plan).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// No progress bar or summary.
    #[arg(long, short)]
    pub quiet: bool,
}

pub fn run(args: &PlanArgs) -> CliResult {
    let job = Job::load(&args.job)?;
    let opts = SearchOptions {
        starts: args.starts.max(1),
        seed: args.seed,
        progress: !args.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr()),
        ..SearchOptions::default()
    };
    let plan = plan(&job, &opts)?;
    let json = serde_json::to_string_pretty(&plan)
        .map_err(|e| CliError::bad_input(format!("cannot encode plan: {e}")))?;
    if let Some(dir) = &args.plot {
        write_plots(&plan, dir)?;
    }
    write_atomic(&args.output, format!("{json}\n").as_bytes())?;
    if !args.quiet {
        let m = &plan.max_abs;
        let max = |v: [f64; 3]| v.iter().fold(0.0f64, |a, b| a.max(*b));
        eprintln!(
            "planned {} segments, T = {:.6} s: max |jerk| {:.6} m/s³, |a| {:.4} m/s², |v| {:.4} m/s, |τ| {:.4} N·m ({} starts, {} LP solves, {:.3} s) → {}",
            plan.segments.len(),
            plan.total_time_s,
            max(m.jerk),
            max(m.acceleration),
            max(m.velocity),
            max(m.torque),
            plan.solver.starts,
            plan.solver.lp_solves,
            plan.solver.seconds,
            args.output.display()
        );
    }
    Ok(())
}

/// Writes the report's SVG plots of a plan into `dir`.
fn write_plots(plan: &triquint_shared::plan::Plan, dir: &std::path::Path) -> CliResult {
    let bad = |e: crate::report::ReportError| CliError::bad_input(format!("plots: {e}"));
    let stats = crate::report::plan_stats(plan).map_err(bad)?;
    for (name, svg) in crate::report::plots::plots(plan, &stats).map_err(bad)? {
        write_atomic(&dir.join(name), svg.as_bytes())?;
    }
    Ok(())
}
