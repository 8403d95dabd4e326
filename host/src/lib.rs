//! Host side of triquint: the `triquint` command's subcommands, plan
//! reports, and the host side of the CAN session. Planning itself is the
//! `triquint-planner` library.

pub mod cli;
pub mod exit;
pub mod report;
pub mod robot_file;
pub mod upload;
