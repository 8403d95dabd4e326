//! `triquint upload PLAN.json --iface IFACE`: runs a plan on real drives (or
//! `triquint-sim`) over SocketCAN (`ops::run`), with a progress bar and keys
//! on a terminal, then prints each node's final state and fault code.

use std::path::PathBuf;

use clap::Args;
use triquint_shared::machine::Machine;
use triquint_shared::plan::Plan;

use crate::cli::bus_args::BusArgs;
use crate::cli::load_plan;
use crate::cli::terminal_watch::TerminalWatch;
use crate::cli::upload_summary;
use crate::exit::{CliError, CliResult};
use crate::machine_arg::{plan_for_machine, verified};
use crate::ops::bus::Bus;
use crate::ops::joints::reported_joints;
use crate::ops::plan_move::plan_move;
use crate::ops::run::run_plan;

#[derive(Args, Debug)]
pub struct UploadArgs {
    /// Plan file written by `triquint plan`.
    pub plan: PathBuf,
    #[command(flatten)]
    pub bus: BusArgs,
    /// Print the summary as JSON.
    #[arg(long)]
    pub json: bool,
    /// Clear faulted drives first (without it, an upload to a faulted
    /// drive is refused: see `triquint status`, `triquint clear`).
    #[arg(long)]
    pub clear: bool,
    /// First a minimum-time move (as `move-to`) from where the drives
    /// report the platform to the plan's start, then the plan.
    #[arg(long)]
    pub approach: bool,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

pub fn run(args: &UploadArgs, machine: &Machine) -> CliResult {
    let plan = load_plan(&args.plan)?;
    let bus = &args.bus.bus(machine)?;
    plan_for_machine(&plan, &args.plan, machine, &args.machine.shown())?;
    verified(&plan, &args.plan)?;
    let mut watch = TerminalWatch::open();
    if args.approach {
        let start = plan.via_points_m.first().copied().ok_or_else(|| {
            CliError::bad_input(format!(
                "{}: the plan has no via-points",
                args.plan.display()
            ))
        })?;
        let approach = approach_plan(machine, bus, start)?;
        if let Some(p) = approach {
            triquint_cli_common::errln!(
                "approach: {} segments, {:.3} s, to the plan's start",
                p.segments.len(),
                p.total_time_s
            );
            let s = run_plan(&p, bus, machine, args.clear, &mut watch)?;
            if !(s.completed && s.faults.is_empty()) {
                triquint_cli_common::errln!("the approach did not complete; the plan is not run");
                return upload_summary::show(&s, bus, args.json);
            }
        }
    }
    let summary = run_plan(&plan, bus, machine, args.clear, &mut watch)?;
    drop(watch);
    upload_summary::show(&summary, bus, args.json)
}

/// The minimum-time move (the planner of `move-to`) from where the drives
/// report the platform to `start` (m); `None` if already there.
fn approach_plan(machine: &Machine, bus: &Bus, start: [f64; 3]) -> CliResult<Option<Plan>> {
    let q0 = reported_joints(machine, bus)?;
    Ok(plan_move(machine, q0, start.into())?)
}
