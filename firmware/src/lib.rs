//! Drive firmware core of triquint: target-independent, `no_std`, allocation-free.
//!
//! A drive node is two parts in two contexts. The board's CAN receive task
//! gives every received frame (with its receive timestamp) to a
//! [`receiver::Receiver`], which decodes, reassembles and validates it and
//! returns a finished [`inbox::Item`]; the control-rate timer takes those
//! items ([`drive::Drive::take_from`], a lock-free queue in between), runs
//! [`drive::Drive::tick`] and drains [`drive::Drive::pop_tx`] into the CAN
//! controller. [`node::Node`] is both in one context (simulators, tests).
//! Hardware is reached only through the small traits in [`hal`].
#![no_std]
#![forbid(unsafe_code)]

pub mod ceiling_lock;
pub mod ceilings;
pub mod derived_config;
pub mod drive;
pub mod enable_check;
pub mod f32_cast;
pub mod hal;
pub mod handoff;
pub mod homing;
pub mod inbox;
pub mod law;
pub mod node;
pub mod reaction;
pub mod receiver;
pub mod scaling;
pub mod segment;
pub mod sync;
pub mod watchdog;

pub use drive::{Drive, QUEUE_CAPACITY};
pub use hal::{CanBus, Encoder, LimitSwitch, MotorOutput, NoSwitch, RxFrame};
pub use inbox::{Item, TickSnapshot};
pub use node::Node;
pub use receiver::Receiver;
#[cfg(test)]
mod tests;
