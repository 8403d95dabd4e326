//! Loading `--robot FILE.toml` overrides of the machine parameters.

use std::path::Path;

use triquint_shared::Robot;
pub use triquint_sim::robot_file::one_line;

use crate::exit::{CliError, CliResult};

/// Reads a TOML file that sets any of [`Robot`]'s fields (unknown keys rejected
/// with line and column); without a file, the paper's Table 1.
pub fn load_robot(path: Option<&Path>) -> CliResult<Robot> {
    triquint_sim::robot_file::read_robot(path).map_err(CliError::bad_input)
}
