//! Loading `--robot FILE.toml` overrides of the machine parameters (shared
//! with `triquint-sim` in `triquint-cli-common`).

pub use triquint_cli_common::robot_file::{load_machine, load_robot};
