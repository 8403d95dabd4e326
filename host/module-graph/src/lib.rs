//! A crate's sources read as a graph of module imports, for the tests that
//! keep triquint's modules importing one way: layers in a listed order (the
//! firmware core, the planner) or no cycle (the host binary, the board
//! images). Test tooling: it reads source text, it does not parse Rust.

mod graph;
mod layers;
mod paths;
mod sources;

pub use graph::{Graph, find_cycle, graph, show};
pub use layers::layer_violations;
pub use paths::{CratePath, crate_paths};
pub use sources::{Module, block_end, module_of, rust_files, strip_comments, without_tests};
