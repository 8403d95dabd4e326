//! `triquint simulate PLAN.json`: runs a plan on the in-process virtual hardware.

use std::path::{Path, PathBuf};

use clap::Args;
use triquint_shared::plan::Plan;
use triquint_sim::plant_model::PlantKind;
use triquint_sim::report::JsonFault;
use triquint_sim::vibration::Residual;

use triquint_cli_common::outln;
use triquint_cli_common::output::write_outputs;

use crate::exit::{CliError, CliResult};
use crate::inprocess::simulate::{SimReport, SimulateError, SimulateOptions, simulate};
use crate::inprocess::test_reference::{self, TestReference};
use crate::ops::shown::drive_name;

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
    /// Control tick rate of the drives (Hz), 1000 to 10000
    /// [default: the machine file's `drive.control_rate`].
    #[arg(long, value_name = "HZ")]
    pub rate: Option<f64>,
    /// The machine: rigid, or flexible (screw and strut compliance, current-loop
    /// lag, an accelerometer on the platform: adds the residual vibration).
    #[arg(long, value_enum, default_value_t = PlantKind::Rigid)]
    pub plant: PlantKind,
    /// TEST REFERENCE, not a drive's path: run the plan, or a jerk-discontinuous
    /// 7-phase profile of its move or along its path (which the drives
    /// refuse), through the
    /// firmware's control law below the drives' checks, and report the
    /// residual vibration (with --plant flexible).
    #[arg(long, value_enum, value_name = "KIND")]
    pub test_reference: Option<TestReference>,
    /// Print the result as JSON.
    #[arg(long)]
    pub json: bool,
    /// Write SVG plots into DIR: joint positions (reference and measured),
    /// tracking error, torque command, feedforward against the total, overview.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<PathBuf>,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

fn to_cli(e: SimulateError) -> CliError {
    match e {
        SimulateError::Upload(u) if u.is_config() || u.is_bad_plan() => CliError::bad_input(u),
        SimulateError::Upload(u @ triquint_link::UploadError::Segment { .. }) => {
            CliError::bad_input(u)
        }
        SimulateError::Upload(u) if u.is_refusal() => CliError::refused(u),
        e @ (SimulateError::NoSegments | SimulateError::NoEnd | SimulateError::ClosedPath) => {
            CliError::bad_input(e)
        }
        e @ SimulateError::Config(_) => CliError::bad_input(e),
        other => CliError::device(other),
    }
}

pub fn run(args: &SimulateArgs) -> CliResult {
    crate::cli::check_plot_folder(args.plot.as_deref())?;
    let plan = crate::cli::load_plan(&args.plan)?;
    let machine = args.machine.load()?;
    let rate_hz = args.rate.unwrap_or(machine.drive.control_rate);
    triquint_cli_common::parse::check_rate("--rate", rate_hz)?;
    crate::machine_arg::plan_for_machine(&plan, &args.plan, &machine, &args.machine.shown())?;
    crate::machine_arg::verified(&plan, &args.plan)?;
    let opts = SimulateOptions {
        settings: machine.drive_settings(),
        fd: args.fd,
        feedforward: !args.no_feedforward,
        rate_hz,
        plant: args.plant,
        flex: triquint_sim::flex::FlexParams::for_machine(&machine),
        ..SimulateOptions::default()
    };
    if let Some(kind) = args.test_reference {
        return run_test_reference(args, &plan, &opts, kind);
    }
    let report = simulate(&plan, &opts).map_err(to_cli)?;
    if let Some(dir) = &args.plot {
        write_plots(dir, &args.plan, &plan, &opts, &report)?;
    }
    let start_s = report.start_us as f64 * 1e-6;
    if args.json {
        outln!(
            "{}",
            serde_json::to_string(&report.run).map_err(|e| CliError::device(e.to_string()))?
        )?;
    } else {
        print_human(&plan, &opts, &report, &report.run.faults)?;
    }
    if report.run.completed && report.faults_on_nodes.is_empty() {
        Ok(())
    } else {
        let first = report.faults_on_nodes.first();
        Err(CliError::motion_fault(match first {
            Some(f) => format!(
                "{} faulted: {} ({}) at {:.3} s",
                drive_name(opts.settings.node_ids, f.node),
                f.code.name(),
                f.code as u8,
                f.t_ns as f64 * 1e-9 - start_s
            ),
            None => "the plan did not complete".to_string(),
        }))
    }
}

fn run_test_reference(
    args: &SimulateArgs,
    plan: &Plan,
    opts: &SimulateOptions,
    kind: TestReference,
) -> CliResult {
    let r = test_reference::run(plan, opts, kind).map_err(to_cli)?;
    if let Some(dir) = &args.plot {
        let title = format!(
            "Platform accelerometer: TEST REFERENCE {} of {:.3} s",
            kind.name(),
            r.duration_s
        );
        let svg = crate::report::sim_plots::accelerometer(
            &title,
            &r.accel,
            r.start_s,
            r.duration_s,
            r.vibration.as_ref(),
        )
        .map_err(|e| CliError::bad_input(format!("plots: {e}")))?;
        let path = dir.join("accelerometer.svg");
        write_outputs(&[(path.as_path(), svg.as_bytes())], &[&args.plan])?;
    }
    if args.json {
        outln!(
            "{}",
            serde_json::to_string(&r).map_err(|e| CliError::device(e.to_string()))?
        )?;
        return Ok(());
    }
    outln!(
        "TEST REFERENCE (the firmware's control law below the drives' checks, no bus): {}, {:.3} s, {} plant, largest following error {:.3} µm",
        kind.name(),
        r.duration_s,
        if r.vibration.is_some() {
            "flexible"
        } else {
            "rigid"
        },
        r.max_error_m * 1e6
    )?;
    if let Some(v) = &r.vibration {
        print_residual(v)?;
    }
    Ok(())
}

fn print_residual(v: &Residual) -> CliResult {
    outln!(
        "residual vibration over {:.2} s after the end: acceleration peak {:.4} RMS {:.4} m/s², position peak {:.3} RMS {:.3} µm{}",
        v.window_s,
        v.peak_accel_m_s2,
        v.rms_accel_m_s2,
        v.peak_position_m * 1e6,
        v.rms_position_m * 1e6,
        v.dominant_hz
            .map_or(String::new(), |f| format!(", at {f:.1} Hz"))
    )?;
    Ok(())
}

/// The bus as the summary names it: one name, each bit rate once.
fn bus_name(fd: bool) -> &'static str {
    if fd {
        "CAN-FD (1 Mbit/s arbitration, 5 Mbit/s data)"
    } else {
        "classic CAN (1 Mbit/s)"
    }
}

fn print_human(
    plan: &Plan,
    opts: &SimulateOptions,
    r: &SimReport,
    faults: &[JsonFault],
) -> CliResult {
    outln!(
        "{} segments, {:.3} s, {}, {} Hz control, feedforward {}",
        plan.segments.len(),
        plan.total_time_s,
        bus_name(opts.fd),
        opts.rate_hz,
        if opts.feedforward { "on" } else { "off" }
    )?;
    outln!("axis   RMS error (µm)   max error (µm)   peak torque (N·m)")?;
    for j in 0..3 {
        outln!(
            "{}      {:>14.3}   {:>14.3}   {:>17.4}",
            j + 1,
            r.run.rms_error_m[j] * 1e6,
            r.run.max_error_m[j] * 1e6,
            r.run.peak_torque_nm[j]
        )?;
    }
    outln!(
        "bus load {:.2} % over {:.3} s (segments {:.2} %); {} frames ({} segment frames, {:.2} per segment, {} of {} segments compact, {} retransmissions)",
        r.run.bus_load * 100.0,
        r.sim_time_s,
        r.run.segment_bus_load * 100.0,
        r.run.frames,
        r.run.segment_frames,
        r.frames_per_segment,
        r.compact_sent,
        r.segments_sent,
        r.retransmits
    )?;
    let skew = match r.start_skew_ns {
        Some(ns) => format!("{:.1} µs", ns as f64 * 1e-3),
        None => "none (not every drive started)".to_string(),
    };
    outln!(
        "start skew {skew} (tick {:.0} µs); stop ramp T_s {:.3} s; f32 vs f64 evaluation error {:.3e} m",
        r.tick_ns as f64 * 1e-3,
        r.run.stop_ramp_s,
        r.f32_eval_error_m
    )?;
    if let Some(v) = &r.run.vibration {
        print_residual(v)?;
    }
    if faults.is_empty() {
        outln!("completed: {}, no faults", r.run.completed)?;
    } else {
        for f in faults {
            outln!(
                "fault: {} {} ({}) at {:.3} s",
                drive_name(opts.settings.node_ids, f.node),
                f.name,
                f.code,
                f.t_s
            )?;
        }
    }
    Ok(())
}

fn write_plots(
    dir: &Path,
    plan_path: &Path,
    plan: &Plan,
    opts: &SimulateOptions,
    r: &SimReport,
) -> CliResult {
    let plots = crate::report::sim_plots::sim_plots(plan, opts, r)
        .map_err(|e| CliError::bad_input(format!("plots: {e}")))?;
    let paths: Vec<_> = plots.iter().map(|(name, _)| dir.join(name)).collect();
    let files: Vec<_> = paths
        .iter()
        .zip(&plots)
        .map(|(p, (_, svg))| (p.as_path(), svg.as_bytes()))
        .collect();
    write_outputs(&files, &[plan_path])
}
