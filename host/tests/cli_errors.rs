//! Bad input to the built `triquint` binary, as a table: each case must end
//! with the exit status of the table in docs/cli.md, exactly one line on stderr
//! naming what is wrong, no panic, and no output file left behind.

use std::path::{Path, PathBuf};
use std::process::Command;

/// An interface no machine has.
const NO_IFACE: &str = "triquint-nosuch0";

const GOOD_POINTS: &str = "points = [[-90, 90, 680], [-90, 90, 660], [-60, 60, 640]]";

struct Case {
    name: &'static str,
    /// Files to create in the case's directory: (name, contents).
    files: Vec<(&'static str, String)>,
    args: Vec<&'static str>,
    status: i32,
    /// Text the one-line error must contain.
    says: &'static str,
}

fn job(limits: &str, path: &str) -> String {
    format!("objective = \"min-max-jerk\"\n[limits]\n{limits}\n[path]\n{path}\n")
}

/// A whole plan (Case I) that passes every check.
fn full_plan_json() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata/hil/paper-case1.json"),
    )
    .unwrap()
}

/// The first part of Case I (the golden vectors' plan): it loads, and does
/// not end at rest.
fn paper_plan_json() -> String {
    std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../testdata/protocol/plans/case1-spline.json"),
    )
    .unwrap()
}

/// The paper's plan with one segment moved 5 mm on every axis: a plan file
/// that loads, which the host's check refuses before the drives see it
/// (the drives' own Discontinuous rejection is tested in tests/faults.rs).
fn discontinuous_plan_json() -> String {
    let mut plan: serde_json::Value = serde_json::from_str(&paper_plan_json()).unwrap();
    for axis in plan["segments"][4]["coeffs"].as_array_mut().unwrap() {
        let q0 = axis[0].as_f64().unwrap();
        axis[0] = (q0 + 0.005).into();
    }
    serde_json::to_string(&plan).unwrap()
}

fn cases() -> Vec<Case> {
    let plan_args = vec![
        "plan", "job.toml", "-o", "out.json", "--starts", "1", "--quiet",
    ];
    let units = "units = \"mm\"";
    let good_job = || vec![("job.toml", job("", &format!("{units}\n{GOOD_POINTS}")))];
    let with = |extra: &'static [&'static str]| {
        let mut a = plan_args.clone();
        a.extend_from_slice(extra);
        a
    };
    vec![
        Case {
            name: "unknown shaper",
            files: good_job(),
            args: with(&["--shaper", "zz:30"]),
            status: 2,
            says: "unknown shaper `zz`",
        },
        Case {
            name: "shaper without a frequency",
            files: good_job(),
            args: with(&["--shaper", "ei"]),
            status: 2,
            says: "give TYPE:HZ[:DAMPING]",
        },
        Case {
            name: "shaper damping out of range",
            files: good_job(),
            args: with(&["--shaper", "ei:30:1.5"]),
            status: 2,
            says: "shaper.damping",
        },
        Case {
            name: "a job's shaper out of range",
            files: vec![(
                "job.toml",
                format!(
                    "[shaper]\ntype = \"mzv\"\nfrequency_hz = 0\n[path]\n{units}\n{GOOD_POINTS}\n"
                ),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "shaper.frequency_hz",
        },
        Case {
            name: "resonance outside the workspace",
            files: vec![],
            args: vec!["resonance", "--at", "0,0,100"],
            status: 2,
            says: "outside the travel",
        },
        Case {
            name: "malformed TOML",
            files: vec![("job.toml", "[limits\nvelocity = 0.5\n".into())],
            args: plan_args.clone(),
            status: 2,
            says: "job.toml",
        },
        Case {
            name: "malformed JSON plan",
            files: vec![(
                "plan.json",
                "{\"format\": \"triquint-plan\", \"segments\": [".into(),
            )],
            args: vec!["check", "plan.json"],
            status: 2,
            says: "plan.json",
        },
        Case {
            name: "JSON that is not a plan",
            files: vec![("plan.json", "[1, 2, 3]".into())],
            args: vec!["simulate", "plan.json"],
            status: 2,
            says: "plan.json",
        },
        Case {
            name: "a discontinuous plan",
            files: vec![("plan.json", discontinuous_plan_json())],
            args: vec!["simulate", "plan.json"],
            status: 2,
            says: "fails check, nothing sent: knot interpolation error",
        },
        Case {
            name: "unknown units",
            files: vec![(
                "job.toml",
                job("", &format!("units = \"inch\"\n{GOOD_POINTS}")),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "inch",
        },
        Case {
            name: "units in metres but values in mm (outside the workspace)",
            files: vec![(
                "job.toml",
                job("", &format!("units = \"m\"\n{GOOD_POINTS}")),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "outside the workspace",
        },
        Case {
            name: "NaN limit",
            files: vec![(
                "job.toml",
                job("velocity = nan", &format!("{units}\n{GOOD_POINTS}")),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "velocity",
        },
        Case {
            name: "infinite coordinate",
            files: vec![(
                "job.toml",
                job(
                    "",
                    &format!("{units}\npoints = [[-90, 90, 680], [-90, 90, inf]]"),
                ),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "point 2",
        },
        Case {
            name: "unreachable via-point",
            files: vec![(
                "job.toml",
                job(
                    "",
                    &format!("{units}\npoints = [[-90, 90, 680], [900, 90, 660]]"),
                ),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "point 2",
        },
        Case {
            name: "duplicate consecutive points",
            files: vec![(
                "job.toml",
                job(
                    "",
                    &format!("{units}\npoints = [[-90, 90, 680], [-90, 90, 680], [-90, 90, 660]]"),
                ),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "repeats",
        },
        Case {
            name: "too few points",
            files: vec![(
                "job.toml",
                job("", &format!("{units}\npoints = [[-90, 90, 680]]")),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "at least 2 points",
        },
        Case {
            name: "zero velocity limit",
            files: vec![(
                "job.toml",
                job("velocity = 0.0", &format!("{units}\n{GOOD_POINTS}")),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "velocity",
        },
        Case {
            name: "negative jerk limit",
            files: vec![(
                "job.toml",
                job("jerk = -5.0", &format!("{units}\n{GOOD_POINTS}")),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "jerk",
        },
        Case {
            name: "unknown key",
            files: vec![(
                "job.toml",
                job("speed = 1.0", &format!("{units}\n{GOOD_POINTS}")),
            )],
            args: plan_args.clone(),
            status: 2,
            says: "speed",
        },
        Case {
            name: "total time far too short (infeasible)",
            files: vec![(
                "job.toml",
                job("total_time = 0.05", &format!("{units}\n{GOOD_POINTS}")),
            )],
            args: plan_args.clone(),
            status: 3,
            says: "",
        },
        Case {
            name: "a plan for another robot",
            files: vec![
                ("plan.json", paper_plan_json()),
                ("other.toml", "[robot]\nlead = 0.005\n".into()),
            ],
            args: vec!["simulate", "plan.json", "--robot", "other.toml"],
            status: 2,
            says: "planned for another machine than other.toml: robot.lead is 0.01 in the plan, 0.005",
        },
        Case {
            name: "a plan for another robot (check)",
            files: vec![
                ("plan.json", paper_plan_json()),
                ("other.toml", "[robot]\nlead = 0.005\n".into()),
            ],
            args: vec!["check", "plan.json", "--machine", "other.toml"],
            status: 2,
            says: "robot.lead",
        },
        // An unknown interface name: the kernel has no such device (with or
        // without CAN support): exit 4, one line.
        Case {
            name: "upload on an unknown interface",
            files: vec![("plan.json", full_plan_json())],
            args: vec!["upload", "plan.json", "--iface", NO_IFACE],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "monitor on an unknown interface",
            files: vec![],
            args: vec!["monitor", "--iface", NO_IFACE, "--count", "1"],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "move-to on an unknown interface",
            files: vec![],
            args: vec!["move-to", "-85", "90", "670", "--iface", NO_IFACE],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "status on an unknown interface",
            files: vec![],
            args: vec!["status", "--iface", NO_IFACE, "--json"],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "home on an unknown interface",
            files: vec![],
            args: vec!["home", "--iface", NO_IFACE],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "clear on an unknown interface",
            files: vec![],
            args: vec!["clear", "--iface", NO_IFACE],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "estop on an unknown interface",
            files: vec![],
            args: vec!["estop", "--iface", NO_IFACE],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "upload to two node ids",
            files: vec![("plan.json", paper_plan_json())],
            args: vec!["upload", "plan.json", "--iface", NO_IFACE, "--nodes", "4,5"],
            status: 2,
            says: "--nodes",
        },
        Case {
            name: "home with a repeated node id",
            files: vec![],
            args: vec!["home", "--iface", NO_IFACE, "--nodes", "4,4,5"],
            status: 2,
            says: "--nodes",
        },
        Case {
            name: "status with node id 16",
            files: vec![],
            args: vec!["status", "--iface", NO_IFACE, "--nodes", "1,2,16"],
            status: 2,
            says: "--nodes",
        },
        Case {
            name: "a bad [homing] table",
            files: vec![("robot.toml", "[homing]\nvelocity = -1\n".into())],
            args: vec!["home", "--iface", NO_IFACE, "--robot", "robot.toml"],
            status: 2,
            says: "velocity",
        },
        Case {
            name: "hold on an unknown interface",
            files: vec![],
            args: vec!["hold", "--iface", NO_IFACE],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "resume on an unknown interface",
            files: vec![],
            args: vec!["resume", "--iface", NO_IFACE],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "stop on an unknown interface",
            files: vec![],
            args: vec!["stop", "--iface", NO_IFACE],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "override on an unknown interface",
            files: vec![],
            args: vec!["override", "50", "--iface", NO_IFACE],
            status: 4,
            says: "triquint-nosuch0: cannot open SocketCAN interface",
        },
        Case {
            name: "plan --plot - (no folder on standard output)",
            files: vec![("job.toml", job("", GOOD_POINTS))],
            args: vec!["plan", "job.toml", "-o", "p.json", "--plot", "-"],
            status: 2,
            says: "--plot -: plots are SVG files in a folder, not standard output",
        },
        Case {
            name: "report --plot - (no folder on standard output)",
            files: vec![("p.json", full_plan_json())],
            args: vec!["report", "p.json", "--plot", "-"],
            status: 2,
            says: "--plot -: plots are SVG files in a folder, not standard output",
        },
        Case {
            name: "simulate --plot - (no folder on standard output)",
            files: vec![("p.json", full_plan_json())],
            args: vec!["simulate", "p.json", "--plot", "-"],
            status: 2,
            says: "--plot -: plots are SVG files in a folder, not standard output",
        },
        Case {
            // `ik` prints millimetres; pasted into `--q` (metres) they were
            // an error about struts, or, all equal, torques of a pose
            // hundreds of metres up.
            name: "torque given ik's millimetres",
            files: vec![],
            args: vec![
                "torque",
                "--q",
                "376.685,244.164,336.130",
                "--qd",
                "0,0,0",
                "--qdd",
                "0,0,0",
            ],
            status: 2,
            says: "(--q is in metres; `triquint ik` prints millimetres: divide by 1000)",
        },
        Case {
            name: "torque of equal sliders far above the travel",
            files: vec![],
            args: vec![
                "torque",
                "--q",
                "300,300,300",
                "--qd",
                "0,0,0",
                "--qdd",
                "0,0,0",
            ],
            status: 2,
            says: "--q 300,300,300: outside the travel",
        },
        Case {
            name: "override that is not a number",
            files: vec![],
            args: vec!["override", "fast", "--iface", NO_IFACE],
            status: 2,
            says: "not a percentage",
        },
        Case {
            name: "override out of range",
            files: vec![],
            args: vec!["override", "4000", "--iface", NO_IFACE],
            status: 2,
            says: "0.1 to 3200 per cent",
        },
        Case {
            name: "missing job file",
            files: vec![],
            args: plan_args.clone(),
            status: 2,
            says: "job.toml",
        },
    ]
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "triquint-cli-errors-{}-{}",
        std::process::id(),
        name.replace(|c: char| !c.is_ascii_alphanumeric(), "-")
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn every_bad_input_gets_one_line_and_its_exit_status() {
    let mut failures = Vec::new();
    for case in cases() {
        let dir = scratch(case.name);
        for (file, text) in &case.files {
            std::fs::write(dir.join(file), text).unwrap();
        }
        let out = Command::new(env!("CARGO_BIN_EXE_triquint"))
            .args(&case.args)
            .current_dir(&dir)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        let lines: Vec<&str> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        let status = out.status.code();
        let mut why = Vec::new();
        if status != Some(case.status) {
            why.push(format!("status {status:?}, want {}", case.status));
        }
        if lines.len() != 1 {
            why.push(format!("{} stderr lines", lines.len()));
        }
        if stderr.contains("panicked") {
            why.push("panicked".into());
        }
        if !stderr.contains(case.says) {
            why.push(format!("does not say `{}`", case.says));
        }
        if dir.join("out.json").exists() {
            why.push("left out.json behind".into());
        }
        let leftovers: Vec<_> = std::fs::read_dir(&dir)
            .unwrap()
            .filter_map(|e| e.ok())
            .map(|e| e.file_name().to_string_lossy().into_owned())
            .filter(|n| !case.files.iter().any(|f| f.0 == n))
            .collect();
        if !leftovers.is_empty() {
            why.push(format!("left files {leftovers:?}"));
        }
        eprintln!(
            "{:<58} exit {:?}  {}",
            case.name,
            status,
            lines.first().unwrap_or(&"")
        );
        if !why.is_empty() {
            failures.push(format!("{}: {} ({stderr})", case.name, why.join(", ")));
        }
        let _ = std::fs::remove_dir_all(&dir);
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

/// An interface that exists but is not CAN (`lo`, on every machine): the
/// kernel's reason depends on the kernel (with SocketCAN: binding a CAN socket
/// to a non-CAN device is "No such device"; without CAN, as on this test
/// machine: "Address family not supported"), the line and status do not.
#[test]
fn a_network_interface_that_is_not_can_is_a_device_error() {
    for args in [
        &["monitor", "--iface", "lo", "--count", "1"][..],
        &["move-to", "-85", "90", "670", "--iface", "lo"],
    ] {
        let out = Command::new(env!("CARGO_BIN_EXE_triquint"))
            .args(args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(4), "{stderr}");
        assert_eq!(stderr.trim().lines().count(), 1, "{stderr}");
        let reason = stderr.split("lo: cannot open SocketCAN interface: ").nth(1);
        assert!(
            reason.is_some_and(|r| r.starts_with("No such device")
                || r.starts_with("Address family not supported")),
            "{stderr}"
        );
    }
}
