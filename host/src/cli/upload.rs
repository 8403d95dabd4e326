//! `triquint upload PLAN.json --iface IFACE`: runs a plan on real drives (or
//! `triquint-sim`) over SocketCAN (`ops::run`), with a progress bar and keys
//! on a terminal, then prints each node's final state and fault code.

use std::path::PathBuf;

use clap::Args;
use triquint_cli_common::outln;
use triquint_shared::machine::Machine;
use triquint_shared::plan::Plan;

use crate::cli::load_plan;
use crate::cli::terminal_watch::TerminalWatch;
use crate::exit::{CliError, CliResult, Status};
use crate::machine_arg::{plan_for_machine, verified};
use crate::ops::bus::{BusArgs, check_bus_args};
use crate::ops::joints::reported_joints;
use crate::ops::plan_move::plan_move;
use crate::ops::run::{UploadSummary, run_plan};

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

/// Prints the summary; exit 0 only when every node completed without a fault.
pub fn report(s: &UploadSummary, bus: &BusArgs, json: bool) -> CliResult {
    if json {
        outln!(
            "{}",
            serde_json::to_string(s).map_err(|e| CliError::device(e.to_string()))?
        )?;
    } else {
        outln!(
            "{} segments over {} ({}): {} frames ({} segment frames, {} retransmissions); all acknowledged after {:.3} s, done after {:.3} s",
            s.segments,
            bus.iface,
            if bus.fd { "CAN-FD" } else { "classic CAN" },
            s.frames_sent,
            s.segment_frames,
            s.retransmits,
            s.upload_s,
            s.total_s
        )?;
        for n in &s.nodes {
            outln!(
                "node {}: {}, fault {} ({})",
                n.node,
                n.state,
                n.fault_name,
                n.fault
            )?;
        }
    }
    if s.completed && s.faults.is_empty() {
        return Ok(());
    }
    if s.stopped && s.faults.is_empty() {
        return Err(CliError::new(
            Status::Cancelled,
            "stopped on request before the plan's end: at rest on its path, every drive Idle",
        ));
    }
    Err(CliError::motion_fault(match s.faults.first() {
        Some(f) => format!("node {} faulted: {} ({})", f.node, f.name, f.code),
        None => "the plan did not complete".to_string(),
    }))
}

pub fn run(args: &UploadArgs, machine: &Machine) -> CliResult {
    let plan = load_plan(&args.plan)?;
    let bus = &args.bus.for_machine(machine);
    check_bus_args(bus)?;
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
                return report(&s, bus, args.json);
            }
        }
    }
    let summary = run_plan(&plan, bus, machine, args.clear, &mut watch)?;
    drop(watch);
    report(&summary, bus, args.json)
}

/// The minimum-time move (the planner of `move-to`) from where the drives
/// report the platform to `start` (m); `None` if already there.
fn approach_plan(machine: &Machine, bus: &BusArgs, start: [f64; 3]) -> CliResult<Option<Plan>> {
    let q0 = reported_joints(machine, bus)?;
    plan_move(machine, q0, start.into())
}
