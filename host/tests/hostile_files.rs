//! Hostile files around the built `triquint` binary: outputs that are not
//! regular files or are the command's inputs, links planted at temporary
//! names, plots of a plan that is not written, inputs without an end,
//! standard output closed or full, standard error closed, and job points
//! of the wrong length.
//! Each case ends with the exit status of docs/cli.md and one line on stderr, no
//! panic, and nothing written where it must not be.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

const JOB: &str = "objective = \"min-max-jerk\"\n[path]\nunits = \"mm\"\n\
                   points = [[-90, 90, 680], [-90, 90, 660], [-60, 60, 640]]\n";

fn bin() -> &'static str {
    env!("CARGO_BIN_EXE_triquint")
}

/// A fresh scratch folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("triquint-hostile-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `triquint ARGS` in `dir` with the address space capped (ulimit -v,
/// KiB), so an unbounded read fails fast instead of taking the machine.
fn run_in(dir: &Path, args: &[&str]) -> Output {
    Command::new("sh")
        .arg("-c")
        .arg("ulimit -v 2000000; exec \"$0\" \"$@\"")
        .arg(bin())
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

/// Asserts exit `status` with exactly one stderr line containing `says`.
fn assert_error(out: &Output, status: i32, says: &str, case: &str) {
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(status), "{case}: stderr {err}");
    assert_eq!(err.lines().count(), 1, "{case}: {err}");
    assert!(err.contains(says), "{case}: {err:?} lacks {says:?}");
    assert!(!err.contains("panicked"), "{case}: {err}");
}

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// A plan of the job, written once per test that needs one.
fn planned(dir: &Path) -> PathBuf {
    std::fs::write(dir.join("job.toml"), JOB).unwrap();
    let out = run_in(
        dir,
        &["plan", "job.toml", "-o", "plan.json", "--starts", "1", "-q"],
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    dir.join("plan.json")
}

#[cfg(unix)]
#[test]
fn outputs_that_are_not_regular_files_are_left_alone() {
    use std::os::unix::fs::FileTypeExt;
    let dir = scratch("targets");
    std::fs::write(dir.join("job.toml"), JOB).unwrap();
    let plan = |target: &str| run_in(&dir, &["plan", "job.toml", "-o", target, "-q"]);

    let fifo = dir.join("fifo");
    assert!(
        Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .unwrap()
            .success()
    );
    assert_error(&plan("fifo"), 2, "fifo: is a FIFO", "FIFO");
    assert!(
        std::fs::symlink_metadata(&fifo)
            .unwrap()
            .file_type()
            .is_fifo()
    );

    std::fs::write(dir.join("target"), "keep").unwrap();
    std::os::unix::fs::symlink("target", dir.join("link.json")).unwrap();
    assert_error(&plan("link.json"), 2, "is a symbolic link", "link");
    assert!(
        std::fs::symlink_metadata(dir.join("link.json"))
            .unwrap()
            .file_type()
            .is_symlink()
    );
    assert_eq!(std::fs::read_to_string(dir.join("target")).unwrap(), "keep");

    std::fs::create_dir(dir.join("folder")).unwrap();
    assert_error(&plan("folder"), 2, "is a folder", "folder");

    // A device node (a /dev/full of our own, so the real one is never at
    // stake): root only; CI runs as root.
    let dev = dir.join("full");
    let made = Command::new("mknod")
        .arg(&dev)
        .args(["c", "1", "7"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if made {
        assert_error(&plan("full"), 2, "full: is a device", "device");
        assert!(
            std::fs::symlink_metadata(&dev)
                .unwrap()
                .file_type()
                .is_char_device()
        );
    } else {
        eprintln!("device case skipped: mknod needs root");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_plan_never_overwrites_its_job_or_points() {
    let dir = scratch("inputs");
    std::fs::write(dir.join("job.toml"), JOB).unwrap();
    let out = run_in(&dir, &["plan", "job.toml", "-o", "job.toml", "-q"]);
    assert_error(&out, 2, "is also an input", "job");
    assert_eq!(std::fs::read_to_string(dir.join("job.toml")).unwrap(), JOB);
    // The same file through another name, and the job's points file.
    let out = run_in(&dir, &["plan", "job.toml", "-o", "./job.toml", "-q"]);
    assert_error(&out, 2, "is also an input", "job by another name");
    let pts = "-90 90 680\n-90 90 660\n-60 60 640\n";
    std::fs::write(dir.join("pts.csv"), pts).unwrap();
    std::fs::write(
        dir.join("file.toml"),
        "[path]\nunits = \"mm\"\nfile = \"pts.csv\"\n",
    )
    .unwrap();
    let out = run_in(&dir, &["plan", "file.toml", "-o", "pts.csv", "-q"]);
    assert_error(&out, 2, "is also an input", "points file");
    assert_eq!(std::fs::read_to_string(dir.join("pts.csv")).unwrap(), pts);
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(unix)]
#[test]
fn links_planted_at_temporary_names_are_not_followed() {
    let dir = scratch("planted");
    std::fs::write(dir.join("job.toml"), JOB).unwrap();
    std::fs::write(dir.join("target"), "keep").unwrap();
    // The old temporary name was `.NAME.tmp<PID>`: plant the next PIDs.
    let pid = std::process::id();
    for p in pid..pid + 3000 {
        std::os::unix::fs::symlink("target", dir.join(format!(".out.json.tmp{p}"))).unwrap();
    }
    let out = run_in(
        &dir,
        &["plan", "job.toml", "-o", "out.json", "--starts", "1", "-q"],
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert_eq!(std::fs::read_to_string(dir.join("target")).unwrap(), "keep");
    assert!(
        std::fs::symlink_metadata(dir.join("out.json"))
            .unwrap()
            .is_file()
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn plots_are_not_left_when_the_plan_is_not_written() {
    let dir = scratch("plots");
    std::fs::write(dir.join("job.toml"), JOB).unwrap();
    std::fs::create_dir(dir.join("taken")).unwrap();
    let out = run_in(
        &dir,
        &[
            "plan", "job.toml", "-o", "taken", "--plot", "svg", "--starts", "1", "-q",
        ],
    );
    assert_error(&out, 2, "taken", "plan output is a folder");
    let svgs = dir.join("svg");
    assert!(
        !svgs.exists() || names(&svgs).is_empty(),
        "{:?}",
        names(&svgs)
    );
    // No temporary left anywhere either.
    assert_eq!(names(&dir), ["job.toml", "taken"]);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn endless_inputs_are_refused_at_their_limit() {
    let dir = scratch("endless");
    let plan = planned(&dir);
    let plan = plan.to_str().unwrap();
    let cases: [(&str, Vec<&str>, &str); 6] = [
        (
            "job",
            vec!["plan", "/dev/zero", "-o", "x.json"],
            "larger than 4 MiB, the limit for a job file",
        ),
        (
            "plan",
            vec!["check", "/dev/zero"],
            "larger than 16 MiB, the limit for a plan file",
        ),
        (
            "report",
            vec!["report", "/dev/zero"],
            "the limit for a plan file",
        ),
        (
            "simulate",
            vec!["simulate", "/dev/zero"],
            "the limit for a plan file",
        ),
        (
            "machine",
            vec!["check", plan, "--machine", "/dev/zero"],
            "larger than 64 KiB, the limit for a machine file",
        ),
        (
            "starts",
            vec!["plan", "job.toml", "-o", "x.json", "--starts", "1000000000"],
            "1 to 1000",
        ),
    ];
    for (case, args, says) in cases {
        let out = run_in(&dir, &args);
        assert_error(&out, 2, says, case);
    }
    std::fs::write(
        dir.join("zero.toml"),
        "[path]\nunits = \"mm\"\nfile = \"/dev/zero\"\n",
    )
    .unwrap();
    let out = run_in(&dir, &["plan", "zero.toml", "-o", "x.json"]);
    assert_error(
        &out,
        2,
        "/dev/zero: larger than 4 MiB, the limit for a points file",
        "points",
    );
    assert!(!dir.join("x.json").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `triquint ARGS` with standard output a pipe whose reader is gone.
fn into_closed_pipe(dir: &Path, args: &[&str]) -> Output {
    // The reader is a process that has already ended: every write fails
    // with EPIPE, whatever the timing.
    let mut reader = Command::new("true").stdin(Stdio::piped()).spawn().unwrap();
    let write_end = reader.stdin.take().unwrap();
    reader.wait().unwrap();
    Command::new(bin())
        .args(args)
        .current_dir(dir)
        .stdout(Stdio::from(write_end))
        .stderr(Stdio::piped())
        .output()
        .unwrap()
}

/// Every subcommand that prints without a bus.
fn printing_commands(plan: &str) -> Vec<Vec<&str>> {
    vec![
        vec!["check", plan],
        vec!["report", plan],
        vec!["report", plan, "--json"],
        vec!["simulate", plan],
        vec!["simulate", plan, "--json"],
        vec!["ik", "0", "0", "600"],
        vec!["ik", "0", "0", "600", "--json"],
        vec!["fk", "300", "300", "300"],
        vec!["fk", "300", "300", "300", "--json"],
        vec![
            "torque",
            "--q",
            "0.3,0.3,0.3",
            "--qd",
            "0,0,0",
            "--qdd",
            "0,0,0",
        ],
        vec![
            "torque",
            "--q",
            "0.3,0.3,0.3",
            "--qd",
            "0,0,0",
            "--qdd",
            "0,0,0",
            "--json",
        ],
        vec!["plan", "job.toml", "-o", "-", "--starts", "1", "-q"],
    ]
}

#[test]
fn a_closed_pipe_ends_quietly_with_status_0() {
    let dir = scratch("pipe");
    let plan = planned(&dir);
    for args in printing_commands(plan.to_str().unwrap()) {
        let out = into_closed_pipe(&dir, &args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {err}");
        assert!(err.is_empty(), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Runs `triquint ARGS` with standard error a pipe whose reader is gone
/// (`closed_pipe`) or closed outright (`2>&-`).
fn without_stderr(dir: &Path, args: &[&str], closed_pipe: bool) -> Output {
    let mut cmd = if closed_pipe {
        let mut reader = Command::new("true").stdin(Stdio::piped()).spawn().unwrap();
        let write_end = reader.stdin.take().unwrap();
        reader.wait().unwrap();
        let mut c = Command::new(bin());
        c.stderr(Stdio::from(write_end));
        c
    } else {
        let mut c = Command::new("sh");
        c.arg("-c").arg("exec \"$0\" \"$@\" 2>&-").arg(bin());
        c.stderr(Stdio::null());
        c
    };
    cmd.args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .output()
        .unwrap()
}

/// An error, a progress line or a note on a standard error nobody reads
/// keeps its exit status instead of a panic (101): standard output is
/// covered above.
#[test]
fn a_closed_standard_error_keeps_the_exit_status() {
    let dir = scratch("stderr");
    let plan = planned(&dir);
    let plan = plan.to_str().unwrap();
    let plots = dir.join("plots");
    let cases: [(&[&str], i32); 4] = [
        (&["check", "missing.json"], 2),
        (
            &["plan", "missing.toml", "-o", "x.json", "--starts", "1"],
            2,
        ),
        (&["plan", "job.toml", "-o", "y.json", "--starts", "1"], 0),
        (&["report", plan, "--plot", plots.to_str().unwrap()], 0),
    ];
    for closed_pipe in [true, false] {
        for (args, status) in cases {
            let out = without_stderr(&dir, args, closed_pipe);
            assert_eq!(
                out.status.code(),
                Some(status),
                "{args:?} (stderr a closed pipe: {closed_pipe})"
            );
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[cfg(target_os = "linux")]
#[test]
fn a_full_standard_output_is_a_clear_error() {
    let dir = scratch("full");
    let plan = planned(&dir);
    for args in printing_commands(plan.to_str().unwrap()) {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap();
        let out = Command::new(bin())
            .args(&args)
            .current_dir(&dir)
            .stdout(full)
            .output()
            .unwrap();
        let case = format!("{args:?}");
        assert_error(
            &out,
            2,
            "cannot write standard output: No space left on device",
            &case,
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_job_point_has_exactly_three_coordinates() {
    let dir = scratch("points");
    for (points, found) in [
        (
            "[[-90, 90, 680], [-90, 90, 660, 5], [-60, 60, 640]]",
            "found 4",
        ),
        ("[[-90, 90, 680], [-90, 90], [-60, 60, 640]]", "found 2"),
    ] {
        let job = format!("[path]\nunits = \"mm\"\npoints = {points}\n");
        std::fs::write(dir.join("job.toml"), job).unwrap();
        let out = run_in(
            &dir,
            &["plan", "job.toml", "-o", "x.json", "--starts", "1", "-q"],
        );
        assert_error(&out, 2, found, points);
        assert_error(&out, 2, "job.toml:3", points);
        assert!(!dir.join("x.json").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn absurd_robots_are_bad_input_in_short_messages() {
    let dir = scratch("robots");
    let plan = planned(&dir);
    let job = format!(
        "[robot]\nlead = 1e300\n{}",
        JOB.replace("objective = \"min-max-jerk\"\n", "")
    );
    std::fs::write(dir.join("absurd.toml"), job).unwrap();
    let out = run_in(
        &dir,
        &["plan", "absurd.toml", "-o", "x.json", "--starts", "1", "-q"],
    );
    assert_error(
        &out,
        2,
        "robot.lead: robot parameter `lead` must be in 1e-6..1e6, got 1e300",
        "job",
    );
    std::fs::write(dir.join("robot.toml"), "[robot]\nplatform_mass = -1e250\n").unwrap();
    let out = run_in(
        &dir,
        &["check", plan.to_str().unwrap(), "--robot", "robot.toml"],
    );
    assert_error(
        &out,
        2,
        "line 2: `robot.platform_mass` = -1e250: must be in 0..1e6",
        "machine file",
    );
    assert!(
        out.stderr.len() < 200,
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}
