//! The host's operations on the machine, shared by the subcommands, the web
//! control and the tests, each failing with an [`error::OpError`]: the bus,
//! listening, sending a command,
//! configuring the drives, where the joints are, planning a move, running
//! a plan, the feed commands (hold, resume, stop, override). Imports
//! go one way: `cli` and `web` use `ops`, never the reverse
//! (`tests/module_cycles.rs`).

pub mod bus;
pub mod configure;
pub mod error;
pub mod feed;
pub mod joints;
pub mod listen;
pub mod plan_move;
pub mod run;
pub mod send;
pub mod shown;
