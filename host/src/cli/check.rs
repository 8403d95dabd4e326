//! `triquint check PLAN.json`: independent re-verification of a plan.

use std::path::PathBuf;

use clap::Args;
use triquint_cli_common::outln;
use triquint_firmware::QUEUE_CAPACITY;
use triquint_link::DriveConfigs;
use triquint_shared::plan::Plan;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::streaming::{Shortfall, StreamRule};

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
    let stream = streamability(&plan);
    if let Some(s) = &stream {
        outln!(
            "{:<42} {:>14.6e} {:>14.6e}  {}",
            format!("streaming: segments {}–{} (s)", s.first, s.last),
            s.run_us as f64 * 1e-6,
            s.need_us as f64 * 1e-6,
            if s.run_us >= s.need_us {
                "ok"
            } else {
                "VIOLATED"
            }
        )?;
    }
    let unstreamable = stream.is_some_and(|s| s.run_us < s.need_us);
    let failed = rows.iter().filter(|r| !r.ok).count() + usize::from(unstreamable);
    if failed > 0 {
        return Err(CliError::violation(format!(
            "{}: {failed} of {} checks failed",
            args.plan.display(),
            rows.len() + usize::from(stream.is_some())
        )));
    }
    outln!(
        "all {} checks hold",
        rows.len() + usize::from(stream.is_some())
    )?;
    Ok(())
}

/// The shortest run of segments the drives' queues hold ahead, against what
/// they need at σ = 1 with the default drive settings and this firmware's
/// queue (docs/protocol.md, Streamability); `None` when the plan fits the
/// queue whole or has no configuration.
fn streamability(plan: &Plan) -> Option<Shortfall> {
    let s = DriveSettings::default();
    let configs = DriveConfigs::for_plan(plan, &s).ok()?;
    let rule = StreamRule::new(
        QUEUE_CAPACITY,
        configs.stop_time_s,
        s.underrun_margin,
        s.heartbeat_period,
    );
    let d: Vec<u32> = plan
        .wire_segments()
        .ok()?
        .iter()
        .map(|w| w.duration_us)
        .collect();
    rule.shortest_run(&d)
}
