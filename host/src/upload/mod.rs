//! Host-side upload session: configuration check, segment streaming with flow
//! control, time sync, arm and start. One code path for the in-process bus and
//! SocketCAN: the [`Session`] is a non-blocking state machine driven by
//! [`Session::poll`] over any [`CanPort`].

pub mod fault_run;
pub mod session;
pub mod sim_port;
pub mod socket_port;
#[cfg(test)]
mod tests;

pub use session::{FaultReport, Outcome, Progress, Session, SessionOptions, UploadError};

use triquint_shared::protocol::Frame;

/// A frame the port received, with the host time (µs) it completed on the bus.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Received {
    pub frame: Frame,
    pub t_us: u64,
    /// The host's own frame echoed back (transmit confirmation with timestamp).
    pub own: bool,
}

/// A transport failure (device gone, bus off).
#[derive(Debug, thiserror::Error)]
#[error("CAN port: {0}")]
pub struct PortError(pub String);

/// What the session needs from a CAN interface.
pub trait CanPort {
    /// Host clock (µs), monotonic.
    fn now_us(&mut self) -> u64;
    /// Queues a frame; `Ok(false)` when the transmit queue is full (try later).
    fn send(&mut self, frame: &Frame) -> Result<bool, PortError>;
    /// The next received frame, own transmissions included, if any.
    fn recv(&mut self) -> Result<Option<Received>, PortError>;
}
