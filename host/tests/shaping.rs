//! `triquint plan --shaper` and a job's `[shaper]` write a format 5 plan that
//! `check` proves from its record (docs/plan-format.md, docs/vibration.md).

use std::path::PathBuf;
use std::process::Command;

fn triquint(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_triquint"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("triquint-shaping-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn row<'a>(checks: &'a serde_json::Value, name: &str) -> &'a serde_json::Value {
    checks["checks"]
        .as_array()
        .unwrap()
        .iter()
        .find(|r| r["check"].as_str().unwrap().starts_with(name))
        .unwrap_or_else(|| panic!("no `{name}` in {checks:#}"))
}

#[test]
fn a_shaped_plan_records_its_shaper_and_check_proves_it() {
    let dir = scratch();
    let job = dir.join("job.toml");
    std::fs::write(
        &job,
        "[shaper]\ntype = \"mzv\"\nfrequency_hz = 30\n\
         [path]\nunits = \"mm\"\npoints = [[-90, 90, 680], [-90, 90, 660], [-60, 60, 640]]\n",
    )
    .unwrap();
    let plan = |out: &str, extra: &[&str]| {
        let out = dir.join(out);
        let mut args = vec![
            "plan",
            job.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ];
        args.extend_from_slice(extra);
        let (code, _, err) = triquint(&args);
        assert_eq!(code, 0, "{err}");
        let text = std::fs::read_to_string(&out).unwrap();
        (
            out,
            serde_json::from_str::<serde_json::Value>(&text).unwrap(),
        )
    };
    // The job's shaper, then the command line's over it, then none.
    let (_, p) = plan("mzv.json", &[]);
    assert_eq!(p["format"], "triquint-plan/5");
    assert_eq!(p["shaping"]["shaper"]["type"], "mzv");
    assert_eq!(p["shaping"]["shaper"]["damping"], 0.1);
    let (ei, p) = plan("ei.json", &["--shaper", "EI:25.5:0.05"]);
    assert_eq!(p["shaping"]["shaper"]["type"], "ei");
    assert_eq!(p["shaping"]["shaper"]["frequency_hz"], 25.5);
    let unshaped = p["shaping"]["unshaped"]["total_time_s"].as_f64().unwrap();
    let shaped = p["total_time_s"].as_f64().unwrap();
    // EI at 25.5 Hz lasts one damped period, 39.3 ms.
    assert!(
        (shaped - unshaped - 0.039265).abs() < 2e-6,
        "{shaped} {unshaped}"
    );
    let (_, p) = plan("none.json", &["--shaper", "none"]);
    assert_eq!(p["format"], "triquint-plan/3");
    assert!(p.get("shaping").is_none());

    let json = |path: &PathBuf| {
        let (code, out, err) = triquint(&["check", path.to_str().unwrap(), "--json"]);
        (
            code,
            serde_json::from_str::<serde_json::Value>(&out).unwrap_or_else(|_| panic!("{err}")),
        )
    };
    let (_, c) = json(&ei);
    assert_eq!(row(&c, "shaped = unshaped")["ok"], true, "{c:#}");
    let dev = row(&c, "via-point deviation");
    assert_eq!(dev["ok"], true);
    assert!(dev["value"].as_f64().unwrap() > 1e-6, "{dev}");

    // Another shaper of the same duration in the record: the convolution
    // row fails, exit 1.
    let text = std::fs::read_to_string(&ei).unwrap();
    let tampered = dir.join("tampered.json");
    std::fs::write(
        &tampered,
        text.replacen("\"type\": \"ei\"", "\"type\": \"zvd\"", 1),
    )
    .unwrap();
    let (code, c) = json(&tampered);
    assert_eq!(code, 1);
    assert_eq!(row(&c, "shaped = unshaped")["ok"], false, "{c:#}");
    // A shaped plan that says it is format 3: refused as no plan, exit 2.
    std::fs::write(
        &tampered,
        text.replacen("triquint-plan/5", "triquint-plan/3", 1),
    )
    .unwrap();
    let (code, _, err) = triquint(&["check", tampered.to_str().unwrap()]);
    assert_eq!(code, 2, "{err}");
    assert!(err.contains("has no `shaping`"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
