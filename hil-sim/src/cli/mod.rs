//! Subcommands of `triquint-sim` besides the machine itself (one module each).

pub mod proxy;
