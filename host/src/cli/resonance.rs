//! `triquint resonance [--at X,Y,Z] [--plot DIR] [--json]`: each axis of the
//! simulated flexible machine (the machine file's `[vibration]`) swept
//! within its ceilings, its resonances measured from the accelerometer, and
//! the input shaper that keeps the lowest one's residual smallest for the
//! least time, as Klipper's TEST_RESONANCES and calibrate_shaper do;
//! `--across` sweeps every pose of a grid around `--at` and sets each
//! measured peak beside the linearised model's nearest mode; `--model`
//! prints the model's modes instead of measuring (docs/input-shaping.md,
//! docs/vibration.md).

use clap::Args;
use nalgebra::Vector3;
use serde::Serialize;
use triquint_cli_common::outln;
use triquint_planner::shaping::{Impulses, Shaper};
use triquint_shared::kinematics::Pose;
use triquint_shared::machine::Machine;
use triquint_sim::flex::{FlexError, FlexParams, FlexPlant, Mode};
use triquint_sim::plant::PlantConfig;
use triquint_sim::resonance::{AxisResponse, Sweep};

use crate::exit::{CliError, CliResult};

/// The residual a suggested shaper may leave (Klipper's 5 %).
const TARGET_RESIDUAL: f64 = 0.05;
/// Modes within this factor of the lowest at a pose are the shaper's targets.
const TARGET_BAND: f64 = 1.2;
/// Half the side of `--across`'s square grid at the pose's height (mm).
const ACROSS_HALF_MM: f64 = 120.0;
/// Poses per side of `--across`'s grid: the model's, and the measurement's
/// (each pose is a minute of simulation).
const MODEL_GRID: usize = 5;
const MEASURED_GRID: usize = 3;

#[derive(Args, Debug)]
pub struct ResonanceArgs {
    /// Platform position (mm) [default: the machine's reference pose, 0,0,600].
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub at: Option<String>,
    /// The model's modes, not a measurement: with `--across`, also every
    /// pose of a ±120 mm grid at that height inside the travel.
    #[arg(long)]
    pub model: bool,
    /// Every pose of a ±120 mm grid at that height inside the travel:
    /// measured (each peak against the model's nearest mode, and the worst
    /// deviation), or with `--model` the model's modes.
    #[arg(long)]
    pub across: bool,
    /// Poses per side of `--across`'s grid, 1 to 9 [default: 3 measured, 5 with --model].
    #[arg(long, value_name = "N", requires = "across")]
    pub grid: Option<usize>,
    /// The sweep's lowest and highest frequency (Hz).
    #[arg(long, default_value_t = Sweep::default().from_hz)]
    pub from_hz: f64,
    #[arg(long, default_value_t = Sweep::default().to_hz)]
    pub to_hz: f64,
    /// How long each axis is swept (s).
    #[arg(long, default_value_t = Sweep::default().duration_s)]
    pub sweep_s: f64,
    /// Acceleration amplitude per Hz (m/s² per Hz; Klipper's 0.075), cut to the ceilings.
    #[arg(long, default_value_t = Sweep::default().accel_per_hz)]
    pub accel_per_hz: f64,
    /// Write the measured response as response.svg here.
    #[arg(long, value_name = "DIR")]
    pub plot: Option<std::path::PathBuf>,
    /// Print JSON.
    #[arg(long)]
    pub json: bool,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

/// Why the modes cannot be found.
#[derive(Debug, thiserror::Error)]
pub enum ResonanceError {
    #[error("the flexible plant: {0}")]
    Plant(#[from] FlexError),
    #[error("({x:.1}, {y:.1}, {z:.1}) mm: {reason}")]
    Pose {
        x: f64,
        y: f64,
        z: f64,
        reason: String,
    },
}

#[derive(Serialize)]
struct PoseModes {
    position_mm: [f64; 3],
    modes: Vec<ModeRow>,
}

#[derive(Serialize)]
struct ModeRow {
    hz: f64,
    damping: f64,
    platform_share: f64,
}

#[derive(Serialize)]
struct ShaperRow {
    #[serde(rename = "type")]
    shaper: Shaper,
    frequency_hz: f64,
    damping: f64,
    /// What the shaper adds to a move (ms).
    duration_ms: f64,
    /// The largest residual over the target modes at every pose (0–1).
    worst_residual: f64,
}

/// The modes at each pose.
fn modes(machine: &Machine, poses_mm: &[[f64; 3]]) -> Result<Vec<PoseModes>, ResonanceError> {
    let params = FlexParams::for_machine(machine);
    let model = machine.robot.model::<f64>();
    let bad = |p: [f64; 3], reason: String| ResonanceError::Pose {
        x: p[0],
        y: p[1],
        z: p[2],
        reason,
    };
    let reference = params.reference_pose;
    let q0 = Pose::from_cartesian(&model, Vector3::from(reference))
        .map_err(|e| bad(reference.map(|x| x * 1e3), e.to_string()))?
        .q;
    let plant = FlexPlant::new(&machine.robot, PlantConfig::default(), params, q0)?;
    poses_mm
        .iter()
        .map(|&p| {
            let r = Vector3::from(p) * 1e-3;
            let pose = Pose::from_cartesian(&model, r).map_err(|e| bad(p, e.to_string()))?;
            if let Some(o) = machine.travel().outside(&pose.q.into()) {
                return Err(bad(p, format!("outside the travel: {o}")));
            }
            let modes = plant.modes(r).map_err(|e| bad(p, e.to_string()))?;
            Ok(PoseModes {
                position_mm: p,
                modes: modes
                    .iter()
                    .map(|m: &Mode| ModeRow {
                        hz: m.hz,
                        damping: m.damping,
                        platform_share: m.platform_share,
                    })
                    .collect(),
            })
        })
        .collect()
}

/// The modes a shaper aims at: at each pose, those within [`TARGET_BAND`]
/// of the lowest (the lateral pair of the platform), as (Hz, damping).
fn targets(poses: &[PoseModes]) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for p in poses {
        let lowest = p.modes.iter().map(|m| m.hz).fold(f64::INFINITY, f64::min);
        out.extend(
            p.modes
                .iter()
                .filter(|m| m.hz <= TARGET_BAND * lowest)
                .map(|m| (m.hz, m.damping)),
        );
    }
    out
}

/// For each shaper, the frequency (0.1 Hz grid over ±30 % of the targets)
/// whose worst residual over the targets is least, at the targets' mean
/// damping.
fn shapers(targets: &[(f64, f64)]) -> Vec<ShaperRow> {
    let lo = targets.iter().map(|t| t.0).fold(f64::INFINITY, f64::min);
    let hi = targets.iter().map(|t| t.0).fold(0.0, f64::max);
    let damping = targets.iter().map(|t| t.1).sum::<f64>() / targets.len().max(1) as f64;
    let steps = ((1.3 * hi - 0.7 * lo) / 0.1).ceil() as usize;
    Shaper::ALL
        .into_iter()
        .filter_map(|shaper| {
            (0..=steps)
                .filter_map(|i| {
                    let f = ((0.7 * lo + 0.1 * i as f64) * 10.0).round() / 10.0;
                    let imp = Impulses::new(shaper, f, damping).ok()?;
                    let worst = targets
                        .iter()
                        .map(|&(hz, z)| imp.residual(hz, z))
                        .fold(0.0, f64::max);
                    Some(ShaperRow {
                        shaper,
                        frequency_hz: f,
                        damping: (damping * 1e3).round() / 1e3,
                        duration_ms: imp.duration_s() * 1e3,
                        worst_residual: worst,
                    })
                })
                .min_by(|a, b| a.worst_residual.total_cmp(&b.worst_residual))
        })
        .collect()
}

/// The shortest shaper within [`TARGET_RESIDUAL`], else the one leaving least.
fn suggestion(rows: &[ShaperRow]) -> Option<&ShaperRow> {
    rows.iter()
        .filter(|r| r.worst_residual <= TARGET_RESIDUAL)
        .min_by(|a, b| a.duration_ms.total_cmp(&b.duration_ms))
        .or_else(|| {
            rows.iter()
                .min_by(|a, b| a.worst_residual.total_cmp(&b.worst_residual))
        })
}

/// The shaper's targets from a measurement: each axis's peaks within
/// [`TARGET_BAND`] of the lowest, the lowest at its ring-down damping.
fn measured_targets(axes: &[AxisResponse]) -> Vec<(f64, f64)> {
    let lowest = axes
        .iter()
        .flat_map(|a| a.modes.first())
        .map(|m| m.hz)
        .fold(f64::INFINITY, f64::min);
    axes.iter()
        .flat_map(|a| {
            a.modes.iter().enumerate().filter_map(move |(k, m)| {
                let damping = match (k, a.ringdown_damping) {
                    (0, Some(d)) => d,
                    _ => m.damping,
                };
                (m.hz <= TARGET_BAND * lowest).then_some((m.hz, damping))
            })
        })
        .collect()
}

/// The response of each axis, with its peaks and the shaper's frequency.
fn response_chart(axes: &[AxisResponse], suggested: Option<&ShaperRow>) -> triquint_plot::Chart {
    let mut chart = triquint_plot::Chart::new(
        "Measured response: platform acceleration per rigid-body acceleration",
    )
    .x_label("frequency (Hz)")
    .y_label("|H|");
    for a in axes {
        let points = a
            .magnitude
            .iter()
            .enumerate()
            .map(|(k, m)| (a.from_hz + a.step_hz * k as f64, *m))
            .collect();
        chart = chart.line(triquint_plot::Line::joint(
            a.axis,
            format!("axis {}", a.axis + 1),
            points,
        ));
    }
    // One mark per peak, the axes' peaks at one frequency marked once.
    let mut marked: Vec<String> = Vec::new();
    for m in axes.iter().flat_map(|a| &a.modes) {
        let label = format!("{:.1} Hz", m.hz);
        if !marked.contains(&label) {
            chart = chart.knot(m.hz, label.clone()).knots_name("mode");
            marked.push(label);
        }
    }
    if let Some(s) = suggested {
        chart = chart.note(format!(
            "suggested {} at {:.1} Hz, ζ {:.3}: adds {:.1} ms, leaves {:.1} %",
            s.shaper.name(),
            s.frequency_hz,
            s.damping,
            s.duration_ms,
            s.worst_residual * 100.0
        ));
    }
    chart
}

/// The sweep the options ask for.
fn sweep(args: &ResonanceArgs) -> Sweep {
    Sweep {
        from_hz: args.from_hz,
        to_hz: args.to_hz,
        duration_s: args.sweep_s,
        accel_per_hz: args.accel_per_hz,
    }
}

/// Sweeps each axis at `centre` (mm) and prints what it found.
fn run_measured(args: &ResonanceArgs, machine: &Machine, centre: [f64; 3]) -> CliResult {
    let sweep = sweep(args);
    // The pose first, so that a bad one is named as `--model` names it.
    let model = modes(machine, &[centre]).map_err(|e| CliError::bad_input(e.to_string()))?;
    let axes = triquint_sim::resonance::measure(machine, Vector3::from(centre) * 1e-3, &sweep)
        .map_err(|e| CliError::bad_input(e.to_string()))?;
    let targets = measured_targets(&axes);
    if targets.is_empty() {
        return Err(CliError::bad_input(format!(
            "no resonance found between {} and {} Hz",
            sweep.from_hz, sweep.to_hz
        )));
    }
    let rows = shapers(&targets);
    let suggested = suggestion(&rows);
    if let Some(dir) = &args.plot {
        let svg = response_chart(&axes, suggested)
            .to_svg()
            .map_err(|e| CliError::bad_input(format!("plot: {e}")))?;
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::bad_input(format!("{}: {e}", dir.display())))?;
        let path = dir.join("response.svg");
        std::fs::write(&path, svg)
            .map_err(|e| CliError::bad_input(format!("{}: {e}", path.display())))?;
    }
    if args.json {
        outln!(
            "{:#}",
            serde_json::json!({
                "position_mm": centre,
                "sweep": sweep,
                "axes": axes,
                "model": model[0].modes,
                "shapers": rows,
                "suggested": suggested,
                "target_residual": TARGET_RESIDUAL,
            })
        )?;
        return Ok(());
    }
    outln!(
        "sweep {:.0}–{:.0} Hz over {:.0} s per axis, {:.0} mm/s² per Hz within the ceilings, at ({:.1}, {:.1}, {:.1}) mm (simulated flexible plant)",
        sweep.from_hz,
        sweep.to_hz,
        sweep.duration_s,
        sweep.accel_per_hz * 1e3,
        centre[0],
        centre[1],
        centre[2]
    )?;
    for a in &axes {
        let peaks: Vec<String> = a
            .modes
            .iter()
            .map(|m| format!("{:.2} Hz ζ {:.3} (×{:.1})", m.hz, m.damping, m.peak))
            .collect();
        outln!(
            "axis {}: peaks {}; ring-down ζ {}; sweep peak {:.2} m/s², {:.0} m/s³, {:.3} N·m, following error {:.1} µm",
            a.axis + 1,
            if peaks.is_empty() {
                "none".to_string()
            } else {
                peaks.join(", ")
            },
            a.ringdown_damping
                .map_or("—".to_string(), |d| format!("{d:.3}")),
            a.peak_accel_m_s2,
            a.peak_jerk_m_s3,
            a.peak_torque_nm,
            a.max_following_error_m * 1e6
        )?;
    }
    if axes.iter().any(|a| a.ringdown_damping.is_none()) {
        outln!(
            "warning: a ring-down was lost in the accelerometer's {:.1} mg counts: that axis's damping is the sweep's fit, unreliable at this amplitude (the ceilings bound it)",
            triquint_sim::resonance::ACCEL_COUNT_M_S2 / 9.80665 * 1e3
        )?;
    }
    let m: Vec<String> = model[0]
        .modes
        .iter()
        .take(3)
        .map(|m| format!("{:.2} Hz ζ {:.3}", m.hz, m.damping))
        .collect();
    outln!("model (motors held): {}", m.join(", "))?;
    print_shapers(&rows, suggested)
}

fn print_shapers(rows: &[ShaperRow], suggested: Option<&ShaperRow>) -> CliResult {
    outln!(
        "{:<9} {:>8} {:>7} {:>10} {:>14}",
        "shaper",
        "Hz",
        "ζ",
        "adds (ms)",
        "worst residual"
    )?;
    for r in rows {
        outln!(
            "{:<9} {:>8.1} {:>7.3} {:>10.1} {:>13.1} %",
            r.shaper.name(),
            r.frequency_hz,
            r.damping,
            r.duration_ms,
            r.worst_residual * 100.0
        )?;
    }
    if let Some(s) = suggested {
        outln!(
            "suggested: [shaper] type = \"{}\", frequency_hz = {:.1}, damping = {:.3}  (triquint plan --shaper {}:{:.1}:{:.3})",
            s.shaper.name(),
            s.frequency_hz,
            s.damping,
            s.shaper.name(),
            s.frequency_hz,
            s.damping
        )?;
    }
    Ok(())
}

/// `centre` (mm) first, then the other poses of an `n` × `n` grid over
/// ±[`ACROSS_HALF_MM`] at its height that are inside the travel.
fn grid(machine: &Machine, centre: [f64; 3], n: usize) -> CliResult<Vec<[f64; 3]>> {
    if !(1..=9).contains(&n) {
        return Err(CliError::bad_input(format!(
            "--grid {n}: 1 to 9 poses per side"
        )));
    }
    let offset = |i: usize| match n {
        1 => 0.0,
        _ => -ACROSS_HALF_MM + 2.0 * ACROSS_HALF_MM * i as f64 / (n - 1) as f64,
    };
    let mut poses = vec![centre];
    for i in 0..n {
        for j in 0..n {
            let (x, y) = (offset(i), offset(j));
            let p = [centre[0] + x, centre[1] + y, centre[2]];
            let inside =
                Pose::from_cartesian(&machine.robot.model::<f64>(), Vector3::from(p) * 1e-3)
                    .is_ok_and(|pose| machine.travel().outside(&pose.q.into()).is_none());
            if (x, y) != (0.0, 0.0) && inside {
                poses.push(p);
            }
        }
    }
    Ok(poses)
}

/// One measured peak beside the model's nearest mode.
#[derive(Serialize)]
struct PeakRow {
    axis: usize,
    hz: f64,
    /// The fit's damping ratio, and for an axis's lowest peak the ring-down's.
    damping: f64,
    ringdown_damping: Option<f64>,
    model_hz: f64,
    model_damping: f64,
    /// (measured − model) / model.
    deviation: f64,
}

#[derive(Serialize)]
struct PoseMeasured {
    position_mm: [f64; 3],
    peaks: Vec<PeakRow>,
}

/// Each axis's peaks at one pose beside the model's nearest modes.
fn compare(axes: &[AxisResponse], model: &PoseModes) -> Vec<PeakRow> {
    axes.iter()
        .flat_map(|a| {
            a.modes.iter().enumerate().filter_map(move |(k, m)| {
                let near = model
                    .modes
                    .iter()
                    .min_by(|x, y| (x.hz - m.hz).abs().total_cmp(&(y.hz - m.hz).abs()))?;
                Some(PeakRow {
                    axis: a.axis,
                    hz: m.hz,
                    damping: m.damping,
                    ringdown_damping: if k == 0 { a.ringdown_damping } else { None },
                    model_hz: near.hz,
                    model_damping: near.damping,
                    deviation: (m.hz - near.hz) / near.hz,
                })
            })
        })
        .collect()
}

/// Sweeps each axis at every pose of `poses` (mm) and prints the peaks
/// against the model, the worst deviation and the shaper for them all.
fn run_across(args: &ResonanceArgs, machine: &Machine, poses: &[[f64; 3]]) -> CliResult {
    let sweep = sweep(args);
    let model = modes(machine, poses).map_err(|e| CliError::bad_input(e.to_string()))?;
    let mut all_axes = Vec::new();
    let mut rows = Vec::new();
    for (p, m) in poses.iter().zip(&model) {
        let axes = triquint_sim::resonance::measure(machine, Vector3::from(*p) * 1e-3, &sweep)
            .map_err(|e| {
                CliError::bad_input(format!("({:.1}, {:.1}, {:.1}) mm: {e}", p[0], p[1], p[2]))
            })?;
        rows.push(PoseMeasured {
            position_mm: *p,
            peaks: compare(&axes, m),
        });
        all_axes.extend(axes);
    }
    let worst = rows
        .iter()
        .flat_map(|p| p.peaks.iter().map(move |k| (p.position_mm, k)))
        .max_by(|a, b| a.1.deviation.abs().total_cmp(&b.1.deviation.abs()));
    let targets = measured_targets(&all_axes);
    if targets.is_empty() || worst.is_none() {
        return Err(CliError::bad_input(format!(
            "no resonance found between {} and {} Hz",
            sweep.from_hz, sweep.to_hz
        )));
    }
    let shaper_rows = shapers(&targets);
    let suggested = suggestion(&shaper_rows);
    if args.json {
        outln!(
            "{:#}",
            serde_json::json!({
                "sweep": sweep,
                "poses": rows,
                "worst_deviation": worst.map(|w| w.1.deviation),
                "shapers": shaper_rows,
                "suggested": suggested,
                "target_residual": TARGET_RESIDUAL,
            })
        )?;
        return Ok(());
    }
    outln!(
        "sweep {:.0}–{:.0} Hz over {:.0} s per axis at each of {} poses (simulated flexible plant); measured against the model (motors held)",
        sweep.from_hz,
        sweep.to_hz,
        sweep.duration_s,
        poses.len()
    )?;
    for p in &rows {
        let cells: Vec<String> = p
            .peaks
            .iter()
            .map(|k| {
                format!(
                    "axis {} {:.2} Hz ζ {:.3}{} vs {:.2} Hz ζ {:.3} ({:+.2} %)",
                    k.axis + 1,
                    k.hz,
                    k.damping,
                    k.ringdown_damping
                        .map_or(String::new(), |d| format!(" ring-down {d:.3}")),
                    k.model_hz,
                    k.model_damping,
                    k.deviation * 100.0
                )
            })
            .collect();
        outln!(
            "({:.1}, {:.1}, {:.1}) mm: {}",
            p.position_mm[0],
            p.position_mm[1],
            p.position_mm[2],
            cells.join("; ")
        )?;
    }
    if let Some((at, k)) = worst {
        outln!(
            "worst deviation from the model: {:+.2} % (axis {}, {:.2} against {:.2} Hz at ({:.1}, {:.1}, {:.1}) mm)",
            k.deviation * 100.0,
            k.axis + 1,
            k.hz,
            k.model_hz,
            at[0],
            at[1],
            at[2]
        )?;
    }
    print_shapers(&shaper_rows, suggested)
}

pub fn run(args: &ResonanceArgs, machine: &Machine) -> CliResult {
    let centre: [f64; 3] = match &args.at {
        Some(text) => triquint_cli_common::parse::parse_triple("--at", text)?.into(),
        None => FlexParams::for_machine(machine)
            .reference_pose
            .map(|x| x * 1e3),
    };
    if !(args.model || args.across) {
        return run_measured(args, machine, centre);
    }
    let poses = match args.across {
        true => {
            let n = args.grid.unwrap_or(if args.model {
                MODEL_GRID
            } else {
                MEASURED_GRID
            });
            grid(machine, centre, n)?
        }
        false => vec![centre],
    };
    if !args.model {
        return run_across(args, machine, &poses);
    }
    let found = modes(machine, &poses).map_err(|e| CliError::bad_input(e.to_string()))?;
    let rows = shapers(&targets(&found));
    let suggested = suggestion(&rows);
    if args.json {
        outln!(
            "{:#}",
            serde_json::json!({
                "poses": found,
                "shapers": rows,
                "suggested": suggested,
                "target_residual": TARGET_RESIDUAL,
            })
        )?;
        return Ok(());
    }
    for p in &found {
        let cells: Vec<String> = p
            .modes
            .iter()
            .map(|m| {
                format!(
                    "{:.1} Hz ζ {:.3}{}",
                    m.hz,
                    m.damping,
                    if m.platform_share > 0.5 {
                        " (platform)"
                    } else {
                        ""
                    }
                )
            })
            .collect();
        outln!(
            "({:.1}, {:.1}, {:.1}) mm: {}",
            p.position_mm[0],
            p.position_mm[1],
            p.position_mm[2],
            cells.join(", ")
        )?;
    }
    let t = targets(&found);
    let lo = t.iter().map(|t| t.0).fold(f64::INFINITY, f64::min);
    let hi = t.iter().map(|t| t.0).fold(0.0, f64::max);
    outln!(
        "lowest modes {lo:.1}–{hi:.1} Hz over {} pose{}",
        found.len(),
        if found.len() == 1 { "" } else { "s" }
    )?;
    print_shapers(&rows, suggested)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_suggestion_is_the_shortest_shaper_within_five_per_cent() {
        let machine = Machine::default();
        let at = modes(&machine, &[[0.0, 0.0, 600.0]]).unwrap();
        let t = targets(&at);
        // The lateral pair at the centre, degenerate.
        assert!(t.len() >= 2, "{t:?}");
        let rows = shapers(&t);
        assert_eq!(rows.len(), Shaper::ALL.len());
        // One pose: ZV at the pair's frequency cancels it.
        let s = suggestion(&rows).unwrap();
        assert_eq!(s.shaper, Shaper::Zv, "{:?}", s.shaper);
        assert!(
            (s.frequency_hz - t[0].0).abs() <= 0.1,
            "{} vs {t:?}",
            s.frequency_hz
        );
        assert!(s.worst_residual <= TARGET_RESIDUAL);

        // Across the grid the lowest modes spread: ZV no longer holds them
        // within 5 %, a more robust shaper does, and every residual is what
        // the impulses leave at every target.
        let poses = grid(&machine, [0.0, 0.0, 600.0], MODEL_GRID).unwrap();
        assert_eq!(poses.len(), 25, "{poses:?}");
        let across = modes(&machine, &poses).unwrap();
        let t = targets(&across);
        let rows = shapers(&t);
        let zv = rows.iter().find(|r| r.shaper == Shaper::Zv).unwrap();
        assert!(zv.worst_residual > TARGET_RESIDUAL, "{}", zv.worst_residual);
        let s = suggestion(&rows).unwrap();
        assert_ne!(s.shaper, Shaper::Zv);
        assert!(s.worst_residual <= TARGET_RESIDUAL, "{}", s.worst_residual);
        let imp = Impulses::new(s.shaper, s.frequency_hz, s.damping).unwrap();
        for (hz, z) in &t {
            assert!(imp.residual(*hz, *z) <= s.worst_residual + 1e-3);
        }
        // A pose outside the workspace is named, not a panic.
        let e = modes(&machine, &[[0.0, 0.0, 100.0]]).err().unwrap();
        assert!(e.to_string().starts_with("(0.0, 0.0, 100.0) mm:"), "{e}");
    }
}

#[cfg(test)]
mod across_tests {
    use super::*;

    /// `--across` measures: at the centre and two edges of the grid, swept
    /// around the lateral pair, every peak lies within 1 % of the model's
    /// nearest mode (the 20 s sweep finds them within 0.6 %:
    /// docs/input-shaping.md), and every axis's ring-down damping within
    /// 30 % of the centre's mean (the damping tolerance; the rotors'
    /// friction that sets it does not depend on the pose).
    #[test]
    fn across_the_grid_the_measured_peaks_are_the_models() {
        let machine = Machine::default();
        let sweep = Sweep {
            from_hz: 15.0,
            to_hz: 45.0,
            duration_s: 6.0,
            ..Sweep::default()
        };
        let poses = [[0.0, 0.0, 600.0], [-120.0, 0.0, 600.0], [0.0, 120.0, 600.0]];
        let model = modes(&machine, &poses).unwrap();
        let mut centre_damping = None;
        for (p, m) in poses.iter().zip(&model) {
            let axes = triquint_sim::resonance::measure(&machine, Vector3::from(*p) * 1e-3, &sweep)
                .unwrap();
            let rows = compare(&axes, m);
            assert!(rows.len() >= 3, "{p:?}: {} peaks", rows.len());
            let ringdown: Vec<f64> = rows.iter().filter_map(|r| r.ringdown_damping).collect();
            assert_eq!(ringdown.len(), 3, "{p:?}: a ring-down lost");
            let mean = ringdown.iter().sum::<f64>() / 3.0;
            let centre = *centre_damping.get_or_insert(mean);
            for r in &rows {
                eprintln!(
                    "{p:?} axis {}: {:.3} Hz vs {:.3} ({:+.3} %), ring-down {:?}",
                    r.axis + 1,
                    r.hz,
                    r.model_hz,
                    r.deviation * 100.0,
                    r.ringdown_damping
                );
                assert!(r.deviation.abs() <= 0.01, "{p:?}: {:.4}", r.deviation);
                if let Some(d) = r.ringdown_damping {
                    assert!((d - centre).abs() <= 0.3 * centre, "{p:?}: {d} vs {centre}");
                }
            }
        }
        // A grid of no poses is refused.
        assert!(grid(&machine, [0.0, 0.0, 600.0], 0).is_err());
        assert_eq!(grid(&machine, [0.0, 0.0, 600.0], 1).unwrap().len(), 1);
    }
}
