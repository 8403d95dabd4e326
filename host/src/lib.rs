//! Host side of triquint: the `triquint` command's subcommands, plan
//! reports, and runs on the in-process virtual hardware. Planning itself is
//! the `triquint-planner` library, the host's side of the bus (SocketCAN,
//! the upload session) is `triquint-link`.

pub mod cli;
pub mod exit;
pub mod inprocess;
pub mod machine_arg;
pub mod ops;
pub mod report;
pub mod web;
