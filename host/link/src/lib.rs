//! The host side of the triquint CAN bus.
//!
//! - [`session`]: one upload of one plan to the three drives, a
//!   non-blocking state machine driven by [`Session::poll`] over any
//!   [`CanPort`], split by concern: the time-sync master
//!   (`session/time_sync.rs`), the configuration (`session/configure.rs`),
//!   flow-controlled streaming with retransmission (`session/stream.rs`),
//!   the arm/start sequence (`session/start.rs`), and what the host knows
//!   of each node (`session/nodes.rs`);
//! - [`estop`]: the host's emergency stop, confirmed by every drive;
//! - [`configs`]: the drives' configurations for a plan, from its exact
//!   maxima (`plan.max_abs`), or for the limits themselves;
//! - [`override_cap`]: the largest feed override a plan allows;
//! - [`host_clock`]: the host time another process learns from TimeSync;
//! - [`status`]: what state each drive is in, from its heartbeats (the
//!   model of `triquint status`, serialisable);
//! - [`socketcan`]: a Linux SocketCAN interface as a port (the one SocketCAN
//!   access of the project; `triquint-sim` uses it too).
//!
//! One code path for the in-process bus of `triquint-sim` and SocketCAN.
//! Depends on `triquint-shared` and the bus crates only: no planner, no
//! simulator.

pub mod configs;
pub mod drive;
pub mod estop;
pub mod host_clock;
pub mod session;
pub mod socketcan;
pub mod status;

pub use configs::DriveConfigs;
pub use drive::Drive;
pub use estop::{EstopAnswer, EstopError, EstopWatch, emergency_stop};
pub use host_clock::HostClock;
pub use session::{
    FaultReport, Feed, NodeView, Outcome, Progress, Session, SessionOptions, UploadError,
};
pub use socketcan::{SocketCanError, SocketCanPort, SocketRx, open_host};
pub use status::{Listener, MachineStatus, NodeStatus};
pub use triquint_shared::plan::override_cap;

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
pub enum PortError {
    /// The SocketCAN interface failed to send or receive.
    #[error("CAN port: {0}")]
    SocketCan(#[from] SocketCanError),
}

/// What the session needs from a CAN interface.
pub trait CanPort {
    /// Host clock (µs), monotonic.
    fn now_us(&mut self) -> u64;
    /// Queues a frame; `Ok(false)` when the transmit queue is full (try later).
    fn send(&mut self, frame: &Frame) -> Result<bool, PortError>;
    /// The next received frame, own transmissions included, if any.
    fn recv(&mut self) -> Result<Option<Received>, PortError>;
}
