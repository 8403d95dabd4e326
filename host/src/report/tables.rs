//! The statistics as aligned text tables: intervals and per-segment maxima
//! (paper Tables 4/7) and per-joint max and mean (paper Tables 5/8).

use std::fmt::Write as _;

use triquint_shared::plan::{Objective, Plan};

use super::knot_labels::knot_labels;
use super::stats::{PlanStats, Quantity};

/// Left-aligned first column, right-aligned others, two spaces between.
fn render(header: &[String], rows: &[Vec<String>]) -> String {
    let cols = header.len();
    let width = |c: usize| {
        rows.iter()
            .map(|r| r[c].chars().count())
            .chain([header[c].chars().count()])
            .max()
            .unwrap_or(0)
    };
    let widths: Vec<usize> = (0..cols).map(width).collect();
    let line = |cells: &[String]| {
        let mut s = String::new();
        for (c, cell) in cells.iter().enumerate() {
            if c == 0 {
                let _ = write!(s, "{cell:<w$}", w = widths[0]);
            } else {
                let _ = write!(s, "  {cell:>w$}", w = widths[c]);
            }
        }
        s.trim_end().to_string()
    };
    let mut out = line(header);
    out.push('\n');
    out.push_str(&"-".repeat(widths.iter().sum::<usize>() + 2 * (cols - 1)));
    out.push('\n');
    for r in rows {
        out.push_str(&line(r));
        out.push('\n');
    }
    out
}

fn max3(v: &[f64; 3]) -> f64 {
    v.iter().copied().fold(0.0, f64::max)
}

/// Intervals (paper Tables 4/7) with each segment's maxima over the three joints.
pub fn intervals_table(plan: &Plan, stats: &PlanStats) -> String {
    let header: Vec<String> = [
        "segment",
        "t0 (s)",
        "h (s)",
        "max|v| (m/s)",
        "max|a| (m/s²)",
        "max|jerk| (m/s³)",
        "max|τ| (N·m)",
    ]
    .map(String::from)
    .to_vec();
    let labels = knot_labels(plan);
    let label = |k: usize| {
        labels
            .get(k)
            .cloned()
            .unwrap_or_else(|| format!("P{}", k + 1))
    };
    let mut rows: Vec<Vec<String>> = stats
        .segments
        .iter()
        .map(|s| {
            vec![
                format!("h{:<2} {}→{}", s.index, label(s.index - 1), label(s.index)),
                format!("{:.6}", s.t0_s),
                format!("{:.6}", s.duration_s),
                format!("{:.5}", max3(&s.max_velocity)),
                format!("{:.5}", max3(&s.max_acceleration)),
                format!("{:.5}", max3(&s.max_jerk)),
                format!("{:.5}", max3(&s.max_torque)),
            ]
        })
        .collect();
    rows.push(vec![
        "T (total)".into(),
        String::new(),
        format!("{:.6}", stats.total_time_s),
        format!("{:.5}", max3(&stats.velocity.max)),
        format!("{:.5}", max3(&stats.acceleration.max)),
        format!("{:.5}", max3(&stats.jerk.max)),
        format!("{:.5}", max3(&stats.torque.max)),
    ]);
    let mut out = format!(
        "Intervals ({} segments, objective {}, limit T ≤ {} s)\n",
        stats.segments.len(),
        match plan.objective {
            Objective::MinMaxJerk => "min-max-jerk",
            Objective::MinTime => "min-time",
        },
        plan.limits.total_time
    );
    out.push_str(&render(&header, &rows));
    out
}

/// Per-joint max and mean of |v|, |a|, |jerk|, |τ| (paper Tables 5/8), with the limits.
pub fn joint_table(plan: &Plan, stats: &PlanStats) -> String {
    let header: Vec<String> = ["quantity", "joint 1", "joint 2", "joint 3", "limit", "use"]
        .map(String::from)
        .to_vec();
    let l = &plan.limits;
    let quantities: [(&str, &str, &Quantity, f64); 4] = [
        ("|v|", "m/s", &stats.velocity, l.velocity),
        ("|a|", "m/s²", &stats.acceleration, l.acceleration),
        ("|jerk|", "m/s³", &stats.jerk, l.jerk),
        ("|τ|", "N·m", &stats.torque, l.torque),
    ];
    let mut rows = Vec::new();
    for (name, unit, q, limit) in &quantities {
        let mut row = vec![format!("max {name} ({unit})")];
        row.extend(q.max.iter().map(|v| format!("{v:.5}")));
        row.push(format!("{limit}"));
        row.push(format!("{:.1} %", 100.0 * max3(&q.max) / limit));
        rows.push(row);
    }
    for (name, unit, q, _) in &quantities {
        let mut row = vec![format!("mean {name} ({unit})")];
        row.extend(q.mean.iter().map(|v| format!("{v:.5}")));
        row.extend([String::new(), String::new()]);
        rows.push(row);
    }
    let mut out = String::from(
        "Joint statistics (max exact in continuous time; |τ| on a refined grid; mean = time average)\n",
    );
    out.push_str(&render(&header, &rows));
    out
}

/// Compares the maxima recorded in the plan file (`max_abs`) with the
/// recomputed ones: exact quantities to 1e-6 relative, torque to 0.1 %.
pub fn recorded_check(plan: &Plan, stats: &PlanStats) -> String {
    let r = &plan.max_abs;
    let all = [r.velocity, r.acceleration, r.jerk, r.torque];
    if all.iter().flatten().all(|&x| x == 0.0) {
        return "max_abs in the plan file: not recorded (all zero)\n".into();
    }
    let mut diffs = Vec::new();
    for (name, rec, got, tol) in [
        ("velocity", &r.velocity, &stats.velocity.max, 1e-6),
        (
            "acceleration",
            &r.acceleration,
            &stats.acceleration.max,
            1e-6,
        ),
        ("jerk", &r.jerk, &stats.jerk.max, 1e-6),
        ("torque", &r.torque, &stats.torque.max, 1e-3),
    ] {
        for j in 0..3 {
            let scale = got[j].abs().max(1e-12);
            if (rec[j] - got[j]).abs() > tol * scale {
                diffs.push(format!(
                    "{name} joint {}: recorded {:.6}, recomputed {:.6}",
                    j + 1,
                    rec[j],
                    got[j]
                ));
            }
        }
    }
    if diffs.is_empty() {
        "max_abs in the plan file: agrees with the recomputed maxima\n".into()
    } else {
        format!(
            "max_abs in the plan file DIFFERS from the recomputed maxima: {}\n",
            diffs.join("; ")
        )
    }
}
