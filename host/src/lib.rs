//! Host side of triquint: job files, the planner, plan checks and reports.

pub mod cli;
pub mod exit;
pub mod job;
pub mod planner;
pub mod report;
pub mod robot_file;
pub mod upload;
