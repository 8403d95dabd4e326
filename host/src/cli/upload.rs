//! `triquint upload PLAN.json --iface IFACE`: runs a plan on real drives (or
//! `triquint-sim`) over SocketCAN: heartbeat check, configuration, segment
//! streaming with flow control, time sync, arm, common start, then each
//! node's final state and fault code.

use std::path::PathBuf;
use std::time::{Duration, Instant};

use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use serde::Serialize;
use triquint_cli_common::outln;
use triquint_shared::machine::Machine;
use triquint_shared::plan::Plan;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{FaultCode, State};

use triquint_link::{DriveConfigs, Outcome, Session, SessionOptions, open_host};

use crate::cli::keys::Keys;
use crate::cli::load_plan;
use crate::exit::{CliError, CliResult, Status};
use crate::machine_arg::{plan_for_machine, verified};
use crate::ops::bus::{BusArgs, check_bus_args, upload_error};
use crate::ops::joints::reported_joints;
use crate::ops::plan_move::plan_move;

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

/// What an upload did.
#[derive(Clone, Debug, Serialize)]
pub struct UploadSummary {
    pub completed: bool,
    /// Stopped on request (a stop key, `triquint stop`): at rest on the path.
    pub stopped: bool,
    /// The override cap the drives were configured with (σ).
    pub override_cap: f64,
    pub segments: usize,
    pub frames_sent: u64,
    pub segment_frames: u64,
    pub retransmits: u64,
    /// From the first frame until every segment was acknowledged by every node (s).
    pub upload_s: f64,
    /// From the first frame until every node reported rest (s).
    pub total_s: f64,
    pub nodes: Vec<NodeSummary>,
    pub faults: Vec<FaultSummary>,
}

#[derive(Clone, Debug, Serialize)]
pub struct NodeSummary {
    pub node: u8,
    pub state: &'static str,
    pub fault: u8,
    pub fault_name: &'static str,
}

#[derive(Clone, Debug, Serialize)]
pub struct FaultSummary {
    pub node: u8,
    pub code: u8,
    pub name: &'static str,
}

/// The progress line's message: phase, hold, override, stop, keys.
fn progress_message(p: &triquint_link::Progress, keys: bool) -> String {
    let mut m = p.phase.to_string();
    if p.started {
        m += &format!(
            ", plan time {:.1}/{:.1} s",
            p.plan_time_us as f64 * 1e-6,
            p.plan_end_us as f64 * 1e-6
        );
    }
    if p.stopped {
        m += ", STOPPING";
    } else if p.held {
        m += ", HELD";
    }
    if let Some(pm) = p.override_permille.filter(|pm| *pm != 1000) {
        m += &format!(", override {} %", crate::ops::feed::percent(pm));
    }
    if keys {
        m += &format!("  [{}]", Keys::help());
    }
    m
}

/// Uploads and runs `plan` over `bus`, with a progress bar on a terminal;
/// `keys`: hold, resume, override and stop from the keyboard, its
/// override also sent before the start.
pub fn run_plan(
    plan: &Plan,
    bus: &BusArgs,
    machine: &Machine,
    clear: bool,
    mut keys: Option<&mut Keys>,
) -> CliResult<UploadSummary> {
    check_bus_args(bus)?;
    let settings = DriveSettings {
        control_rate: bus.rate(),
        node_ids: bus.ids()?,
        ..machine.drive_settings()
    };
    let configs = DriveConfigs::for_plan(plan, &settings).map_err(CliError::bad_input)?;
    let override_cap = configs.override_cap;
    let cap_pm = configs.override_cap_permille();
    let configs = configs.nodes;
    let opts = SessionOptions {
        fd: bus.fd,
        response_timeout_us: (bus.timeout * 1e6) as u64,
        clear_faults: clear,
        // The override chosen by key (in an approach before this plan).
        feed_override: keys
            .as_ref()
            .map(|k| k.override_pm)
            .filter(|pm| *pm != 1000),
        ..SessionOptions::default()
    };
    let mut session = Session::new(plan, configs, opts).map_err(|e| upload_error(e, bus))?;
    let mut port = open_host(&bus.iface, bus.fd).map_err(CliError::device)?;
    let bar = ProgressBar::new(plan.segments.len() as u64);
    bar.set_style(
        ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {bar:30} {pos}/{len} segments  {msg}",
        )
        .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    let t0 = Instant::now();
    let mut acked_at: Option<f64> = None;
    let outcome: Outcome = loop {
        if let Some(k) = keys.as_deref_mut() {
            // `+`/`-` step from the override the drives hold (one set before
            // the upload is reported in their answer to Arm).
            k.learn(session.progress().override_permille);
            for f in k.poll(cap_pm) {
                session.feed(f);
            }
        }
        let polled = session.poll(&mut port);
        let p = session.progress();
        bar.set_position(p.segments_acked as u64);
        bar.set_message(progress_message(&p, keys.is_some()));
        if acked_at.is_none() && p.segments_acked == p.segments {
            acked_at = Some(t0.elapsed().as_secs_f64());
        }
        match polled {
            Ok(Some(o)) => break o,
            Ok(None) => {}
            Err(e) => {
                bar.abandon();
                return Err(upload_error(e, bus));
            }
        }
        // 1 ms: the window (4 segments) stays full and time stamps come from
        // the kernel, so polling faster only burns CPU.
        std::thread::sleep(Duration::from_millis(1));
    };
    bar.finish_and_clear();
    let total_s = t0.elapsed().as_secs_f64();
    let nodes = session
        .node_states()
        .iter()
        .zip(session.nodes())
        .map(|((state, fault), v)| NodeSummary {
            node: v.id,
            state: state.map_or("silent", State::name),
            fault: *fault,
            fault_name: FaultCode::from_u8(*fault).map_or("unknown", FaultCode::name),
        })
        .collect();
    Ok(UploadSummary {
        completed: outcome.completed,
        stopped: outcome.stopped,
        override_cap,
        segments: plan.segments.len(),
        frames_sent: outcome.frames_sent,
        segment_frames: outcome.segment_frames_sent,
        retransmits: outcome.retransmits,
        upload_s: acked_at.unwrap_or(total_s),
        total_s,
        nodes,
        faults: outcome
            .faults
            .iter()
            .map(|f| FaultSummary {
                node: f.node,
                code: f.code as u8,
                name: f.code.name(),
            })
            .collect(),
    })
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
    let mut keys = Keys::open(1000);
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
            let s = run_plan(&p, bus, machine, args.clear, keys.as_mut())?;
            if !(s.completed && s.faults.is_empty()) {
                triquint_cli_common::errln!("the approach did not complete; the plan is not run");
                return report(&s, bus, args.json);
            }
        }
    }
    let summary = run_plan(&plan, bus, machine, args.clear, keys.as_mut())?;
    drop(keys);
    report(&summary, bus, args.json)
}

/// The minimum-time move (the planner of `move-to`) from where the drives
/// report the platform to `start` (m); `None` if already there.
fn approach_plan(machine: &Machine, bus: &BusArgs, start: [f64; 3]) -> CliResult<Option<Plan>> {
    let q0 = reported_joints(machine, bus)?;
    plan_move(machine, q0, start.into())
}
