//! `triquint report`: statistics on synthetic plans with known answers, plots,
//! and the command's exit statuses.

use std::path::PathBuf;
use std::process::Command;

use nalgebra::Vector3;
use triquint_host::report::{plan_stats, plots};
use triquint_planner::files::parse_plan;
use triquint_shared::kinematics::Pose;
use triquint_shared::plan::{MaxAbs, Objective, PLAN_FORMAT, Plan, Segment, SolverStats};
use triquint_shared::{Limits, Robot, dynamics};

/// Rest-to-rest quintic segments (q = q0 + Δq(10s³ − 15s⁴ + 6s⁵)) through the
/// IK images of `points_mm`, with durations `h`.
fn rest_to_rest_plan(points_mm: &[[f64; 3]], h: &[f64]) -> Plan {
    let robot = Robot::default();
    let model = robot.model::<f64>();
    let via: Vec<[f64; 3]> = points_mm.iter().map(|p| p.map(|v| v / 1e3)).collect();
    let knots: Vec<[f64; 3]> = via
        .iter()
        .map(|p| {
            let q = Pose::from_cartesian(&model, Vector3::from(*p)).unwrap().q;
            [q[0], q[1], q[2]]
        })
        .collect();
    let mut t0 = 0.0;
    let mut segments = Vec::new();
    for (i, &d) in h.iter().enumerate() {
        let coeffs = std::array::from_fn(|j| {
            let (q0, dq) = (knots[i][j], knots[i + 1][j] - knots[i][j]);
            [
                q0,
                0.0,
                0.0,
                10.0 * dq / d.powi(3),
                -15.0 * dq / d.powi(4),
                6.0 * dq / d.powi(5),
            ]
        });
        segments.push(Segment {
            t0_s: t0,
            duration_s: d,
            coeffs,
        });
        t0 += d;
    }
    Plan {
        format: PLAN_FORMAT.into(),
        objective: Objective::MinMaxJerk,
        robot,
        limits: Limits::default(),
        travel: Default::default(),
        ceilings: Default::default(),
        via_points_m: via,
        knots_m: knots,
        free_knots: Vec::new(),
        max_deviation_m: None,
        intervals_s: h.to_vec(),
        total_time_s: t0,
        segments,
        max_abs: MaxAbs::default(),
        solver: SolverStats::default(),
        shaping: None,
    }
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs().max(1e-300)
}

#[test]
fn single_quintic_has_the_analytic_peaks_and_means() {
    // Paper Case I P3 → P4: all three joints move, by different amounts.
    let h = 0.8;
    let plan = rest_to_rest_plan(&[[-90.0, 90.0, 640.0], [-60.0, 60.0, 620.0]], &[h]);
    let s = plan_stats(&plan).unwrap();
    assert_eq!(s.total_time_s, h);
    for j in 0..3 {
        let dq = (plan.knots_m[1][j] - plan.knots_m[0][j]).abs();
        let cases = [
            ("peak v", s.velocity.max[j], 15.0 / 8.0 * dq / h),
            (
                "peak a",
                s.acceleration.max[j],
                10.0 / 3f64.sqrt() * dq / (h * h),
            ),
            ("peak jerk", s.jerk.max[j], 60.0 * dq / h.powi(3)),
            ("mean v", s.velocity.mean[j], dq / h),
            ("mean a", s.acceleration.mean[j], 15.0 / 4.0 * dq / (h * h)),
            (
                "mean jerk",
                s.jerk.mean[j],
                40.0 / 3f64.sqrt() * dq / h.powi(3),
            ),
        ];
        for (what, got, want) in cases {
            assert!(
                rel(got, want) < 1e-12,
                "joint {}: {what} {got} vs {want}",
                j + 1
            );
        }
        assert!((s.velocity.argmax_s[j] - h / 2.0).abs() < 1e-9);
    }
}

#[test]
fn torque_statistics_match_a_dense_independent_sampling() {
    let plan = rest_to_rest_plan(
        &[
            [-86.0, 83.66, 597.66],
            [-43.0, 97.74, 654.74],
            [0.0, 84.85, 684.85],
        ],
        &[0.6, 0.35],
    );
    let s = plan_stats(&plan).unwrap();
    let model = plan.robot.model::<f64>();
    let (mut max, mut integral) = ([0.0f64; 3], [0.0f64; 3]);
    for seg in &plan.segments {
        let n = 20_000;
        let dt = seg.duration_s / n as f64;
        for k in 0..n {
            let m = seg.quintic().eval((k as f64 + 0.5) * dt);
            let tau = dynamics::torque(&model, &m.q, &m.qd, &m.qdd).unwrap();
            for j in 0..3 {
                max[j] = max[j].max(tau[j].abs());
                integral[j] += tau[j].abs() * dt;
            }
        }
    }
    for j in 0..3 {
        assert!(s.torque.max[j] >= max[j] * (1.0 - 1e-12), "joint {}", j + 1);
        assert!(
            rel(s.torque.max[j], max[j]) < 1e-6,
            "{} vs {}",
            s.torque.max[j],
            max[j]
        );
        let mean = integral[j] / s.total_time_s;
        assert!(
            rel(s.torque.mean[j], mean) < 1e-4,
            "{} vs {mean}",
            s.torque.mean[j]
        );
    }
    // Per-segment maxima are consistent with the totals.
    for j in 0..3 {
        let seg_max = s.segments.iter().map(|g| g.max_jerk[j]).fold(0.0, f64::max);
        assert_eq!(seg_max, s.jerk.max[j]);
    }
}

#[test]
fn plots_are_complete_svg_documents() {
    let plan = rest_to_rest_plan(
        &[
            [-90.0, 90.0, 680.0],
            [-90.0, 90.0, 660.0],
            [-60.0, 60.0, 620.0],
        ],
        &[0.5, 0.7],
    );
    let s = plan_stats(&plan).unwrap();
    let files = plots::plots(&plan, &s).unwrap();
    let names: Vec<&str> = files.iter().map(|f| f.0).collect();
    for want in [
        "position.svg",
        "velocity.svg",
        "acceleration.svg",
        "jerk.svg",
        "torque.svg",
        "path3d.svg",
    ] {
        assert!(names.contains(&want), "{want} missing from {names:?}");
    }
    for (name, svg) in &files {
        assert!(
            svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
            "{name}"
        );
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "{name}");
    }
    let path = &files.iter().find(|f| f.0 == "path3d.svg").unwrap().1;
    assert!(path.contains(">\nP3\n</text>") && path.contains("x (mm)"));
}

fn triquint() -> Command {
    Command::new(env!("CARGO_BIN_EXE_triquint"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("triquint-report-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn cli_reports_tables_json_and_plots() {
    let dir = temp_dir("ok");
    let plan = rest_to_rest_plan(&[[-90.0, 90.0, 680.0], [-90.0, 90.0, 660.0]], &[1.0]);
    let file = dir.join("plan.json");
    std::fs::write(&file, serde_json::to_string(&plan).unwrap()).unwrap();
    let plots = dir.join("plots");
    let out = triquint()
        .arg("report")
        .arg(&file)
        .arg("--plot")
        .arg(&plots)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    assert!(
        text.contains("max |jerk| (m/s³)") && text.contains("h1"),
        "{text}"
    );
    for f in [
        "position",
        "velocity",
        "acceleration",
        "jerk",
        "torque",
        "path3d",
    ] {
        assert!(plots.join(format!("{f}.svg")).is_file(), "{f}.svg");
    }
    let out = triquint()
        .arg("report")
        .arg(&file)
        .arg("--json")
        .output()
        .unwrap();
    assert!(out.status.success());
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let peak = v["velocity"]["max"][0].as_f64().unwrap();
    let dq = (plan.knots_m[1][0] - plan.knots_m[0][0]).abs();
    assert!(rel(peak, 15.0 / 8.0 * dq) < 1e-12);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn cli_bad_input_exits_2_with_one_line() {
    let dir = temp_dir("bad");
    let good = rest_to_rest_plan(&[[-90.0, 90.0, 680.0], [-90.0, 90.0, 660.0]], &[1.0]);
    let mut wrong_format = good.clone();
    wrong_format.format = "something-else".into();
    let mut bad_duration = good.clone();
    bad_duration.segments[0].duration_s = -1.0;
    let cases: Vec<(&str, Option<String>, &str)> = vec![
        ("missing.json", None, "missing.json"),
        (
            "syntax.json",
            Some("{\"format\": \n  oops}".into()),
            "line 2 column",
        ),
        (
            "unknown.json",
            Some("{\"formt\": 1}".into()),
            "line 1 column",
        ),
        (
            "format.json",
            Some(serde_json::to_string(&wrong_format).unwrap()),
            "format",
        ),
        (
            "duration.json",
            Some(serde_json::to_string(&bad_duration).unwrap()),
            "duration",
        ),
    ];
    for (name, contents, needle) in cases {
        let path = dir.join(name);
        if let Some(c) = contents {
            std::fs::write(&path, c).unwrap();
        }
        let out = triquint().arg("report").arg(&path).output().unwrap();
        assert_eq!(out.status.code(), Some(2), "{name}");
        let err = String::from_utf8(out.stderr).unwrap();
        assert_eq!(err.trim_end().lines().count(), 1, "{name}: {err}");
        assert!(err.contains(needle), "{name}: {err}");
    }
    // Library-level parse gives the same line/column detail.
    assert!(parse_plan("[").unwrap_err().to_string().contains("line 1"));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn recorded_maxima_are_compared() {
    use triquint_host::report::tables::recorded_check;
    let mut plan = rest_to_rest_plan(&[[-90.0, 90.0, 680.0], [-90.0, 90.0, 660.0]], &[1.0]);
    let s = plan_stats(&plan).unwrap();
    assert!(recorded_check(&plan, &s).contains("not recorded"));
    plan.max_abs = MaxAbs {
        velocity: s.velocity.max,
        acceleration: s.acceleration.max,
        jerk: s.jerk.max,
        torque: s.torque.max,
    };
    assert!(recorded_check(&plan, &s).contains("agrees"));
    plan.max_abs.jerk[1] *= 1.001;
    let text = recorded_check(&plan, &s);
    assert!(
        text.contains("DIFFERS") && text.contains("jerk joint 2"),
        "{text}"
    );
}
