//! Drive firmware core of triquint: target-independent, `no_std`, allocation-free.
//!
//! One [`node::Node`] per drive. The board support calls
//! [`node::Node::on_frame`] for every received frame (with its receive
//! timestamp), [`node::Node::tick`] from the control-rate timer, and drains
//! [`node::Node::poll_tx`] into the CAN controller. Hardware is reached only
//! through the small traits in [`hal`].
#![no_std]
#![forbid(unsafe_code)]

pub mod hal;
pub mod node;
pub mod ns;
pub mod scaling;
pub mod segment;
pub mod sync;

pub use hal::{CanPort, Clock, Encoder, MotorOutput, RxFrame};
pub use node::{Node, QUEUE_CAPACITY};
#[cfg(test)]
mod tests;
