//! The paper's Figures 10/12 as SVG: joint position, velocity, acceleration,
//! jerk and torque against time (three joints per chart, limits dashed, knots
//! dotted), the platform path in 3-D by forward kinematics, and an overview
//! with all six panels.

use triquint_shared::kinematics::Pose;
use triquint_shared::plan::Plan;

use super::ReportError;
use super::extrema::{derivative, roots_in};
use super::knot_labels::knot_labels;
use super::stats::{PlanStats, Quantity, segment_torque};
use triquint_plot::{Chart, Figure, Line, Path3d, PlotError};

/// Approximate number of samples over the whole plan (plus each segment's
/// extremum times, so drawn peaks are the exact ones).
const SAMPLES: usize = 1500;
/// A limit is drawn when the peak reaches at least this fraction of it;
/// otherwise a note says it is off scale (drawing it would flatten the data).
const LIMIT_DRAW_FRACTION: f64 = 0.25;

/// Samples of the plan at increasing times.
struct Samples {
    t: Vec<f64>,
    /// [quantity][joint][sample]: q (mm), v, a, jerk, τ.
    values: [[Vec<f64>; 3]; 5],
    /// Platform position (mm).
    path: Vec<[f64; 3]>,
}

fn sample(plan: &Plan) -> Result<Samples, ReportError> {
    let model = plan.robot.model::<f64>();
    let total: f64 = plan.segments.iter().map(|s| s.duration_s).sum();
    let mut out = Samples {
        t: Vec::new(),
        values: Default::default(),
        path: Vec::new(),
    };
    for (i, seg) in plan.segments.iter().enumerate() {
        let h = seg.duration_s;
        let n = ((SAMPLES as f64 * h / total).ceil() as usize).max(40);
        let mut times: Vec<f64> = (0..=n).map(|k| h * k as f64 / n as f64).collect();
        for c in &seg.coeffs {
            let mut d = derivative(c);
            for _ in 0..3 {
                let dd = derivative(&d);
                times.extend(roots_in(&dd, 0.0, h));
                d = dd;
            }
        }
        times.sort_by(f64::total_cmp);
        times.dedup();
        if i > 0 {
            times.remove(0); // the previous segment's end
        }
        let quintic = seg.quintic();
        for t in times {
            let m = quintic.eval(t);
            let tau = segment_torque(&model, seg, i, t)?;
            out.t.push(seg.t0_s + t);
            for j in 0..3 {
                out.values[0][j].push(m.q[j] * 1e3);
                out.values[1][j].push(m.qd[j]);
                out.values[2][j].push(m.qdd[j]);
                out.values[3][j].push(m.qddd[j]);
                out.values[4][j].push(tau[j]);
            }
            let pose =
                Pose::from_joints(&model, m.q).map_err(|source| ReportError::Kinematics {
                    segment: i + 1,
                    time_s: seg.t0_s + t,
                    source,
                })?;
            out.path.push((pose.r * 1e3).into());
        }
    }
    Ok(out)
}

/// Knot times: each segment's start and the plan's end.
/// The knots' times and labels ([`knot_labels`]).
fn knot_times(plan: &Plan) -> Vec<(f64, String)> {
    let mut t: Vec<f64> = plan.segments.iter().map(|s| s.t0_s).collect();
    if let Some(last) = plan.segments.last() {
        t.push(last.t0_s + last.duration_s);
    }
    t.into_iter().zip(knot_labels(plan)).collect()
}

fn time_chart(
    title: &str,
    y_label: &str,
    samples: &Samples,
    q: usize,
    knots: &[(f64, String)],
) -> Chart {
    let mut chart = Chart::new(title).x_label("time (s)").y_label(y_label);
    for j in 0..3 {
        let pts: Vec<(f64, f64)> = samples
            .t
            .iter()
            .zip(&samples.values[q][j])
            .map(|(&t, &v)| (t, v))
            .collect();
        chart = chart.line(Line::joint(j, format!("joint {}", j + 1), pts));
    }
    for (t, label) in knots {
        chart = chart.knot(*t, label.clone());
    }
    if let (Some(&(a, _)), Some(&(b, _))) = (knots.first(), knots.last()) {
        chart = chart.x_range(a, b);
    }
    chart
}

/// Adds ±limit lines, or a note when the limit is far off the data's scale.
fn with_limit(chart: Chart, name: &str, unit: &str, stat: &Quantity, limit: f64) -> Chart {
    let peak = stat.max.iter().copied().fold(0.0, f64::max);
    let chart = chart.note(format!(
        "max |{name}|: joint 1 {:.4}, joint 2 {:.4}, joint 3 {:.4} {unit}",
        stat.max[0], stat.max[1], stat.max[2]
    ));
    if peak >= LIMIT_DRAW_FRACTION * limit {
        chart
            .limit(limit, format!("+{limit} {unit}"))
            .limit(-limit, format!("−{limit} {unit}"))
    } else {
        chart.note(format!(
            "limit ±{limit} {unit} not drawn (off scale: the peak is {:.1} % of it)",
            100.0 * peak / limit
        ))
    }
}

/// Labels P1..Pn, with a repeated point (closed path) labelled once as "P1 = P11".
fn via_labels(points: &[[f64; 3]]) -> Vec<String> {
    let mut labels: Vec<String> = (1..=points.len()).map(|k| format!("P{k}")).collect();
    for k in 0..points.len() {
        for m in 0..k {
            let same = (0..3).all(|a| (points[k][a] - points[m][a]).abs() < 1e-6);
            if same && !labels[m].is_empty() {
                labels[m] = format!("{} = P{}", labels[m], k + 1);
                labels[k].clear();
                break;
            }
        }
    }
    labels
}

/// All plots as (file name, SVG document): position, velocity, acceleration,
/// jerk, torque, path3d and overview.
pub fn plots(plan: &Plan, stats: &PlanStats) -> Result<Vec<(&'static str, String)>, ReportError> {
    let s = sample(plan)?;
    let knots = knot_times(plan);
    let l = &plan.limits;
    let position = time_chart(
        "(a) Joint position",
        "slider position q (mm)",
        &s,
        0,
        &knots,
    );
    let velocity = with_limit(
        time_chart("(b) Joint velocity", "velocity (m/s)", &s, 1, &knots),
        "v",
        "m/s",
        &stats.velocity,
        l.velocity,
    );
    let acceleration = with_limit(
        time_chart(
            "(c) Joint acceleration",
            "acceleration (m/s²)",
            &s,
            2,
            &knots,
        ),
        "a",
        "m/s²",
        &stats.acceleration,
        l.acceleration,
    );
    let jerk = with_limit(
        time_chart("(d) Joint jerk", "jerk (m/s³)", &s, 3, &knots),
        "jerk",
        "m/s³",
        &stats.jerk,
        l.jerk,
    );
    let torque = with_limit(
        time_chart("(e) Joint torque", "motor torque τ (N·m)", &s, 4, &knots),
        "τ",
        "N·m",
        &stats.torque,
        l.torque,
    );
    let via_mm: Vec<[f64; 3]> = plan
        .via_points_m
        .iter()
        .map(|p| p.map(|v| v * 1e3))
        .collect();
    let path = Path3d::new("(f) Platform path (forward kinematics)")
        .unit("mm")
        .path("platform path", &s.path)
        .markers("via points", &via_mm, &via_labels(&via_mm));
    let overview = Figure::new(
        format!(
            "Plan: {} segments, T = {:.3} s, max |jerk| = {:.4} m/s³",
            plan.segments.len(),
            stats.total_time_s,
            stats.jerk.max.iter().copied().fold(0.0, f64::max)
        ),
        3,
        (640, 460),
    )
    .panel(position.clone())
    .panel(velocity.clone())
    .panel(acceleration.clone())
    .panel(jerk.clone())
    .panel(torque.clone())
    .panel(path.clone());
    let svg = |r: Result<String, PlotError>| r.map_err(ReportError::from);
    Ok(vec![
        ("position.svg", svg(position.to_svg())?),
        ("velocity.svg", svg(velocity.to_svg())?),
        ("acceleration.svg", svg(acceleration.to_svg())?),
        ("jerk.svg", svg(jerk.to_svg())?),
        ("torque.svg", svg(torque.to_svg())?),
        ("path3d.svg", svg(path.projections(true).to_svg())?),
        ("overview.svg", svg(overview.to_svg())?),
    ])
}
