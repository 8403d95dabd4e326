//! Charts of a simulation run (`triquint simulate --plot`): reference and
//! measured joint positions, tracking error, torque command, feedforward
//! against the total, and an overview of the four.

use triquint_plot::{Chart, DARK, Figure, Line, PlotError, Stroke};
use triquint_shared::dynamics;
use triquint_shared::plan::Plan;
use triquint_sim::flex::AccelSample;
use triquint_sim::metrics::plan_position;
use triquint_sim::vibration::Residual;

use super::ReportError;
use super::knot_labels::knot_labels;
use crate::inprocess::simulate::{SimReport, SimulateOptions};

const TIME: &str = "time since start (s)";

/// The plan's knots as (time, "Pk") for dotted markers.
fn knots(plan: &Plan) -> Vec<(f64, String)> {
    let mut t: Vec<f64> = plan.segments.iter().map(|s| s.t0_s).collect();
    if let Some(last) = plan.segments.last() {
        t.push(last.t0_s + last.duration_s);
    }
    t.into_iter().zip(knot_labels(plan)).collect()
}

fn with_knots(mut chart: Chart, knots: &[(f64, String)]) -> Chart {
    for (t, label) in knots {
        chart = chart.knot(*t, label.clone());
    }
    chart
}

/// The drives' inverse-dynamics feedforward along the plan (N·m), as the
/// firmware computes it: the model torque 1.5 ticks ahead plus the identified
/// friction, smoothed through zero speed. Recomputed here in f64 from the
/// plan (the drives do not report it), over the plan's duration only.
fn feedforward(plan: &Plan, opts: &SimulateOptions, t: f64) -> Option<[f64; 3]> {
    let model = plan.robot.model::<f64>();
    let ahead = (t + 1.5 / opts.rate_hz).min(plan.total_time_s);
    let idx = plan
        .segments
        .partition_point(|s| s.t0_s + s.duration_s < ahead)
        .min(plan.segments.len().checked_sub(1)?);
    let seg = plan.segments.get(idx)?;
    let m = seg
        .quintic()
        .eval((ahead - seg.t0_s).clamp(0.0, seg.duration_s));
    let tau = dynamics::torque(&model, &m.q, &m.qd, &m.qdd).ok()?;
    let s = &opts.settings;
    Some([0, 1, 2].map(|j| {
        let v = m.qd[j];
        let sign = (1000.0 * v).clamp(-20.0, 20.0).tanh();
        tau[j] + (s.friction_coulomb * sign + s.friction_viscous * v) * model.inv_ratio
    }))
}

/// All charts of a run as (file name, SVG document).
pub fn sim_plots(
    plan: &Plan,
    opts: &SimulateOptions,
    r: &SimReport,
) -> Result<Vec<(&'static str, String)>, ReportError> {
    let start = r.start_us as f64 * 1e-6;
    let t = |ns: u64| ns as f64 * 1e-9 - start;
    let knots = knots(plan);
    let end = plan.total_time_s;
    let first = r.samples.first().map_or(0.0, |s| t(s.t_ns));
    let last = r.samples.last().map_or(end, |s| t(s.t_ns));
    let (lo, hi) = (first.min(0.0), last.max(end));

    let mut position = Chart::new("Joint position: reference and measured")
        .x_label(TIME)
        .y_label("slider position q (mm)")
        .x_range(lo, hi);
    for j in 0..3 {
        // Before the start the drives' reference is their hold (or 0 before arming).
        let reference = r
            .samples
            .iter()
            .filter(|s| t(s.t_ns) >= 0.0)
            .map(|s| (t(s.t_ns), s.reference[j] as f64 * 1e3))
            .collect();
        let measured = r
            .samples
            .iter()
            .map(|s| (t(s.t_ns), s.q[j] * 1e3))
            .collect();
        position = position
            .line(
                Line::joint(j, format!("joint {} reference", j + 1), reference)
                    .stroke(Stroke::Wide),
            )
            .line(
                Line::joint(j, format!("joint {} measured", j + 1), measured).stroke(Stroke::Thin),
            );
    }
    let position = with_knots(position, &knots);

    let mut error = Chart::new("Tracking error (plant − plan)")
        .x_label(TIME)
        .y_label("tracking error (µm)")
        .x_range(lo, hi)
        .note(format!(
            "RMS: joint 1 {:.2}, joint 2 {:.2}, joint 3 {:.2} µm; max |e|: {:.2}, {:.2}, {:.2} µm",
            r.run.rms_error_m[0] * 1e6,
            r.run.rms_error_m[1] * 1e6,
            r.run.rms_error_m[2] * 1e6,
            r.run.max_error_m[0] * 1e6,
            r.run.max_error_m[1] * 1e6,
            r.run.max_error_m[2] * 1e6,
        ));
    for j in 0..3 {
        let pts = r
            .samples
            .iter()
            .filter(|s| t(s.t_ns) >= 0.0)
            .map(|s| {
                let ts = t(s.t_ns);
                (ts, (s.q[j] - plan_position(plan, ts)[j]) * 1e6)
            })
            .collect();
        error = error.line(Line::joint(j, format!("joint {}", j + 1), pts));
    }
    let error = with_knots(error, &knots);

    let mut torque = Chart::new("Motor torque command")
        .x_label(TIME)
        .y_label("torque command τ (N·m)")
        .x_range(lo, hi)
        .note(format!(
            "peak |τ|: joint 1 {:.4}, joint 2 {:.4}, joint 3 {:.4} N·m (limit ±{} N·m)",
            r.run.peak_torque_nm[0],
            r.run.peak_torque_nm[1],
            r.run.peak_torque_nm[2],
            plan.limits.torque
        ));
    for j in 0..3 {
        let pts = r
            .samples
            .iter()
            .map(|s| (t(s.t_ns), s.torque[j] as f64))
            .collect();
        torque = torque.line(Line::joint(j, format!("joint {}", j + 1), pts));
    }
    let torque = with_knots(torque, &knots);

    let ff_name = if opts.feedforward {
        "feedforward (model)"
    } else {
        "feedforward (model; off in this run)"
    };
    let mut ff = Chart::new("Feedforward against the total torque command")
        .x_label(TIME)
        .y_label("torque τ (N·m)")
        .x_range(lo, hi)
        .note(if opts.feedforward {
            "dashed: the inverse-dynamics feedforward the drives add; solid: their whole command"
        } else {
            "feedback only: dashed is the inverse-dynamics torque a feedforward would have added"
        });
    let model_ff: Vec<(f64, [f64; 3])> = r
        .samples
        .iter()
        .map(|s| t(s.t_ns))
        .filter(|&ts| (0.0..=end).contains(&ts))
        .filter_map(|ts| feedforward(plan, opts, ts).map(|f| (ts, f)))
        .collect();
    for j in 0..3 {
        let total = r
            .samples
            .iter()
            .map(|s| (t(s.t_ns), s.torque[j] as f64))
            .collect();
        ff = ff.line(Line::joint(j, format!("joint {} total", j + 1), total));
    }
    for j in 0..3 {
        let f = model_ff.iter().map(|(ts, f)| (*ts, f[j])).collect();
        // One legend entry for the three (dark, over each joint's total).
        let name = if j == 0 { ff_name } else { "" };
        ff = ff.line(Line::new(name, DARK, f).stroke(Stroke::Dashed));
    }
    let ff = with_knots(ff, &knots);

    let overview = Figure::new(
        format!(
            "Simulation: feedforward {}, {} Hz control, RMS error ≤ {:.2} µm, peak |τ| {:.3} N·m",
            if opts.feedforward { "on" } else { "off" },
            opts.rate_hz,
            r.run.rms_error_m.iter().copied().fold(0.0, f64::max) * 1e6,
            r.run.peak_torque_nm.iter().copied().fold(0.0, f64::max),
        ),
        2,
        (900, 520),
    )
    .panel(position.clone())
    .panel(error.clone())
    .panel(torque.clone())
    .panel(ff.clone());
    let svg = |c: Result<String, PlotError>| c.map_err(ReportError::from);
    let mut out = vec![
        ("position.svg", svg(position.to_svg())?),
        ("tracking_error.svg", svg(error.to_svg())?),
        ("torque.svg", svg(torque.to_svg())?),
        ("feedforward.svg", svg(ff.to_svg())?),
        ("overview.svg", svg(overview.to_svg())?),
    ];
    if !r.accel.is_empty() {
        let title = format!("Platform accelerometer: plan of {:.3} s", plan.total_time_s);
        out.push((
            "accelerometer.svg",
            accelerometer(&title, &r.accel, start, end, r.run.vibration.as_ref())?,
        ));
    }
    Ok(out)
}

/// The flexible plant's accelerometer (per axis) against time since the
/// reference's start `start_s` (plant time): the whole run in m/s², and the
/// settle window of `residual` after the end (`end`, since the start)
/// magnified, in mm/s², with its figures.
pub fn accelerometer(
    title: &str,
    accel: &[AccelSample],
    start_s: f64,
    end: f64,
    residual: Option<&Residual>,
) -> Result<String, ReportError> {
    let window = residual.map_or(0.5, |v| v.window_s);
    let (from, to) = (-0.2, end + window);
    let trace = |k: usize, lo: f64, hi: f64, scale: f64| -> Vec<(f64, f64)> {
        accel
            .iter()
            .map(|s| (s.t_s - start_s, s.accel[k] * scale))
            .filter(|p| (lo..=hi).contains(&p.0))
            .collect()
    };
    let mut whole = Chart::new("The whole run")
        .x_label(TIME)
        .y_label("platform acceleration (m/s²)")
        .x_range(from, to)
        .knot(end, "end");
    let mut settle = Chart::new("After the end: the residual vibration")
        .x_label(TIME)
        .y_label("platform acceleration (mm/s²)")
        .x_range(end, to)
        .note(match residual {
            Some(v) => format!(
                "{:.2} s window: |a| peak {:.1} RMS {:.1} mm/s²; position peak {:.3} RMS {:.3} µm{}",
                v.window_s,
                v.peak_accel_m_s2 * 1e3,
                v.rms_accel_m_s2 * 1e3,
                v.peak_position_m * 1e6,
                v.rms_position_m * 1e6,
                v.dominant_hz
                    .map_or(String::new(), |f| format!("; dominant {f:.1} Hz"))
            ),
            None => "no settle window recorded".to_string(),
        });
    for (k, axis) in ["x", "y", "z"].iter().enumerate() {
        whole = whole.line(Line::joint(k, format!("a_{axis}"), trace(k, from, to, 1.0)));
        settle = settle
            .line(Line::joint(k, format!("a_{axis}"), trace(k, end, to, 1e3)).stroke(Stroke::Thin));
    }
    Figure::new(title, 1, (900, 420))
        .panel(whole)
        .panel(settle)
        .to_svg()
        .map_err(ReportError::from)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::inprocess::simulate::simulate;

    fn case1() -> Plan {
        let text = include_str!("../../../testdata/protocol/plans/case1-spline.json");
        triquint_planner::files::parse_plan(text).unwrap()
    }

    /// The recomputed feedforward is the drives' own: with feedforward on,
    /// what the feedback adds on top of it stays a small part of the command.
    #[test]
    fn recomputed_feedforward_matches_the_drives_command() {
        let plan = case1();
        let opts = SimulateOptions::default();
        let r = simulate(&plan, &opts).unwrap();
        let start = r.start_us as f64 * 1e-6;
        let (mut rest, mut ff_sq, mut n) = (0.0, 0.0, 0);
        for s in &r.samples {
            let t = s.t_ns as f64 * 1e-9 - start;
            // Away from the start's transient.
            if !(0.2..=plan.total_time_s).contains(&t) {
                continue;
            }
            let f = feedforward(&plan, &opts, t).unwrap();
            for (total, f) in s.torque.iter().zip(f) {
                rest += (*total as f64 - f).powi(2);
                ff_sq += f * f;
                n += 1;
            }
        }
        assert!(n > 1000);
        let ratio = (rest / ff_sq).sqrt();
        assert!(ratio < 0.15, "feedback is {ratio:.3} of the feedforward");
    }

    #[test]
    fn every_chart_is_drawn_for_a_run_without_samples() {
        let plan = case1();
        let opts = SimulateOptions::default();
        let mut r = simulate(&plan, &opts).unwrap();
        r.samples.clear();
        let files = sim_plots(&plan, &opts, &r).unwrap();
        assert_eq!(files.len(), 5);
        assert!(files.iter().all(|(_, s)| s.trim_end().ends_with("</svg>")));
    }
}
