//! `triquint plan` and `triquint check` exit statuses on bad, infeasible and
//! tampered input (README, "Exit status").

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

