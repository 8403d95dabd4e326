// Shared by the `robot_file` fuzz target and
// host/cli-common/tests/fuzz_corpus.rs (via include!): any bytes as a
// `--robot FILE.toml` (robot parameters and the `[homing]` table), read as
// both binaries read it, from a file.

/// The file each input is written to: one per thread, as the corpus tests
/// run in threads of one process.
fn robot_file_path() -> std::path::PathBuf {
    let thread = format!("{:?}", std::thread::current().id());
    let thread: String = thread.chars().filter(char::is_ascii_digit).collect();
    std::env::temp_dir().join(format!(
        "triquint-fuzz-robot-{}-{thread}.toml",
        std::process::id()
    ))
}

/// Runs one fuzz input: a refusal is one line; an accepted
/// machine has a valid robot and homing settings within their rules.
pub fn fuzz_robot_file(data: &[u8]) {
    let path = robot_file_path();
    std::fs::write(&path, data).expect("writing the input file");
    let read = triquint_cli_common::robot_file::read_machine(Some(&path));
    let _ = std::fs::remove_file(&path);
    match read {
        Ok((robot, homing)) => {
            assert!(
                robot.validate().is_ok(),
                "invalid robot accepted: {robot:?}"
            );
            for v in [
                homing.velocity,
                homing.acceleration,
                homing.jerk,
                homing.timeout,
            ] {
                assert!(v.is_finite() && v > 0.0, "{homing:?}");
            }
            assert!(homing.direction == 1.0 || homing.direction == -1.0);
            assert!(homing.backoff.is_finite() && homing.backoff >= 0.0);
            assert!(homing.switch_height.iter().all(|x| x.is_finite()));
        }
        Err(e) => assert!(!e.is_empty() && !e.contains('\n'), "{e:?}"),
    }
}
