//! The exit-status table and one-line errors of every `triquint` and
//! `triquint-sim` command live in `triquint-cli-common`; this module adds
//! the planner's and the operations' errors to it.

pub use triquint_cli_common::exit::*;

use crate::ops::error::OpError;

/// The status of a planner error: infeasible (or unstreamable) 3, cancelled 7, solver
/// failure 6, anything else bad input 2.
pub fn plan_error(e: triquint_planner::PlanError) -> CliError {
    use triquint_planner::PlanError as E;
    let status = match &e {
        E::Infeasible { .. }
        | E::LeavesTravel { .. }
        | E::BelowHoldingTorque { .. }
        | E::Unstreamable { .. }
        | E::Deviation { .. } => Status::Infeasible,
        E::Cancelled { .. } => Status::Cancelled,
        E::Solver(_) => Status::SolverFailure,
        _ => Status::BadInput,
    };
    CliError::new(status, e)
}

/// The status of an operation's error: a refusal of the machine 8 (not
/// homed, faulted, too far from the start, a refused command or protocol),
/// what the input asks that cannot be done 2 (or the planner's status), a
/// silent or failing bus 4.
impl From<OpError> for CliError {
    fn from(e: OpError) -> Self {
        use triquint_link::UploadError as U;
        let e = match e {
            OpError::Plan(p) => return plan_error(p),
            e => e,
        };
        let status = match &e {
            OpError::Plan(_) => Status::BadInput,
            OpError::Unreachable(_) | OpError::OutsideTravel { .. } | OpError::Configs(_) => {
                Status::BadInput
            }
            OpError::Upload { source, .. } if source.is_config() => Status::BadInput,
            OpError::Upload {
                source: U::Segment { .. } | U::Unstreamable { .. },
                ..
            } => Status::BadInput,
            OpError::Upload {
                source:
                    U::Faulted { .. }
                    | U::NotHomed { .. }
                    | U::ArmTooFar { .. }
                    | U::Refused { .. }
                    | U::CeilingsLocked { .. }
                    | U::Version { .. },
                ..
            }
            | OpError::NotHomed { .. }
            | OpError::FeedRefused { .. } => Status::Refused,
            OpError::Open(_)
            | OpError::Port(_)
            | OpError::QueueFull
            | OpError::NoHeartbeat { .. }
            | OpError::NoAnswer { .. }
            | OpError::NoPosition { .. }
            | OpError::NoPose { .. }
            | OpError::Configure { .. }
            | OpError::Upload { .. } => Status::Device,
        };
        CliError::new(status, e)
    }
}
