//! `triquint check PLAN.json`: independent re-verification of a plan.

use std::path::PathBuf;

use clap::Args;
use triquint_cli_common::outln;
use triquint_shared::plan::Plan;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::streaming::{QUEUE_CAPACITY, Shortfall, StreamRule};

use crate::cli::load_plan;
use crate::exit::{CliError, CliResult};

#[derive(Args, Debug)]
pub struct CheckArgs {
    /// Plan file written by `triquint plan`.
    pub plan: PathBuf,
    /// Print the checks as JSON: `{"ok", "checks": [{"check", "value", "bound", "ok"}]}`.
    #[arg(long)]
    pub json: bool,
    /// Also prove a bound on the platform's distance from the straight
    /// segments between the via-points: the certified bound against it (a
    /// plan of a job with `path.max_deviation_mm` records its own, which
    /// `check` proves without this).
    #[arg(long, value_name = "MM")]
    pub max_deviation_mm: Option<f64>,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

/// One line of the table: what, the value found, its bound, whether it holds.
struct Row {
    what: String,
    value: f64,
    bound: f64,
    ok: bool,
}

pub fn run(args: &CheckArgs) -> CliResult {
    let plan = load_plan(&args.plan)?;
    args.machine.check_plan(&plan, &args.plan)?;
    let rows = triquint_planner::check(&plan).map_err(|e| {
        CliError::bad_input(format!("{}: not a valid plan: {e}", args.plan.display()))
    })?;
    let mut table: Vec<Row> = rows
        .into_iter()
        .map(|r| Row {
            what: r.what,
            value: r.value,
            bound: r.bound,
            ok: r.ok,
        })
        .collect();
    if let Some(mm) = args.max_deviation_mm {
        if !(mm.is_finite() && mm > 0.0) {
            return Err(CliError::bad_input(format!(
                "--max-deviation-mm {mm}: a bound is a positive number of millimetres"
            )));
        }
        let r = triquint_planner::check_deviation(&plan, mm * 1e-3).map_err(|e| {
            CliError::bad_input(format!("{}: not a valid plan: {e}", args.plan.display()))
        })?;
        table.push(Row {
            what: r.what,
            value: r.value,
            bound: r.bound,
            ok: r.ok,
        });
    }
    if let Some(s) = streamability(&plan, &args.machine.load()?.drive_settings()) {
        table.push(Row {
            what: format!("streaming: segments {}–{} (s)", s.first, s.last),
            value: s.run_us as f64 * 1e-6,
            bound: s.need_us as f64 * 1e-6,
            ok: s.run_us >= s.need_us,
        });
    }
    let failed = table.iter().filter(|r| !r.ok).count();
    if args.json {
        let checks: Vec<_> = table
            .iter()
            .map(|r| serde_json::json!({"check": r.what, "value": r.value, "bound": r.bound, "ok": r.ok}))
            .collect();
        outln!(
            "{:#}",
            serde_json::json!({"plan": args.plan.display().to_string(), "ok": failed == 0, "checks": checks})
        )?;
    } else {
        outln!("{:<42} {:>14} {:>14}  result", "check", "value", "bound")?;
        for r in &table {
            outln!(
                "{:<42} {:>14.6e} {:>14.6e}  {}",
                r.what,
                r.value,
                r.bound,
                if r.ok { "ok" } else { "VIOLATED" }
            )?;
        }
    }
    if failed > 0 {
        return Err(CliError::violation(format!(
            "{}: {failed} of {} checks failed",
            args.plan.display(),
            table.len()
        )));
    }
    if !args.json {
        outln!("all {} checks hold", table.len())?;
    }
    Ok(())
}

/// The shortest run of segments the drives' queues hold ahead, against what
/// they need at σ = 1 with the machine's drive settings (its override
/// limit sizes the stop ramp) and the drives' queue (docs/protocol.md,
/// Streamability); `None` when the plan fits the queue whole or has no
/// motion.
fn streamability(plan: &Plan, settings: &DriveSettings) -> Option<Shortfall> {
    let rule = StreamRule::for_plan(plan, settings, QUEUE_CAPACITY)?;
    let d: Vec<u32> = plan
        .wire_segments()
        .ok()?
        .iter()
        .map(|w| w.duration_us)
        .collect();
    rule.shortest_run(&d)
}
