//! Every `--plot` of the CLI (`plan`, `report`, `simulate`): each writes the
//! expected files, each a well-formed SVG document (parsed as XML) holding
//! the expected charts, in the one style (embedded font's family named, joint
//! colours, labelled axes with units), and no NaN or unescaped text.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::process::Command;

const JOB: &str = r#"objective = "min-max-jerk"
[limits]
velocity = 0.5
acceleration = 1.2
jerk = 5.0
torque = 10.0
total_time = 3.0
[path]
units = "mm"
points = [[-90, 90, 680], [-90, 90, 650], [-30, 30, 630], [30, -30, 630], [60, -60, 650]]
"#;

fn triquint() -> Command {
    Command::new(env!("CARGO_BIN_EXE_triquint"))
}

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("triquint-plots-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn run(cmd: &mut Command) {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{:?}: {}",
        cmd,
        String::from_utf8_lossy(&out.stderr)
    );
}

/// What one SVG file shows: its size and every text it prints.
struct Svg {
    width: f64,
    texts: Vec<String>,
    fills_and_strokes: BTreeSet<String>,
}

fn parse(path: &Path) -> Svg {
    let text = std::fs::read_to_string(path).unwrap();
    let doc = roxmltree::Document::parse(&text)
        .unwrap_or_else(|e| panic!("{}: not well-formed XML: {e}", path.display()));
    let root = doc.root_element();
    assert_eq!(root.tag_name().name(), "svg", "{}", path.display());
    assert_eq!(
        root.tag_name().namespace(),
        Some("http://www.w3.org/2000/svg")
    );
    assert!(
        !text.contains("NaN") && !text.contains("inf"),
        "{}",
        path.display()
    );
    let mut texts = Vec::new();
    let mut colours = BTreeSet::new();
    for n in doc.descendants().filter(|n| n.is_element()) {
        if n.tag_name().name() == "text" {
            assert_eq!(n.attribute("font-family"), Some("DejaVu Sans, sans-serif"));
            texts.push(n.text().unwrap_or("").trim().to_string());
        }
        for a in ["fill", "stroke"] {
            if let Some(c) = n.attribute(a) {
                colours.insert(c.to_ascii_uppercase());
            }
        }
    }
    Svg {
        width: root.attribute("width").unwrap().parse().unwrap(),
        texts,
        fills_and_strokes: colours,
    }
}

fn has(svg: &Svg, text: &str) -> bool {
    svg.texts.iter().any(|t| t == text)
}

/// Checks `dir` holds exactly `files`, each with the texts given.
fn check_dir(dir: &Path, files: &[(&str, &[&str])]) {
    let mut found: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    found.sort();
    let mut want: Vec<String> = files.iter().map(|f| f.0.to_string()).collect();
    want.sort();
    assert_eq!(found, want, "{}", dir.display());
    for (name, texts) in files {
        let svg = parse(&dir.join(name));
        assert!(svg.width >= 600.0, "{name}");
        for t in *texts {
            assert!(has(&svg, t), "{name}: no text {t:?} in {:?}", svg.texts);
        }
        // Joint 1, 2, 3 in the same colours in every chart of joints.
        if *name != "path3d.svg" {
            for c in ["#1F77B4", "#FF7F0E", "#2CA02C"] {
                assert!(svg.fills_and_strokes.contains(c), "{name}: no {c}");
            }
        }
    }
}

const PLAN_FILES: &[(&str, &[&str])] = &[
    (
        "position.svg",
        &[
            "(a) Joint position",
            "slider position q (mm)",
            "time (s)",
            "P1",
            "P4",
            "knot",
        ],
    ),
    (
        "velocity.svg",
        &[
            "(b) Joint velocity",
            "velocity (m/s)",
            "+0.5 m/s",
            "−0.5 m/s",
            "limit",
        ],
    ),
    (
        "acceleration.svg",
        &["(c) Joint acceleration", "acceleration (m/s²)"],
    ),
    ("jerk.svg", &["(d) Joint jerk", "jerk (m/s³)"]),
    ("torque.svg", &["(e) Joint torque", "motor torque τ (N·m)"]),
    (
        "path3d.svg",
        &[
            "(f) Platform path (forward kinematics)",
            "Top view (x–y)",
            "Front view (x–z)",
            "x (mm)",
            "y (mm)",
            "z (mm)",
            "P3",
        ],
    ),
    (
        "overview.svg",
        &[
            "(a) Joint position",
            "(b) Joint velocity",
            "(c) Joint acceleration",
            "(d) Joint jerk",
            "(e) Joint torque",
            "(f) Platform path (forward kinematics)",
        ],
    ),
];

#[test]
fn plan_report_and_simulate_write_every_chart() {
    let dir = temp_dir("all");
    std::fs::write(dir.join("job.toml"), JOB).unwrap();
    let plan = dir.join("plan.json");
    run(triquint()
        .arg("plan")
        .arg(dir.join("job.toml"))
        .arg("-o")
        .arg(&plan)
        .args(["--starts", "1", "--quiet", "--plot"])
        .arg(dir.join("plan-plots")));
    check_dir(&dir.join("plan-plots"), PLAN_FILES);

    run(triquint()
        .arg("report")
        .arg(&plan)
        .arg("--plot")
        .arg(dir.join("report-plots")));
    check_dir(&dir.join("report-plots"), PLAN_FILES);
    // The same plan gives the same documents through both commands.
    for (name, _) in PLAN_FILES {
        let a = std::fs::read(dir.join("plan-plots").join(name)).unwrap();
        let b = std::fs::read(dir.join("report-plots").join(name)).unwrap();
        assert!(a == b, "{name} differs between plan and report");
    }

    for (flag, ff) in [
        (None, "feedforward (model)"),
        (
            Some("--no-feedforward"),
            "feedforward (model; off in this run)",
        ),
    ] {
        let out = dir.join(format!("sim{}", flag.unwrap_or("")));
        let mut cmd = triquint();
        cmd.arg("simulate").arg(&plan).arg("--plot").arg(&out);
        if let Some(f) = flag {
            cmd.arg(f);
        }
        run(&mut cmd);
        let time = "time since start (s)";
        check_dir(
            &out,
            &[
                (
                    "position.svg",
                    &[
                        "Joint position: reference and measured",
                        "joint 1 reference",
                        "joint 3 measured",
                        time,
                    ],
                ),
                (
                    "tracking_error.svg",
                    &["Tracking error (plant − plan)", "tracking error (µm)", "P4"],
                ),
                (
                    "torque.svg",
                    &["Motor torque command", "torque command τ (N·m)"],
                ),
                (
                    "feedforward.svg",
                    &[
                        "Feedforward against the total torque command",
                        "joint 2 total",
                        ff,
                    ],
                ),
                (
                    "overview.svg",
                    &[
                        "Joint position: reference and measured",
                        "Tracking error (plant − plan)",
                        "Motor torque command",
                        "Feedforward against the total torque command",
                    ],
                ),
            ],
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn unwritable_plot_directory_is_an_error_not_a_panic() {
    let dir = temp_dir("bad");
    std::fs::write(dir.join("job.toml"), JOB).unwrap();
    let plan = dir.join("plan.json");
    run(triquint()
        .arg("plan")
        .arg(dir.join("job.toml"))
        .arg("-o")
        .arg(&plan)
        .args(["--starts", "1", "--quiet"]));
    // A regular file where the plot directory should be.
    let blocker = dir.join("file");
    std::fs::write(&blocker, "x").unwrap();
    for cmd in ["report", "simulate"] {
        let out = triquint()
            .arg(cmd)
            .arg(&plan)
            .arg("--plot")
            .arg(blocker.join("plots"))
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{cmd}");
        assert!(!stderr.contains("panicked"), "{cmd}: {stderr}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The `P…` labels of a chart, in document order.
fn point_labels(svg: &Svg) -> Vec<String> {
    svg.texts
        .iter()
        .filter(|t| t.starts_with('P') && t[1..].starts_with(|c: char| c.is_ascii_digit()))
        .cloned()
        .collect()
}

#[test]
fn the_charts_and_the_report_name_the_users_points_alike() {
    // Four via-points: the planner inserts straight-line knots (a C3
    // quintic spline at rest needs five), which were P1..P7 on the time
    // charts and in the report while the path plot said P1..P4.
    let dir = temp_dir("labels");
    let job = JOB.replace(", [60, -60, 650]]", "]");
    std::fs::write(dir.join("job.toml"), job).unwrap();
    run(triquint()
        .current_dir(&dir)
        .args(["plan", "job.toml", "-o", "p.json", "--plot", "plot", "-q"]));
    let path = point_labels(&parse(&dir.join("plot/path3d.svg")));
    for p in ["P1", "P2", "P3", "P4"] {
        assert!(path.iter().any(|l| l == p), "{path:?}");
    }
    let time = point_labels(&parse(&dir.join("plot/position.svg")));
    assert!(time.len() > 4, "no inserted knot: {time:?}");
    let vias: Vec<&String> = time.iter().filter(|l| !l.contains('.')).collect();
    assert_eq!(vias, ["P1", "P2", "P3", "P4"], "{time:?}");
    assert!(time.iter().any(|l| l.contains('.')), "{time:?}");
    let out = triquint()
        .current_dir(&dir)
        .args(["report", "p.json"])
        .output()
        .unwrap();
    let report = String::from_utf8(out.stdout).unwrap();
    assert!(report.contains("→P4 "), "{report}");
    assert!(!report.contains("P5"), "{report}");
}
