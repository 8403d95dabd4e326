//! `triquint simulate PLAN.json`: runs a plan on the in-process virtual hardware.

use std::path::{Path, PathBuf};

use clap::Args;
use triquint_shared::plan::Plan;
use triquint_sim::report::{JsonFault, RunJson};

use crate::exit::{CliError, CliResult, write_atomic};
use crate::inprocess::simulate::{SimReport, SimulateError, SimulateOptions, simulate};

#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// Plan file written by `triquint plan`.
    pub plan: PathBuf,
    /// CAN-FD (64-byte segment frames, 1/5 Mbit/s) instead of classic CAN at 1 Mbit/s.
    #[arg(long)]
    pub fd: bool,
    /// Drives run feedback only (same gains).
    #[arg(long)]
    pub no_feedforward: bool,
    /// Control tick rate of the drives (Hz), 1000 to 10000 (`triquint_cli_common::parse::RATE_HZ`).
    #[arg(long, default_value_t = 1000.0, value_name = "HZ")]
    pub rate: f64,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
    /// Write SVG plots into DIR: joint positions (reference and measured),
    /// tracking error, torque command, feedforward against the total, overview.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
}

fn to_cli(e: SimulateError) -> CliError {
    match e {
        SimulateError::Upload(u) if u.is_config() => CliError::bad_input(u),
        SimulateError::Upload(u @ triquint_link::UploadError::Segment { .. }) => {
            CliError::bad_input(u)
        }
        SimulateError::Upload(u) if u.is_motion_fault() => CliError::motion_fault(u),
        SimulateError::Plan(m) => CliError::bad_input(m),
        e @ SimulateError::Config(_) => CliError::bad_input(e),
        other => CliError::device(other),
    }
}

pub fn run(args: &SimulateArgs) -> CliResult {
    triquint_cli_common::parse::check_rate("--rate", args.rate)?;
    let plan = crate::cli::load_plan(&args.plan)?;
    let opts = SimulateOptions {
        fd: args.fd,
        feedforward: !args.no_feedforward,
        rate_hz: args.rate,
        ..SimulateOptions::default()
    };
    let report = simulate(&plan, &opts).map_err(to_cli)?;
    if let Some(dir) = &args.plot {
        write_plots(dir, &plan, &opts, &report)?;
    }
    let start_s = report.start_us as f64 * 1e-6;
    let faults: Vec<JsonFault> = report
        .faults_on_nodes
        .iter()
        .map(|f| JsonFault::new(f, f.t_ns as f64 * 1e-9 - start_s))
        .collect();
    if args.json {
        let j = RunJson {
            rms_error_m: report.tracking.rms_error_m,
            max_error_m: report.tracking.max_error_m,
            peak_torque_nm: report.peak_torque_nm,
            bus_load: report.bus_load,
            frames: report.frames,
            faults,
            completed: report.completed,
        };
        println!(
            "{}",
            serde_json::to_string(&j).map_err(|e| CliError::device(e.to_string()))?
        );
    } else {
        print_human(&plan, &opts, &report, &faults);
    }
    if report.completed && report.faults_on_nodes.is_empty() {
        Ok(())
    } else {
        let first = report.faults_on_nodes.first();
        Err(CliError::motion_fault(match first {
            Some(f) => format!(
                "node {} faulted: {} ({}) at {:.3} s",
                f.node,
                f.code.name(),
                f.code as u8,
                f.t_ns as f64 * 1e-9 - start_s
            ),
            None => "the plan did not complete".to_string(),
        }))
    }
}

fn print_human(plan: &Plan, opts: &SimulateOptions, r: &SimReport, faults: &[JsonFault]) {
    println!(
        "{} segments, {:.3} s, {} CAN, {} Hz control, feedforward {}",
        plan.segments.len(),
        plan.total_time_s,
        if opts.fd {
            "CAN-FD 1/5 Mbit/s"
        } else {
            "classic 1 Mbit/s"
        },
        opts.rate_hz,
        if opts.feedforward { "on" } else { "off" }
    );
    println!("axis   RMS error (µm)   max error (µm)   peak torque (N·m)");
    for j in 0..3 {
        println!(
            "q{}     {:>14.3}   {:>14.3}   {:>17.4}",
            j + 1,
            r.tracking.rms_error_m[j] * 1e6,
            r.tracking.max_error_m[j] * 1e6,
            r.peak_torque_nm[j]
        );
    }
    println!(
        "bus load {:.2} % over {:.3} s (segments {:.2} %); {} frames ({} segment frames, {} per segment, {} retransmissions)",
        r.bus_load * 100.0,
        r.sim_time_s,
        r.segment_bus_load * 100.0,
        r.frames,
        r.segment_frames,
        r.frames_per_segment,
        r.retransmits
    );
    println!(
        "start skew {:.1} µs (tick {:.0} µs); stop time {:.3} s; f32 vs f64 evaluation error {:.3e} m",
        r.start_skew_ns as f64 * 1e-3,
        r.tick_ns as f64 * 1e-3,
        r.stop_time_s,
        r.f32_eval_error_m
    );
    if faults.is_empty() {
        println!("completed: {}, no faults", r.completed);
    } else {
        for f in faults {
            println!(
                "fault: node {} {} ({}) at {:.3} s",
                f.node, f.name, f.code, f.t_s
            );
        }
    }
}

fn write_plots(dir: &Path, plan: &Plan, opts: &SimulateOptions, r: &SimReport) -> CliResult {
    let plots = crate::report::sim_plots::sim_plots(plan, opts, r)
        .map_err(|e| CliError::bad_input(format!("plots: {e}")))?;
    for (name, svg) in plots {
        write_atomic(&dir.join(name), svg.as_bytes())?;
    }
    Ok(())
}
