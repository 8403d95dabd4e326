//! Subcommands of `triquint-sim` besides the machine itself (one module
//! each), and the report both write.

pub mod proxy;

use triquint_cli_common::{CliResult, write_atomic};

/// Writes the report to `path`, or to `stdout` for `-` (as `triquint plan
/// -o -` takes it) rather than to a file named `-`.
pub fn write_report(
    path: &std::path::Path,
    json: &str,
    stdout: &mut impl std::io::Write,
) -> CliResult {
    if path.as_os_str() != "-" {
        return write_atomic(path, json.as_bytes());
    }
    writeln!(stdout, "{json}")
        .and_then(|()| stdout.flush())
        .map_err(|e| triquint_cli_common::output::stdout_error(&e))
}

#[cfg(test)]
mod tests {
    use super::write_report;
    use std::path::Path;

    #[test]
    fn a_report_to_dash_goes_to_standard_output_not_a_file() {
        let dir = std::env::temp_dir().join(format!("triquint-sim-report-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let cwd = std::env::current_dir().unwrap();
        let mut out = Vec::new();
        write_report(Path::new("-"), "{\"runs\":[]}", &mut out).unwrap();
        assert_eq!(out, b"{\"runs\":[]}\n");
        assert!(!cwd.join("-").exists(), "a file named - was written");
        let file = dir.join("report.json");
        let mut none = Vec::new();
        write_report(&file, "{}", &mut none).unwrap();
        assert!(none.is_empty());
        assert_eq!(std::fs::read_to_string(&file).unwrap(), "{}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
