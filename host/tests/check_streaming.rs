//! `triquint check` reports whether the drives' queues can stream a plan
//! (docs/protocol.md, Streamability).

use std::process::Command;

use triquint_shared::{Limits, Robot};
use triquint_sim::testplan;

fn check(path: &str) -> (i32, String) {
    check_with(&[path])
}

fn check_with(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_triquint"))
        .arg("check")
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
    )
}

fn streaming_row(out: &str) -> &str {
    out.lines()
        .find(|l| l.starts_with("streaming: segments"))
        .unwrap_or_else(|| panic!("no streaming row in:\n{out}"))
}

#[test]
fn check_reports_streamability() {
    let spiral = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../testdata/protocol/plans/spiral-spline.json"
    );
    // (This test plan, a spline not from the planner, fails `check` on
    // its end jerk: only the streaming row is judged here.)
    let (_, out) = check(spiral);
    assert!(streaming_row(&out).ends_with(" ok"), "{out}");

    // 300 segments of 10 ms on a helix: far less than the look-ahead in a
    // queue's worth of segments.
    let n = 300;
    let pts: Vec<[f64; 3]> = (0..=n)
        .map(|i| {
            let v = i as f64 / n as f64;
            let u = v * v * v * (10.0 - 15.0 * v + 6.0 * v * v);
            let th = 2.0 * std::f64::consts::PI * 3.0 * u;
            [0.08 * th.cos(), 0.08 * th.sin(), 0.56 + 0.12 * u]
        })
        .collect();
    let limits = Limits {
        total_time: 3.0,
        ..Limits::default()
    };
    let plan = testplan::plan_through(&Robot::default(), &limits, &pts, &vec![0.01; n]).unwrap();
    let dir = std::env::temp_dir().join(format!("triquint-check-stream-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("short-segments.json");
    std::fs::write(&path, serde_json::to_string(&plan).unwrap()).unwrap();
    let (code, out) = check(&path.to_string_lossy());
    assert_eq!(code, 1, "{out}");
    assert!(streaming_row(&out).ends_with("VIOLATED"), "{out}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The last column of a check row: what the run needs (s).
fn need_s(row: &str) -> f64 {
    let cols: Vec<&str> = row.split_whitespace().collect();
    cols[cols.len() - 2].parse().unwrap()
}

/// A machine whose override stops at 100 % (`drive.max_override = 1`)
/// needs less plan queued ahead: its stop ramp is sized for a stop from
/// σ = 1, not from the spiral's cap of 2.955 (docs/machine.md).
#[test]
fn a_machine_without_overrides_above_100_percent_needs_less_look_ahead() {
    let spiral = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../testdata/protocol/plans/spiral-spline.json"
    );
    let paper = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../examples/machines/paper.toml"
    ))
    .unwrap();
    let line = paper
        .lines()
        .find(|l| l.starts_with("max_override"))
        .expect("paper.toml names max_override");
    let dir = std::env::temp_dir().join(format!("triquint-check-override-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let machine = dir.join("no-override.toml");
    std::fs::write(&machine, paper.replace(line, "max_override = 1.0")).unwrap();
    let (_, free) = check(spiral);
    let (_, capped) = check_with(&[spiral, "--machine", &machine.to_string_lossy()]);
    let (free, capped) = (need_s(streaming_row(&free)), need_s(streaming_row(&capped)));
    assert!(capped < 0.8 * free, "{capped} s against {free} s");
    let _ = std::fs::remove_dir_all(&dir);
}
