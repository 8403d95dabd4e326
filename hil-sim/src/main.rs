//! `triquint-sim`: three virtual motor controllers (the real firmware core)
//! and the plant, on a SocketCAN interface, in real time. Stops cleanly on
//! SIGINT/SIGTERM and writes the report (the fields of `triquint simulate
//! --json`, for the last plan run, plus every run and the pacing figures).
//! Exit status: 0 stopped by a signal, 2 bad input, 4 interface or bus
//! failure, 5 the machine left its workspace.
//!
//! `triquint-sim proxy` bridges two interfaces through the fault model
//! (`cli/proxy.rs`).

mod cli;

use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use clap::{Parser, Subcommand};
use serde::Serialize;
use triquint_cli_common::machine_file::load_machine;
use triquint_cli_common::parse::{check_rate, parse_nodes, parse_triple};
use triquint_cli_common::{CliError, CliResult, main_exit};
use triquint_shared::kinematics::Pose;
use triquint_sim::plant_model::PlantKind;
use triquint_sim::realtime::{self, RealtimeConfig, RealtimeError, RealtimeReport};
use triquint_sim::report::RunReport;
use triquint_sim::sim::SwitchMode;

#[derive(Parser, Debug)]
#[command(
    name = "triquint-sim",
    version,
    about,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    machine: Args,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Bridge two CAN interfaces both ways through seeded faults.
    Proxy(cli::proxy::ProxyArgs),
}

#[derive(clap::Args, Debug)]
struct Args {
    /// SocketCAN interface (vcan0, can0).
    #[arg(long, value_name = "IFACE", required = true)]
    iface: Option<String>,
    /// Node ids (1–15) of the drives of axes 1, 2, 3 in order; fewer than
    /// three leave the last axes without a drive (a silent node) [default:
    /// the machine file's `axis.N.node_id`].
    #[arg(long, value_name = "A,B,C")]
    nodes: Option<String>,
    /// Power on with an unknown (seeded) encoder offset on every axis:
    /// positions mean nothing until `triquint home`.
    #[arg(long)]
    unhomed: bool,
    /// Seed of the encoder offsets of --unhomed.
    #[arg(long, default_value_t = 1, value_name = "N")]
    seed: u64,
    /// Axis (1–3) whose limit switch is stuck active.
    #[arg(long, value_name = "AXIS")]
    stuck_switch: Option<u8>,
    /// Axis (1–3) whose limit switch never triggers (broken wire).
    #[arg(long, value_name = "AXIS")]
    dead_switch: Option<u8>,
    /// CAN-FD sockets (the interface needs MTU 72).
    #[arg(long)]
    fd: bool,
    /// Control tick rate (Hz), 1000 to 10000; must match the rate the host
    /// configures [default: the machine file's `drive.control_rate`].
    #[arg(long, value_name = "HZ")]
    rate: Option<f64>,
    /// Machine file (TOML, SI units; docs/machine.md): the simulated
    /// robot, switches, encoder scales and motor directions. Without it,
    /// the paper's machine.
    #[arg(long = "machine", visible_alias = "robot", value_name = "FILE.toml")]
    machine: Option<PathBuf>,
    /// The machine: rigid, or flexible (screw and strut compliance, a
    /// current-loop lag, an accelerometer on the platform; `docs/vibration.md`).
    #[arg(long, value_enum, default_value_t = PlantKind::Rigid)]
    plant: PlantKind,
    /// Write the report (JSON) here on exit; `-` for standard output.
    #[arg(long, value_name = "FILE.json")]
    report: Option<PathBuf>,
    /// Platform position at power-on (mm), default the start of paper Case I.
    #[arg(
        long,
        default_value = "-90,90,680",
        value_name = "X,Y,Z",
        allow_hyphen_values = true
    )]
    start: String,
}

#[derive(Serialize)]
struct JsonReport {
    #[serde(flatten)]
    last: RunReport,
    runs: Vec<RunReport>,
    iface: String,
    fd: bool,
    rate_hz: f64,
    ticks: u64,
    missed_deadlines: u64,
    skipped_ticks: u64,
    max_late_us: f64,
    wall_time_s: f64,
    total_frames: u64,
    total_bus_load: f64,
    foreign_frames: u64,
    final_joint_position_m: [f64; 3],
}

/// A flag set by SIGINT or SIGTERM.
fn stop_on_signals() -> CliResult<Arc<AtomicBool>> {
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(sig, Arc::clone(&stop))
            .map_err(|e| CliError::device(format!("cannot install the signal handler: {e}")))?;
    }
    Ok(stop)
}

fn report_json(args: &Args, cfg: &RealtimeConfig, r: &RealtimeReport) -> String {
    let j = JsonReport {
        last: r.runs.last().cloned().unwrap_or_default(),
        runs: r.runs.clone(),
        iface: cfg.iface.to_string(),
        fd: args.fd,
        rate_hz: cfg.rate_hz,
        ticks: r.ticks,
        missed_deadlines: r.missed_deadlines,
        skipped_ticks: r.skipped_ticks,
        max_late_us: r.max_late_us,
        wall_time_s: r.wall_time_s,
        total_frames: r.frames,
        total_bus_load: r.bus_load,
        foreign_frames: r.foreign_frames,
        final_joint_position_m: r.final_joint_position_m,
    };
    serde_json::to_string_pretty(&j).unwrap_or_default()
}

fn run(args: &Args) -> CliResult {
    let machine = load_machine(args.machine.as_deref())?;
    let rate = check_rate("--rate", args.rate.unwrap_or(machine.drive.control_rate))?;
    let nodes = match &args.nodes {
        Some(n) => parse_nodes("--nodes", n)?,
        None => machine.axes.iter().map(|a| a.node_id).collect(),
    };
    let mut switches = [SwitchMode::Working; 3];
    for (opt, axis, mode) in [
        ("--stuck-switch", args.stuck_switch, SwitchMode::Stuck),
        ("--dead-switch", args.dead_switch, SwitchMode::Dead),
    ] {
        match axis {
            None => {}
            Some(a @ 1..=3) => switches[a as usize - 1] = mode,
            Some(a) => {
                return Err(CliError::bad_input(format!("{opt} {a}: an axis 1, 2 or 3")));
            }
        }
    }
    let r0 = parse_triple("--start", &args.start)? * 1e-3;
    let pose = Pose::from_cartesian(&machine.robot.model::<f64>(), r0)
        .map_err(|e| CliError::bad_input(format!("--start {}: {e}", args.start)))?;
    let iface = args.iface.as_deref().unwrap_or_default();
    let mut cfg = RealtimeConfig::new(iface, machine, pose.q);
    cfg.nodes = nodes;
    cfg.unhomed = args.unhomed.then_some(args.seed);
    cfg.switches = switches;
    cfg.fd = args.fd;
    cfg.rate_hz = rate;
    cfg.plant_kind = args.plant;
    let stop = stop_on_signals()?;
    let port = realtime::open(&cfg).map_err(CliError::device)?;
    triquint_cli_common::errln!(
        "triquint-sim: nodes {:?} (axis 1 first{}) on {} ({}), {} Hz; SIGINT/SIGTERM to stop",
        cfg.nodes,
        if args.unhomed { ", unhomed" } else { "" },
        cfg.iface,
        if cfg.fd { "CAN-FD" } else { "classic CAN" },
        cfg.rate_hz
    );
    let mut r = RealtimeReport::default();
    let failure = match realtime::run(port, &cfg, &stop, &mut r) {
        Ok(()) => None,
        Err(e @ RealtimeError::Bus(_)) => Some(CliError::device(e)),
        Err(e @ RealtimeError::Machine(_)) => Some(CliError::motion_fault(e)),
        Err(e @ RealtimeError::Flex(_)) => Some(CliError::bad_input(e)),
    };
    triquint_cli_common::errln!(
        "triquint-sim: {} runs, {} ticks, {} missed deadlines ({} skipped, max late {:.0} µs), {} frames",
        r.runs.len(),
        r.ticks,
        r.missed_deadlines,
        r.skipped_ticks,
        r.max_late_us,
        r.frames
    );
    if let Some(path) = &args.report {
        cli::write_report(
            path,
            &report_json(args, &cfg, &r),
            &mut std::io::stdout().lock(),
        )?;
    }
    match failure {
        Some(f) => Err(f),
        None => Ok(()),
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match &cli.command {
        Some(Command::Proxy(p)) => cli::proxy::run(p),
        None => run(&cli.machine),
    };
    main_exit("triquint-sim", result)
}
