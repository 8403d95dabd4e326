//! Plans run through the host's upload session (`triquint-link`) on the
//! in-process virtual hardware of `triquint-sim`: `triquint simulate`
//! ([`simulate`]), and the seeded fault runs of the fault tests and the
//! soak ([`fault_run`]), both reported as `triquint_sim::report::RunReport`
//! (`measure.rs`).

pub mod fault_run;
#[cfg(test)]
mod fault_stop_tests;
#[cfg(test)]
mod feed_tests;
#[cfg(test)]
mod host_epoch_tests;
mod measure;
pub mod simulate;
#[cfg(test)]
mod stop_harness;
#[cfg(test)]
mod stop_tests;
#[cfg(test)]
mod streaming_tests;
pub mod test_reference;
#[cfg(test)]
mod tests;
