//! The host's station on the in-process bus as a `triquint-link` port, so
//! the host's upload session runs unchanged against the virtual drives
//! (`triquint simulate`, the fault runs).

use triquint_link::{CanPort, PortError, Received};
use triquint_shared::protocol::Frame;

use crate::Sim;

/// The host's station on the in-process bus.
pub struct SimPort<'a> {
    pub sim: &'a mut Sim,
    /// Host transmit queue length (like a SocketCAN txqueuelen).
    pub tx_queue: usize,
}

impl CanPort for SimPort<'_> {
    fn now_us(&mut self) -> u64 {
        self.sim.now_ns() / 1000
    }
    fn send(&mut self, frame: &Frame) -> Result<bool, PortError> {
        if self.sim.host_pending() >= self.tx_queue {
            return Ok(false);
        }
        self.sim.host_send(*frame);
        Ok(true)
    }
    fn recv(&mut self) -> Result<Option<Received>, PortError> {
        Ok(self.sim.host_receive().map(|d| Received {
            frame: d.frame,
            t_us: d.t_ns / 1000,
            own: d.own,
        }))
    }
}
