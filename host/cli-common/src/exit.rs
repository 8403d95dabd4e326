//! The project's exit-status table, shared by every `triquint` and
//! `triquint-sim` command (docs/cli.md, "Exit status"), and how a command ends:
//! one line on stderr, the status from the table.

use std::fmt;
use std::process::ExitCode;

/// Exit statuses. Keep in step with the table in docs/cli.md.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Status {
    /// A check found a violation.
    Violation = 1,
    /// Bad input: unparsable file, unknown key, NaN, unit error, unreachable point, limits ≤ 0.
    BadInput = 2,
    /// Valid input, but no plan meets the limits.
    Infeasible = 3,
    /// Device, bus or timeout.
    Device = 4,
    /// Motion fault: a node stopped with a fault code.
    MotionFault = 5,
    /// The planner's numerical solver failed on a valid job (worth a report).
    SolverFailure = 6,
    /// Planning was cancelled (Ctrl-C) before it finished.
    Cancelled = 7,
    /// Refused: the machine is not ready for the command (not homed, a
    /// node faulted, not at the plan's start); nothing moved.
    Refused = 8,
}

/// An error that ends a command with a status from the table and a one-line message.
#[derive(Debug)]
pub struct CliError {
    pub status: Status,
    pub message: String,
}

impl CliError {
    pub fn new(status: Status, message: impl fmt::Display) -> Self {
        Self {
            status,
            message: message.to_string(),
        }
    }
    pub fn bad_input(message: impl fmt::Display) -> Self {
        Self::new(Status::BadInput, message)
    }
    pub fn infeasible(message: impl fmt::Display) -> Self {
        Self::new(Status::Infeasible, message)
    }
    pub fn violation(message: impl fmt::Display) -> Self {
        Self::new(Status::Violation, message)
    }
    pub fn device(message: impl fmt::Display) -> Self {
        Self::new(Status::Device, message)
    }
    pub fn motion_fault(message: impl fmt::Display) -> Self {
        Self::new(Status::MotionFault, message)
    }
    pub fn refused(message: impl fmt::Display) -> Self {
        Self::new(Status::Refused, message)
    }
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for CliError {}

pub type CliResult<T = ()> = Result<T, CliError>;

/// Ends a command: success, or `NAME: error: MESSAGE` on one stderr line
/// (a multi-line message is folded) and the error's status.
pub fn main_exit(name: &str, result: CliResult) -> ExitCode {
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let msg: Vec<&str> = e.message.lines().map(str::trim).collect();
            crate::errln!("{name}: error: {}", msg.join(" "));
            ExitCode::from(e.status as u8)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn statuses_are_the_readme_table() {
        let table = [
            (Status::Violation, 1),
            (Status::BadInput, 2),
            (Status::Infeasible, 3),
            (Status::Device, 4),
            (Status::MotionFault, 5),
            (Status::SolverFailure, 6),
            (Status::Cancelled, 7),
            (Status::Refused, 8),
        ];
        for (s, n) in table {
            assert_eq!(s as u8, n);
        }
    }
}
