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

use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::Arc;
use std::sync::atomic::AtomicBool;

use clap::{Parser, Subcommand};
use nalgebra::Vector3;
use serde::Serialize;
use triquint_shared::kinematics::Pose;
use triquint_sim::realtime::{self, RealtimeConfig, RealtimeError, RealtimeReport, RunReport};
use triquint_sim::report::{JsonFault, RunJson};
use triquint_sim::robot_file::read_robot;

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
    /// Drives to run, comma-separated (an absent drive is a silent node).
    #[arg(long, default_value = "1,2,3", value_name = "1,2,3")]
    nodes: String,
    /// CAN-FD sockets (the interface needs MTU 72).
    #[arg(long)]
    fd: bool,
    /// Control tick rate (Hz); must match the rate the host configures.
    #[arg(long, default_value_t = 1000.0, value_name = "HZ")]
    rate: f64,
    /// Machine parameters overriding the paper's Table 1 (TOML, SI units).
    #[arg(long, value_name = "FILE.toml")]
    robot: Option<PathBuf>,
    /// Write the report (JSON) here on exit.
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
struct JsonRun {
    #[serde(flatten)]
    run: RunJson,
    segment_bus_load: f64,
    segment_frames: u64,
    segments: usize,
    plan_time_s: f64,
    duration_s: f64,
    start_skew_us: f64,
    tracking_samples: usize,
    /// Per node, the (sequence, body CRC-32) of every segment it executed.
    executed: Vec<Vec<(u16, u32)>>,
    stop_s: Option<f64>,
    stopped_within_buffer: bool,
    max_stop_jerk: [f64; 3],
    stop_ramp_s: f64,
}

#[derive(Serialize)]
struct JsonReport {
    #[serde(flatten)]
    last: JsonRun,
    runs: Vec<JsonRun>,
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
}

fn json_run(r: &RunReport) -> JsonRun {
    JsonRun {
        run: RunJson {
            rms_error_m: r.tracking.rms_error_m,
            max_error_m: r.tracking.max_error_m,
            peak_torque_nm: r.peak_torque_nm,
            bus_load: r.bus_load,
            frames: r.frames,
            faults: r
                .faults
                .iter()
                .map(|(f, t_s)| JsonFault::new(f, *t_s))
                .collect(),
            completed: r.completed,
        },
        segment_bus_load: r.segment_bus_load,
        segment_frames: r.segment_frames,
        segments: r.segments,
        plan_time_s: r.plan_time_s,
        duration_s: r.duration_s,
        start_skew_us: r.start_skew_ns as f64 * 1e-3,
        tracking_samples: r.tracking.samples,
        executed: (1..=3)
            .map(|node| {
                r.executed
                    .iter()
                    .filter(|e| e.0 == node)
                    .map(|e| (e.1, e.2))
                    .collect()
            })
            .collect(),
        stop_s: r.stop_s,
        stopped_within_buffer: r.stopped_within_buffer,
        max_stop_jerk: r.max_stop_jerk,
        stop_ramp_s: r.stop_ramp_s,
    }
}

/// Exit status and the one-line message.
struct Failure(u8, String);

fn bad(msg: impl std::fmt::Display) -> Failure {
    Failure(2, msg.to_string())
}

fn parse_nodes(text: &str) -> Result<Vec<u8>, Failure> {
    let mut nodes = Vec::new();
    for p in text.split(',').map(str::trim) {
        match p.parse::<u8>() {
            Ok(n @ 1..=3) if !nodes.contains(&n) => nodes.push(n),
            _ => {
                return Err(bad(format!(
                    "--nodes: `{p}` in `{text}` is not a distinct node 1, 2 or 3"
                )));
            }
        }
    }
    nodes.sort_unstable();
    Ok(nodes)
}

fn parse_start(text: &str) -> Result<Vector3<f64>, Failure> {
    let v: Vec<f64> = text
        .split(',')
        .map(|p| p.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| bad(format!("--start: `{text}` is not three numbers X,Y,Z (mm)")))?;
    match v.as_slice() {
        [x, y, z] if v.iter().all(|c| c.is_finite()) => Ok(Vector3::new(*x, *y, *z) * 1e-3),
        _ => Err(bad(format!(
            "--start: `{text}` is not three finite numbers X,Y,Z (mm)"
        ))),
    }
}

/// Writes through a temporary file and a rename: never a partial report.
fn write_report(path: &Path, text: &str) -> Result<(), Failure> {
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    std::fs::write(&tmp, text)
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            bad(format!("{}: {e}", path.display()))
        })
}

/// A flag set by SIGINT or SIGTERM.
fn stop_on_signals() -> Result<Arc<AtomicBool>, Failure> {
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(sig, Arc::clone(&stop))
            .map_err(|e| Failure(4, format!("cannot install the signal handler: {e}")))?;
    }
    Ok(stop)
}

fn report_json(args: &Args, iface: &str, r: &RealtimeReport) -> String {
    let runs: Vec<JsonRun> = r.runs.iter().map(json_run).collect();
    let last = json_run(r.runs.last().unwrap_or(&RunReport::default()));
    let j = JsonReport {
        last,
        runs,
        iface: iface.to_string(),
        fd: args.fd,
        rate_hz: args.rate,
        ticks: r.ticks,
        missed_deadlines: r.missed_deadlines,
        skipped_ticks: r.skipped_ticks,
        max_late_us: r.max_late_us,
        wall_time_s: r.wall_time_s,
        total_frames: r.frames,
        total_bus_load: r.bus_load,
        foreign_frames: r.foreign_frames,
    };
    serde_json::to_string_pretty(&j).unwrap_or_default()
}

fn run(args: &Args) -> Result<(), Failure> {
    if !(100.0..=10000.0).contains(&args.rate) {
        return Err(bad(format!(
            "--rate {}: must be 100 to 10000 Hz",
            args.rate
        )));
    }
    let nodes = parse_nodes(&args.nodes)?;
    let robot = read_robot(args.robot.as_deref()).map_err(bad)?;
    let r0 = parse_start(&args.start)?;
    let pose = Pose::from_cartesian(&robot.model::<f64>(), r0)
        .map_err(|e| bad(format!("--start {}: {e}", args.start)))?;
    let iface = args.iface.as_deref().unwrap_or_default();
    let mut cfg = RealtimeConfig::new(iface, robot, pose.q);
    cfg.nodes = nodes;
    cfg.fd = args.fd;
    cfg.rate_hz = args.rate;
    let stop = stop_on_signals()?;
    let port = realtime::open(&cfg).map_err(|e| Failure(4, e.to_string()))?;
    eprintln!(
        "triquint-sim: nodes {:?} on {} ({}), {} Hz; SIGINT/SIGTERM to stop",
        cfg.nodes,
        cfg.iface,
        if cfg.fd { "CAN-FD" } else { "classic CAN" },
        cfg.rate_hz
    );
    let mut r = RealtimeReport::default();
    let failure = match realtime::run(port, &cfg, &stop, &mut r) {
        Ok(()) => None,
        Err(e @ RealtimeError::Bus(_)) => Some(Failure(4, e.to_string())),
        Err(e @ RealtimeError::Machine(_)) => Some(Failure(5, e.to_string())),
    };
    eprintln!(
        "triquint-sim: {} runs, {} ticks, {} missed deadlines ({} skipped, max late {:.0} µs), {} frames",
        r.runs.len(),
        r.ticks,
        r.missed_deadlines,
        r.skipped_ticks,
        r.max_late_us,
        r.frames
    );
    if let Some(path) = &args.report {
        write_report(path, &report_json(args, iface, &r))?;
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
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(Failure(code, msg)) => {
            eprintln!("triquint-sim: error: {msg}");
            ExitCode::from(code)
        }
    }
}
