//! `plan --json` and `check --json`: the summary and the checks as data,
//! with the same exit statuses as the text.

mod common;

use std::path::Path;

fn json(text: &str) -> serde_json::Value {
    serde_json::from_str(text).unwrap_or_else(|e| panic!("{e}: {text}"))
}

#[test]
fn plan_and_check_speak_json() {
    let dir = common::scratch("json_outputs", "plan_check");
    let job = Path::new(env!("CARGO_MANIFEST_DIR")).join("../examples/paper-case1.toml");
    let job = job.to_str().unwrap();
    let (status, out, err) = common::triquint(&dir, &["plan", job, "-o", "p.json", "--json"]);
    assert_eq!(status, 0, "{err}");
    assert!(
        err.is_empty(),
        "the summary went to stdout, not stderr: {err}"
    );
    let s = json(&out);
    assert_eq!(s["plan"], "p.json");
    assert_eq!(s["segments"], 9);
    assert_eq!(s["total_time_s"], 5.0);
    let jerk = s["max_abs"]["jerk"].as_array().unwrap();
    assert!((jerk[0].as_f64().unwrap() - 0.3325).abs() < 1e-3, "{s}");

    let (status, out, err) = common::triquint(&dir, &["check", "p.json", "--json"]);
    assert_eq!(status, 0, "{err}");
    let c = json(&out);
    assert_eq!(c["ok"], true);
    let checks = c["checks"].as_array().unwrap();
    assert!(checks.len() > 10, "{c}");
    assert!(
        checks
            .iter()
            .all(|r| r["ok"] == true && r["value"].is_number())
    );

    // A plan whose recorded jerk limit it exceeds: exit 1, and the JSON
    // says which check failed.
    let mut plan = json(&std::fs::read_to_string(dir.join("p.json")).unwrap());
    plan["limits"]["jerk"] = serde_json::json!(0.1);
    std::fs::write(dir.join("tight.json"), plan.to_string()).unwrap();
    let (status, out, err) = common::triquint(&dir, &["check", "tight.json", "--json"]);
    assert_eq!(status, 1, "{out}{err}");
    let c = json(&out);
    assert_eq!(c["ok"], false);
    let failed: Vec<_> = c["checks"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["ok"] == false)
        .collect();
    let named = |what: &str| {
        failed
            .iter()
            .filter(|r| r["check"].as_str().unwrap().contains(what))
            .count()
    };
    // The three joints' jerk; a tighter jerk limit also lengthens the stop
    // ramp, so the streaming check may fail with it.
    assert_eq!(named("max |jerk"), 3, "{c}");
    assert_eq!(failed.len(), 3 + named("streaming"), "{c}");

    // `-o -` already fills standard output with the plan.
    let (status, _, err) = common::triquint(&dir, &["plan", job, "-o", "-", "--json"]);
    assert_eq!(status, 2);
    assert!(
        err.contains("--json: standard output already holds the plan"),
        "{err}"
    );
}
