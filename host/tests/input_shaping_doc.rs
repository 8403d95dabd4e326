//! docs/input-shaping.md's commands run as written: its `sh` blocks in
//! order, in a fresh folder, with this build's `triquint` first on PATH.

use std::path::Path;
use std::process::Command;

#[test]
fn the_tuning_guide_runs_as_written() {
    let repo = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let page = std::fs::read_to_string(repo.join("docs/input-shaping.md")).unwrap();
    let mut script = String::from("set -eu\n");
    let mut open = false;
    for line in page.lines() {
        if line == "```sh" {
            open = true;
        } else if line.starts_with("```") {
            open = false;
        } else if open {
            script.push_str(line);
            script.push('\n');
        }
    }
    assert!(script.contains("triquint resonance"), "{script}");
    let dir = std::env::temp_dir().join(format!("triquint-input-shaping-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let bin = Path::new(env!("CARGO_BIN_EXE_triquint")).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    let out = Command::new("bash")
        .args(["-c", &script])
        .current_dir(dir.as_path())
        .env("PATH", path)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The measurement suggests a shaper at the measured mode.
    assert!(stdout.contains("suggested: [shaper] type = "), "{stdout}");
    assert!(stdout.contains("peaks 25.6"), "{stdout}");
    assert!(dir.as_path().join("resonance/response.svg").exists());
    // The shaped plan records its shaper, keeps the streaming rule and runs
    // through the drives.
    let plan = std::fs::read_to_string(dir.as_path().join("fast-ei.json")).unwrap();
    assert!(plan.contains("\"shaping\""), "no shaping record");
    assert!(
        stdout
            .lines()
            .any(|l| l.starts_with("streaming:") && l.ends_with("ok")),
        "{stdout}"
    );
    assert_eq!(
        stdout.matches("completed: true, no faults").count(),
        2,
        "{stdout}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
