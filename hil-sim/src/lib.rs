//! Virtual hardware for triquint: three drives running the real firmware
//! core, an in-process CAN bus that carries the exact protocol frames with
//! arbitration and a bit-time model, and a plant built from an independent
//! (Lagrangian) formulation with deliberately different parameters.
#![allow(clippy::needless_range_loop)]

pub mod bus;
pub mod faults;
pub mod metrics;
pub mod plant;
pub mod plot;
pub mod sim;
pub mod testplan;

pub use bus::{Bus, BusConfig, Delivery};
pub use faults::{Fault, FaultInjector, FaultWindow};
pub use plant::{Plant, PlantConfig};
pub use sim::{Sim, SimConfig};
