//! The machine file: every command that uses the machine reads it, the
//! example files match what the firmware fixes, and a plan made for one
//! machine is refused on another. On the built binary.

use std::path::{Path, PathBuf};

use triquint_cli_common::machine_file::{parse_machine, read_machine};
use triquint_shared::machine::{Machine, boards};

mod common;

use common::triquint;

fn scratch(name: &str) -> PathBuf {
    common::scratch("machine", name)
}

fn example(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../examples")
        .join(name)
}

fn esc1() -> String {
    example("machines/b-g431b-esc1.toml")
        .to_str()
        .unwrap()
        .to_string()
}

/// A two-point job within the ESC1 machine's ceilings.
const SMALL_JOB: &str = "objective = \"min-time\"\n[limits]\nvelocity = 0.3\nacceleration = 1.0\n\
                         jerk = 5.0\ntorque = 0.7\ntotal_time = 5.0\n[path]\nunits = \"mm\"\n\
                         points = [[-60, 60, 620], [60, -40, 660]]\n";

#[test]
fn the_example_machines_match_the_default_and_the_firmware() {
    let paper = read_machine(Some(&example("machines/paper.toml"))).unwrap();
    assert_eq!(paper, Machine::default());
    let esc1 = read_machine(Some(Path::new(&esc1()))).unwrap();
    for a in &esc1.axes {
        assert_eq!(
            a.counts_per_rev,
            f64::from(boards::B_G431B_ESC1_COUNTS_PER_REV)
        );
        let limit = a
            .current_limit
            .expect("the ESC1 machine states its current limit");
        assert!(limit <= f64::from(boards::B_G431B_ESC1_MAX_CURRENT));
    }
    // The scale the drives are told: 4 096 counts per 10 mm, not 2^17.
    assert_eq!(esc1.drive_settings().counts_per_metre, [409_600.0; 3]);
    assert!(esc1.effective_ceilings().torque <= 0.75 + 1e-12);
}

#[test]
fn a_bad_machine_file_is_read_not_ignored() {
    let dir = scratch("offered");
    std::fs::write(dir.join("bad.toml"), "[axis.1]\ndirection = 2\n").unwrap();
    let named = "line 2: `axis.1.direction` = 2: must be 1 or -1";
    // The feed commands take their node ids from it: exit 2 naming it.
    for cmd in ["hold", "resume", "stop"] {
        let (status, _, err) = triquint(&dir, &[cmd, "--iface", "none", "--machine", "bad.toml"]);
        assert_eq!(status, 2, "{cmd}: {err}");
        assert!(err.contains(named), "{cmd}: {err}");
    }
    // estop tries the bus before the file: here the interface fails first.
    let (status, _, err) = triquint(&dir, &["estop", "--iface", "none", "--machine", "bad.toml"]);
    assert_eq!(status, 4, "estop: {err}");
    assert!(err.contains("none: cannot open"), "estop: {err}");
    // And `plan`.
    let job = example("paper-case1.toml");
    let (status, _, err) = triquint(
        &dir,
        &[
            "plan",
            job.to_str().unwrap(),
            "-o",
            "p.json",
            "--machine",
            "bad.toml",
        ],
    );
    assert_eq!(status, 2, "{err}");
    assert!(err.contains(named), "{err}");
}

#[test]
fn a_job_is_held_to_the_machines_robot_and_ceilings() {
    let dir = scratch("held");
    // Table 3's 10 N·m is above the ESC1 machine's 0.75 N·m.
    let job = example("paper-case1.toml");
    let (status, _, err) = triquint(
        &dir,
        &[
            "plan",
            job.to_str().unwrap(),
            "-o",
            "p.json",
            "--machine",
            &esc1(),
        ],
    );
    assert_eq!(status, 2, "{err}");
    assert!(
        err.contains("limits.torque = 10 is above the machine's ceiling 0.75"),
        "{err}"
    );
    // A job whose [robot] differs from the machine's names the key.
    std::fs::write(
        dir.join("lead.toml"),
        format!("{SMALL_JOB}[robot]\nlead = 0.012\n"),
    )
    .unwrap();
    let (status, _, err) = triquint(
        &dir,
        &["plan", "lead.toml", "-o", "p.json", "--machine", &esc1()],
    );
    assert_eq!(status, 2, "{err}");
    assert!(
        err.contains("robot.lead is 0.012 in the job and 0.01 in the machine file"),
        "{err}"
    );
}

#[test]
fn a_plan_for_one_machine_runs_there_and_is_refused_elsewhere() {
    let dir = scratch("elsewhere");
    std::fs::write(dir.join("job.toml"), SMALL_JOB).unwrap();
    let (status, _, err) = triquint(
        &dir,
        &[
            "plan",
            "job.toml",
            "-o",
            "p.json",
            "--quiet",
            "--machine",
            &esc1(),
        ],
    );
    assert_eq!(status, 0, "{err}");
    let plan: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("p.json")).unwrap()).unwrap();
    assert_eq!(plan["ceilings"]["torque"], 0.75);
    // check proves it, against its machine too.
    let (status, _, err) = triquint(&dir, &["check", "p.json", "--machine", &esc1()]);
    assert_eq!(status, 0, "{err}");
    // It runs on the simulated ESC1 machine: 4 096-count encoders.
    let (status, out, err) = triquint(&dir, &["simulate", "p.json", "--machine", &esc1()]);
    assert_eq!(status, 0, "{out}{err}");
    // On the paper's machine its ceilings differ: refused, naming one.
    let paper = example("machines/paper.toml");
    let (status, _, err) = triquint(
        &dir,
        &["check", "p.json", "--machine", paper.to_str().unwrap()],
    );
    assert_eq!(status, 2, "{err}");
    assert!(
        err.contains("ceiling velocity is 0.5 in the plan, 1e6 in the machine"),
        "{err}"
    );
    let (status, _, err) = triquint(&dir, &["simulate", "p.json"]);
    assert_eq!(status, 2, "{err}");
    assert!(
        err.contains("planned for another machine than the default machine: ceiling velocity"),
        "{err}"
    );
}

#[test]
fn ik_uses_the_machines_travel() {
    let dir = scratch("ik");
    std::fs::write(
        dir.join("short.toml"),
        "[axis.1]\ntravel_max = 0.30\n[axis.2]\ntravel_max = 0.30\n[axis.3]\ntravel_max = 0.30\n",
    )
    .unwrap();
    let (status, _, err) = triquint(&dir, &["ik", "0", "0", "700"]);
    assert_eq!(status, 0, "{err}");
    let (status, _, err) = triquint(&dir, &["ik", "0", "0", "700", "--machine", "short.toml"]);
    assert_eq!(status, 2, "{err}");
    assert!(err.contains("above its travel max 300 mm"), "{err}");
}

#[test]
fn a_tampered_summary_is_refused_before_anything_moves() {
    let dir = scratch("tampered");
    let job = example("paper-case2.toml");
    let (status, _, err) = triquint(
        &dir,
        &["plan", job.to_str().unwrap(), "-o", "p.json", "--quiet"],
    );
    assert_eq!(status, 0, "{err}");
    let mut p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("p.json")).unwrap()).unwrap();
    p["max_abs"]["velocity"] = serde_json::json!([1e-9, 1e-9, 1e-9]);
    p["max_abs"]["acceleration"] = serde_json::json!([1e-9, 1e-9, 1e-9]);
    std::fs::write(dir.join("t.json"), p.to_string()).unwrap();
    let (status, out, err) = triquint(&dir, &["simulate", "t.json"]);
    assert_eq!(status, 2, "{out}{err}");
    assert!(
        err.contains("fails check, nothing sent: reported max velocity"),
        "{err}"
    );
    // Limits above the ceilings the plan records: check fails them.
    let mut p: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("p.json")).unwrap()).unwrap();
    p["ceilings"]["jerk"] = serde_json::json!(4.0);
    std::fs::write(dir.join("c.json"), p.to_string()).unwrap();
    let (status, out, _) = triquint(&dir, &["check", "c.json"]);
    assert_eq!(status, 1, "{out}");
    assert!(
        out.lines()
            .any(|l| l.starts_with("limit jerk − ceiling") && l.ends_with("VIOLATED")),
        "{out}"
    );
}

#[test]
fn parse_machine_is_the_one_reader() {
    // The fuzz target and Python read through the same function.
    assert!(parse_machine("[axis.2]\ncounts_per_rev = 0\n").is_err());
}
