// Shared by the `machine_file` fuzz target and
// host/cli-common/tests/fuzz_corpus.rs (via include!): any bytes as a
// `--machine FILE.toml`, read as both binaries read it, from a file.

/// The file each input is written to: one per thread, as the corpus tests
/// run in threads of one process.
fn machine_file_path() -> std::path::PathBuf {
    let thread = format!("{:?}", std::thread::current().id());
    let thread: String = thread.chars().filter(char::is_ascii_digit).collect();
    std::env::temp_dir().join(format!(
        "triquint-fuzz-machine-{}-{thread}.toml",
        std::process::id()
    ))
}

/// Runs one fuzz input: a refusal is one line; an accepted machine passes
/// its own validation (every range and rule of docs/machine.md).
pub fn fuzz_machine_file(data: &[u8]) {
    let path = machine_file_path();
    std::fs::write(&path, data).expect("writing the input file");
    let read = triquint_cli_common::machine_file::read_machine(Some(&path));
    let _ = std::fs::remove_file(&path);
    match read {
        Ok(machine) => {
            assert!(machine.validate().is_ok(), "invalid machine accepted: {machine:?}");
            let s = machine.drive_settings();
            assert!(s.counts_per_metre.iter().all(|c| c.is_finite() && *c != 0.0));
            assert!(s.homing.switch_height.iter().all(|x| x.is_finite()));
        }
        Err(e) => {
            let e = e.to_string();
            assert!(!e.is_empty() && !e.contains('\n'), "{e:?}");
        }
    }
}
