//! What the `triquint` and `triquint-sim` binaries share, so that they
//! cannot drift apart: the exit-status table and one-line errors
//! ([`exit`]), output files and standard output ([`output`]), bounded
//! input reads ([`input`]), parsing of numbers, triples, node lists and
//! control rates ([`parse`]), and the machine file `--machine FILE.toml` ([`machine_file`]).
//! The Python package writes its plan files through [`output`] too.
//!
//! It depends on `triquint-shared` only (for [`Robot`](triquint_shared::Robot)):
//! no planner, bus or simulator.

pub mod exit;
pub mod input;
pub mod machine_file;
pub mod output;
pub mod parse;

pub use exit::{CliError, CliResult, Status, main_exit};
pub use output::{write_atomic, write_output, write_outputs};
