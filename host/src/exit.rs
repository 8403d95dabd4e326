//! The project's exit-status table, shared by every `triquint` and `triquint-sim`
//! command (README, "Exit status").

use std::fmt;

/// Exit statuses. Keep in step with the README table.
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
}

impl fmt::Display for CliError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for CliError {}

impl From<triquint_planner::PlanError> for CliError {
    fn from(e: triquint_planner::PlanError) -> Self {
        use triquint_planner::PlanError as E;
        let status = match &e {
            E::Infeasible { .. } => Status::Infeasible,
            E::Cancelled { .. } => Status::Cancelled,
            E::Solver(_) => Status::SolverFailure,
            _ => Status::BadInput,
        };
        Self::new(status, e)
    }
}

pub type CliResult<T = ()> = Result<T, CliError>;

/// Writes `contents` to `path` atomically (temporary file, then rename), so a
/// failing command never leaves a partial output file.
pub fn write_atomic(path: &std::path::Path, contents: &[u8]) -> CliResult {
    let dir = path.parent().filter(|p| !p.as_os_str().is_empty());
    if let Some(dir) = dir {
        std::fs::create_dir_all(dir)
            .map_err(|e| CliError::bad_input(format!("{}: {e}", dir.display())))?;
    }
    let name = path
        .file_name()
        .ok_or_else(|| CliError::bad_input(format!("{}: not a file path", path.display())))?;
    let tmp = path.with_file_name(format!(
        ".{}.tmp{}",
        name.to_string_lossy(),
        std::process::id()
    ));
    std::fs::write(&tmp, contents)
        .and_then(|_| std::fs::rename(&tmp, path))
        .map_err(|e| {
            let _ = std::fs::remove_file(&tmp);
            CliError::bad_input(format!("{}: {e}", path.display()))
        })
}
