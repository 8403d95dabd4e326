//! Virtual hardware for triquint: three drives running the real firmware
//! core, an in-process CAN bus that carries the exact protocol frames with
//! arbitration and a bit-time model, a plant built from an independent
//! (Lagrangian) formulation with deliberately different parameters, and the
//! same machine in real time on a SocketCAN interface (through
//! `triquint-link`, the host's side of the bus, which it also uses as the
//! host's station on the in-process bus: [`host_port`]).
#![allow(clippy::needless_range_loop)]

mod band_lu;
pub mod bus;
pub mod confinement;
pub mod faults;
pub mod flex;
pub mod host_port;
pub mod metrics;
pub mod node_port;
pub mod plant;
pub mod plant_model;
pub mod proxy;
pub mod realtime;
pub mod report;
pub mod resonance;
pub mod sim;
pub mod test_reference;
pub mod testplan;
pub mod vibration;

pub use bus::{Bus, BusConfig, Delivery};
pub use faults::{Fault, FaultInjector, FaultWindow};
pub use plant::{Plant, PlantConfig};
pub use sim::{Sim, SimConfig};
