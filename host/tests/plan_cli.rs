//! `triquint plan` and `triquint check` exit statuses on bad, infeasible and
//! tampered input (docs/cli.md, "Errors, output files and input limits").

use std::process::Command;

use triquint_shared::plan::Plan;

fn max_jerk(p: &Plan) -> f64 {
    p.max_abs.jerk.iter().fold(0.0, |a, b| a.max(*b))
}

fn triquint(args: &[&str]) -> (i32, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_triquint"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn cli_exit_statuses() {
    let dir = std::env::temp_dir().join(format!("triquint-planner-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let write = |name: &str, text: &str| {
        let p = dir.join(name);
        std::fs::write(&p, text).unwrap();
        p.to_string_lossy().into_owned()
    };
    let short = write(
        "short.toml",
        "[limits]\ntotal_time = 0.3\n[path]\nunits = \"mm\"\npoints = [[-90, 90, 680], [-90, 90, 660], [-90, 90, 640], [-60, 60, 620], [-20, 20, 620]]\n",
    );
    let out = dir.join("out.json");
    let outs = out.to_string_lossy().into_owned();
    let (code, err) = triquint(&["plan", &short, "-o", &outs, "--quiet", "--starts", "2"]);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("shortest total time"), "{err}");
    assert!(!out.exists(), "a failing plan left an output file");
    let far = write(
        "far.toml",
        "[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [500, 0, 600]]\n",
    );
    let (code, err) = triquint(&["plan", &far, "-o", &outs, "--quiet"]);
    assert_eq!(code, 2);
    assert!(err.contains("point 2"), "{err}");
    let one = write(
        "one.toml",
        "[path]\nunits = \"mm\"\npoints = [[0, 0, 600]]\n",
    );
    assert_eq!(triquint(&["plan", &one, "-o", &outs]).0, 2);
    let garbage = write("garbage.json", "{\"format\": 3}");
    assert_eq!(triquint(&["check", &garbage]).0, 2);
    // A plan that violates its own limits: check exits 1.
    let ok = write(
        "ok.toml",
        "[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [20, 0, 600], [20, 20, 610], [0, 20, 620], [0, 0, 630]]\n",
    );
    assert_eq!(
        triquint(&["plan", &ok, "-o", &outs, "--quiet", "--starts", "2"]).0,
        0
    );
    let mut p: Plan = serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    p.limits.jerk = max_jerk(&p) * 0.5;
    let tampered = write("tampered.json", &serde_json::to_string(&p).unwrap());
    assert_eq!(triquint(&["check", &tampered]).0, 1);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_numbers_are_named_readably() {
    let dir = std::env::temp_dir().join(format!("triquint-plan-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let job = dir.join("huge.toml");
    std::fs::write(
        &job,
        "[limits]\ntotal_time = 1e300\n[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [10, 0, 600]]\n",
    )
    .unwrap();
    let out = dir.join("huge.json");
    let (code, err) = triquint(&["plan", &job.to_string_lossy(), "-o", &out.to_string_lossy()]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("limits.total_time") && err.contains("1e300"),
        "{err}"
    );
    assert!(err.len() < 200, "{err}");
    let (code, err) = triquint(&["ik", "0", "0", "1e308"]);
    assert_eq!(code, 2);
    assert!(err.contains("1e308") && err.len() < 200, "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn check_and_report_read_plans_of_two_to_four_points() {
    let dir = std::env::temp_dir().join(format!("triquint-plan-few-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for n in 2..=4 {
        let pts: Vec<String> = (0..n)
            .map(|i| format!("[{}, 0, {}]", 10 * i, 600 + 5 * i))
            .collect();
        let job = dir.join(format!("few{n}.toml"));
        std::fs::write(
            &job,
            format!("[path]\nunits = \"mm\"\npoints = [{}]\n", pts.join(", ")),
        )
        .unwrap();
        let out = dir
            .join(format!("few{n}.json"))
            .to_string_lossy()
            .into_owned();
        assert_eq!(
            triquint(&["plan", &job.to_string_lossy(), "-o", &out, "--quiet"]).0,
            0
        );
        let (code, err) = triquint(&["check", &out]);
        assert_eq!(code, 0, "{n} points: {err}");
        let (code, err) = triquint(&["report", &out]);
        assert_eq!(code, 0, "{n} points: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}
