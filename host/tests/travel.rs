//! Slider travel is a limit like the others, and no figure a plan records
//! is trusted: `ik`, `fk`, `plan` and `check` on the built binary.

use std::path::{Path, PathBuf};

mod common;

use common::triquint;

fn scratch(name: &str) -> PathBuf {
    common::scratch("travel", name)
}

/// The paper's Case II as `triquint plan` writes it.
fn case2_plan(dir: &Path) -> serde_json::Value {
    let job = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/paper-case2.toml");
    let (status, _, err) = triquint(
        dir,
        &["plan", job.to_str().unwrap(), "-o", "case2.json", "--quiet"],
    );
    assert_eq!(status, 0, "{err}");
    serde_json::from_str(&std::fs::read_to_string(dir.join("case2.json")).unwrap()).unwrap()
}

#[test]
fn ik_refuses_a_pose_below_the_travel() {
    let dir = scratch("ik_refuses_a_pose_below_the_travel");
    // Was q1 = −286.8 mm, exit 0.
    let (status, out, err) = triquint(dir.as_path(), &["ik", "0", "0", "100"]);
    assert_eq!(status, 2, "{out}{err}");
    assert!(
        err.contains("slider 1 at -286.782 mm is below its travel min 50 mm"),
        "{err}"
    );
    let (status, _, err) = triquint(dir.as_path(), &["ik", "0", "0", "600"]);
    assert_eq!(status, 0, "{err}");
}

#[test]
fn fk_refuses_joints_outside_the_travel() {
    let dir = scratch("fk_refuses_joints_outside_the_travel");
    let (status, _, err) = triquint(dir.as_path(), &["fk", "100", "713", "100"]);
    assert_eq!(status, 2, "{err}");
    assert!(
        err.contains("slider 2 at 713 mm is above its travel max 415 mm"),
        "{err}"
    );
    let (status, _, err) = triquint(dir.as_path(), &["fk", "100", "100", "100"]);
    assert_eq!(status, 0, "{err}");
}

#[test]
fn a_job_down_to_z_100_mm_is_refused_naming_the_point_and_the_slider() {
    let dir = scratch("a_job_down_to_z_100_mm_is_refused_naming_the_point_and_the_slider");
    std::fs::write(
        dir.as_path().join("job.toml"),
        "[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [0, 0, 500], [0, 0, 100]]\n",
    )
    .unwrap();
    let (status, out, err) = triquint(
        dir.as_path(),
        &["plan", "job.toml", "-o", "out.json", "--quiet"],
    );
    assert_eq!(status, 2, "{out}{err}");
    assert!(
        err.contains("point 3 (0, 0, 100) mm is outside the travel: slider 1 at"),
        "{err}"
    );
    assert!(!dir.as_path().join("out.json").exists());
}

#[test]
fn check_compares_every_recorded_maximum() {
    let dir = scratch("check_compares_every_recorded_maximum");
    let case2 = case2_plan(&dir);
    let (status, _, err) = triquint(&dir, &["check", "case2.json"]);
    assert_eq!(status, 0, "{err}");
    for field in ["velocity", "acceleration", "torque"] {
        let mut p = case2.clone();
        p["max_abs"][field] = serde_json::json!([1e-9, 1e-9, 1e-9]);
        std::fs::write(dir.as_path().join("p.json"), p.to_string()).unwrap();
        let (status, out, err) = triquint(dir.as_path(), &["check", "p.json"]);
        assert_eq!(status, 1, "{field}: {out}{err}");
        assert!(
            out.lines()
                .any(|l| l.starts_with(&format!("reported max {field}")) && l.ends_with("VIOLATED")),
            "{field}: {out}"
        );
    }
}

#[test]
fn check_refuses_limits_no_job_could_have() {
    let dir = scratch("check_refuses_limits_no_job_could_have");
    let mut p = case2_plan(&dir);
    for k in ["velocity", "acceleration", "jerk", "torque"] {
        p["limits"][k] = serde_json::json!(1e300);
    }
    std::fs::write(dir.as_path().join("p.json"), p.to_string()).unwrap();
    let (status, out, err) = triquint(dir.as_path(), &["check", "p.json"]);
    assert_eq!(status, 2, "{out}{err}");
    assert!(err.contains("`velocity` is 1e300, not in"), "{err}");
}

#[test]
fn check_proves_the_travel_the_plan_records() {
    let dir = scratch("recorded-travel");
    let mut p = case2_plan(&dir);
    assert_eq!(p["format"], "triquint-plan/3");
    assert_eq!(p["travel"]["max"], serde_json::json!([0.415, 0.415, 0.415]));
    // Case II moves slider 3 down to about 82 mm: a travel from 100 mm fails.
    p["travel"]["min"] = serde_json::json!([0.05, 0.05, 0.1]);
    std::fs::write(dir.join("p.json"), p.to_string()).unwrap();
    let (status, out, err) = triquint(&dir, &["check", "p.json"]);
    assert_eq!(status, 1, "{out}{err}");
    assert!(
        out.lines()
            .any(|l| l.starts_with("travel min − lowest position slider 3")
                && l.ends_with("VIOLATED")),
        "{out}"
    );
    // Format 2 without its travel is refused; format 1 loads with the default.
    let mut p = case2_plan(&dir);
    p.as_object_mut().unwrap().remove("travel");
    std::fs::write(dir.join("p.json"), p.to_string()).unwrap();
    let (status, _, err) = triquint(&dir, &["check", "p.json"]);
    assert_eq!(status, 2, "{err}");
    assert!(err.contains("records its `travel`"), "{err}");
    p["format"] = serde_json::json!("triquint-plan/1");
    std::fs::write(dir.join("p.json"), p.to_string()).unwrap();
    let (status, out, err) = triquint(&dir, &["check", "p.json"]);
    assert_eq!(status, 0, "{out}{err}");
}

#[test]
fn a_path_that_overshoots_a_narrow_travel_plans_inside_it_and_checks() {
    let dir = scratch("narrow-travel");
    std::fs::write(
        dir.join("narrow.toml"),
        "[axis.1]\ntravel_max = 0.254\n[axis.2]\ntravel_max = 0.254\n[axis.3]\ntravel_max = 0.255\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("job.toml"),
        "[limits]\ntotal_time = 4.0\n[path]\nunits = \"mm\"\n\
         points = [[0, 0, 600], [0, 0, 640], [30, 0, 610], [0, 20, 630], [0, 0, 600]]\n",
    )
    .unwrap();
    // Was exit 3: "slider 1 reaches 255.671 mm between knots 2 and 3".
    let (status, out, err) = triquint(
        &dir,
        &[
            "plan",
            "job.toml",
            "--machine",
            "narrow.toml",
            "-o",
            "p.json",
            "--quiet",
        ],
    );
    assert_eq!(status, 0, "{out}{err}");
    let (status, out, err) = triquint(&dir, &["check", "p.json", "--machine", "narrow.toml"]);
    assert_eq!(status, 0, "{out}{err}");
    let travel: Vec<&str> = out.lines().filter(|l| l.contains("travel")).collect();
    assert_eq!(travel.len(), 6, "{out}");
    assert!(travel.iter().all(|l| l.ends_with("ok")), "{out}");
}
