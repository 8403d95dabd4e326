//! What the `triquint` and `triquint-sim` binaries share, so that they
//! cannot drift apart: the exit-status table and one-line errors
//! ([`exit`]), atomic output files ([`write_atomic`]), parsing of numbers,
//! triples, node lists and control rates ([`parse`]), and `--robot
//! FILE.toml` ([`robot_file`]).
//!
//! It depends on `triquint-shared` only (for [`Robot`](triquint_shared::Robot)):
//! no planner, bus or simulator.

pub mod exit;
pub mod parse;
pub mod robot_file;

pub use exit::{CliError, CliResult, Status, main_exit, write_atomic};
