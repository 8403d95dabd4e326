//! `--robot FILE.toml`: machine parameters overriding the paper's Table 1,
//! shared by `triquint` and `triquint-sim`.

use std::path::Path;

use triquint_shared::Robot;

use crate::exit::{CliError, CliResult};

/// Reads a TOML file that sets any of [`Robot`]'s fields (unknown keys rejected
/// with line and column); without a file, the paper's Table 1. The error is
/// one line naming the file.
pub fn read_robot(path: Option<&Path>) -> Result<Robot, String> {
    let robot = match path {
        None => Robot::default(),
        Some(path) => {
            let text =
                std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
            toml::from_str::<Robot>(&text)
                .map_err(|e| format!("{}: {}", path.display(), one_line(&e.to_string())))?
        }
    };
    robot.validate().map_err(|e| e.to_string())?;
    Ok(robot)
}

/// [`read_robot`] with the error as bad input (exit 2).
pub fn load_robot(path: Option<&Path>) -> CliResult<Robot> {
    read_robot(path).map_err(CliError::bad_input)
}

/// Folds a multi-line parser message (toml prints a source excerpt) into one line.
pub fn one_line(msg: &str) -> String {
    msg.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !is_excerpt(l))
        .collect::<Vec<_>>()
        .join(" ")
}

/// A source-excerpt line of a parser message: `|`, `3 | key = 1`, or `^^^`.
fn is_excerpt(line: &str) -> bool {
    let rest = line
        .trim_start_matches(|c: char| c.is_ascii_digit())
        .trim_start();
    rest.starts_with('|') || line.chars().all(|c| c == '^' || c == ' ')
}
