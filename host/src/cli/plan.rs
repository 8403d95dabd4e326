//! `triquint plan JOB.toml -o PLAN.json [--plot DIR] [--shaper TYPE:HZ[:ζ]]`:
//! plans a job.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use triquint_planner::shaping::{DEFAULT_DAMPING, Impulses, Shaper, ShaperSpec};
use triquint_planner::{Control, Job, Options, Progress, Stage, plan_with};

use triquint_cli_common::output::{check_target, output_error, write_outputs};

use crate::exit::{CliError, CliResult, plan_error};

pub use triquint_planner::MAX_STARTS;

/// Parses `--starts`: bad input (exit 2) outside 1 to [`MAX_STARTS`].
fn parse_starts(text: &str) -> CliResult<usize> {
    match text.parse::<usize>() {
        Ok(n) if (1..=MAX_STARTS).contains(&n) => Ok(n),
        _ => Err(CliError::bad_input(format!(
            "--starts `{}`: must be a whole number 1 to {MAX_STARTS}",
            crate::cli::shortened(text)
        ))),
    }
}

/// Parses `--shaper TYPE:HZ[:DAMPING]` (`none` for no shaper): bad input
/// (exit 2) for an unknown type or a frequency or damping out of range.
fn parse_shaper(text: &str) -> CliResult<Option<ShaperSpec>> {
    let bad = |why: String| {
        CliError::bad_input(format!("--shaper `{}`: {why}", crate::cli::shortened(text)))
    };
    if text.eq_ignore_ascii_case("none") {
        return Ok(None);
    }
    let mut parts = text.split(':');
    let shaper: Shaper = parts
        .next()
        .unwrap_or_default()
        .parse()
        .map_err(|e: triquint_planner::shaping::UnknownShaper| bad(e.to_string()))?;
    let number = |part: Option<&str>, what: &str| -> CliResult<Option<f64>> {
        part.map(|p| {
            p.trim()
                .parse::<f64>()
                .map_err(|_| bad(format!("the {what} `{p}` is not a number")))
        })
        .transpose()
    };
    let frequency_hz = number(parts.next(), "frequency")?
        .ok_or_else(|| bad("give TYPE:HZ[:DAMPING], e.g. ei:25.5:0.05".into()))?;
    let damping = number(parts.next(), "damping")?.unwrap_or(DEFAULT_DAMPING);
    if parts.next().is_some() {
        return Err(bad("give TYPE:HZ[:DAMPING], e.g. ei:25.5:0.05".into()));
    }
    let spec = ShaperSpec {
        shaper,
        frequency_hz,
        damping,
    };
    Impulses::for_spec(&spec).map_err(|e| bad(e.to_string()))?;
    Ok(Some(spec))
}

#[derive(Args, Debug)]
pub struct PlanArgs {
    /// Job file (TOML): objective, robot, limits, path.
    pub job: PathBuf,
    /// Where to write the plan (JSON); `-` for standard output.
    #[arg(short, long, value_name = "PLAN.json")]
    pub output: PathBuf,
    /// Also write the report's SVG plots into DIR.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    /// Starting interval sets of the global search (1 to 1000).
    #[arg(long, default_value_t = Options::default().starts.to_string())]
    pub starts: String,
    /// Seed of the random starts (same seed, same plan).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// No progress bar or summary.
    #[arg(long, short)]
    pub quiet: bool,
    /// Print the summary as JSON on standard output (not with `-o -`).
    #[arg(long)]
    pub json: bool,
    /// Shape the plan: TYPE (zv, mzv, zvd, ei, 2hump_ei), the mode's
    /// frequency and damping ratio (default 0.1), e.g. `ei:25.5:0.05`;
    /// `none` drops the job's `[shaper]`.
    #[arg(long, value_name = "TYPE:HZ[:DAMPING]")]
    pub shaper: Option<String>,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

/// The search's progress on stderr, and Ctrl-C as cancellation.
struct Watcher {
    bar: ProgressBar,
    interrupted: Arc<AtomicBool>,
}

impl Watcher {
    fn new(show: bool) -> Self {
        let interrupted = Arc::new(AtomicBool::new(false));
        for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
            // Without the handler Ctrl-C still ends the process, just abruptly.
            let _ = signal_hook::flag::register(sig, Arc::clone(&interrupted));
        }
        let bar = if show {
            let bar = ProgressBar::new_spinner();
            if let Ok(style) = ProgressStyle::with_template("{spinner} {elapsed:>4} {msg}") {
                bar.set_style(style);
            }
            bar
        } else {
            ProgressBar::hidden()
        };
        Self { bar, interrupted }
    }

    fn progress(&self, p: &Progress) -> Control {
        let stage = match p.stage {
            Stage::Searching => "searching",
            Stage::LimitsBind => "limits bind",
            Stage::MinTime => "shortest time",
            _ => "finishing",
        };
        let best = p
            .best_max_jerk
            .map_or(String::new(), |j| format!(", best max jerk {j:.6} m/s³"));
        self.bar
            .set_message(format!("{stage}: {} LP solves{best}", p.lp_solves));
        self.bar.tick();
        if self.interrupted.load(Ordering::Relaxed) {
            Control::Cancel
        } else {
            Control::Continue
        }
    }
}

pub fn run(args: &PlanArgs) -> CliResult {
    let starts = parse_starts(&args.starts)?;
    let shaper = args.shaper.as_deref().map(parse_shaper).transpose()?;
    crate::cli::check_plot_folder(args.plot.as_deref())?;
    let machine = match &args.machine.file {
        Some(_) => Some(args.machine.load()?),
        None => None,
    };
    let (job, inputs) = Job::load_for(&args.job, machine.as_ref()).map_err(plan_error)?;
    let job = match shaper {
        Some(spec) => job.to_builder().shaper(spec).build().map_err(plan_error)?,
        None => job,
    };
    let inputs: Vec<&Path> = inputs.iter().map(PathBuf::as_path).collect();
    let to_stdout = args.output.as_os_str() == "-";
    if to_stdout && args.json {
        return Err(CliError::bad_input(
            "--json: standard output already holds the plan (-o -)".to_string(),
        ));
    }
    // Refused outputs before the search, so they cost nothing.
    if !to_stdout {
        check_target(&args.output, &inputs).map_err(|e| output_error(&args.output, &e))?;
    }
    if let Some(dir) = &args.plot
        && dir.exists()
        && !dir.is_dir()
    {
        return Err(CliError::bad_input(format!(
            "--plot {}: not a folder",
            dir.display()
        )));
    }
    let opts = Options {
        starts,
        seed: args.seed,
        ..Options::default()
    };
    let watcher = Watcher::new(!args.quiet && std::io::IsTerminal::is_terminal(&std::io::stderr()));
    let result = plan_with(&job, &opts, &mut |p: &Progress| watcher.progress(p));
    watcher.bar.finish_and_clear();
    let plan = result.map_err(plan_error)?;
    let json = serde_json::to_string_pretty(&plan)
        .map_err(|e| CliError::bad_input(format!("cannot encode plan: {e}")))?
        + "\n";
    let plots = match &args.plot {
        Some(dir) => plots(&plan, dir)?,
        None => Vec::new(),
    };
    // The plan and the plots are renamed into place together, after all
    // are written: a failure leaves none of them.
    let mut files: Vec<(&Path, &[u8])> = plots
        .iter()
        .map(|(p, svg)| (p.as_path(), svg.as_bytes()))
        .collect();
    if !to_stdout {
        files.insert(0, (args.output.as_path(), json.as_bytes()));
    }
    write_outputs(&files, &inputs)?;
    if to_stdout {
        triquint_cli_common::out!("{json}")?;
    }
    if args.json {
        let summary = serde_json::json!({
            "plan": args.output.display().to_string(),
            "segments": plan.segments.len(),
            "total_time_s": plan.total_time_s,
            "max_abs": &plan.max_abs,
            "starts": plan.solver.starts,
            "lp_solves": plan.solver.lp_solves,
            "seconds": plan.solver.seconds,
            "shaper": plan.shaping.as_ref().map(|s| s.shaper),
            "retimed": plan.shaping.as_ref().and_then(|s| s.unshaped.retimed),
        });
        triquint_cli_common::outln!("{summary:#}")?;
    } else if !args.quiet {
        let m = &plan.max_abs;
        let max = |v: [f64; 3]| v.iter().fold(0.0f64, |a, b| a.max(*b));
        triquint_cli_common::errln!(
            "planned {} segments, T = {:.6} s: max |jerk| {:.6} m/s³, |a| {:.4} m/s², |v| {:.4} m/s, |τ| {:.4} N·m{} ({} starts, {} LP solves, {:.3} s) → {}",
            plan.segments.len(),
            plan.total_time_s,
            max(m.jerk),
            max(m.acceleration),
            max(m.velocity),
            max(m.torque),
            plan.shaping.as_ref().map_or(String::new(), |s| format!(
                ", shaped {} {} Hz ζ {} (+{:.6} s){}",
                s.shaper.shaper,
                s.shaper.frequency_hz,
                s.shaper.damping,
                plan.total_time_s - s.unshaped.total_time_s,
                s.unshaped.retimed.map_or(String::new(), |r| format!(
                    ", the plan slowed ×{r:.4} to {:.6} s so that it streams",
                    s.unshaped.total_time_s
                ))
            )),
            plan.solver.starts,
            plan.solver.lp_solves,
            plan.solver.seconds,
            if to_stdout {
                "standard output".to_string()
            } else {
                args.output.display().to_string()
            }
        );
    }
    Ok(())
}

/// The report's SVG plots of a plan, each with its path in `dir`.
fn plots(plan: &triquint_shared::plan::Plan, dir: &Path) -> CliResult<Vec<(PathBuf, String)>> {
    let bad = |e: crate::report::ReportError| CliError::bad_input(format!("plots: {e}"));
    let stats = crate::report::plan_stats(plan).map_err(|e| bad(e.into()))?;
    Ok(crate::report::plots::plots(plan, &stats)
        .map_err(bad)?
        .into_iter()
        .map(|(name, svg)| (dir.join(name), svg))
        .collect())
}
