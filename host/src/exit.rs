//! The exit-status table and one-line errors of every `triquint` and
//! `triquint-sim` command live in `triquint-cli-common`; this module adds
//! the planner's errors to it.

pub use triquint_cli_common::exit::*;

/// The status of a planner error: infeasible 3, cancelled 7, solver
/// failure 6, anything else bad input 2.
pub fn plan_error(e: triquint_planner::PlanError) -> CliError {
    use triquint_planner::PlanError as E;
    let status = match &e {
        E::Infeasible { .. } | E::LeavesTravel { .. } => Status::Infeasible,
        E::Cancelled { .. } => Status::Cancelled,
        E::Solver(_) => Status::SolverFailure,
        _ => Status::BadInput,
    };
    CliError::new(status, e)
}
