//! The session over a real SocketCAN interface: the port of `triquint-sim`'s
//! drives ([`SocketCanPort`]), opened with transmit confirmations so the time
//! sync carries the kernel's timestamp of each sync frame.

use std::time::SystemTime;

use triquint_shared::protocol::Frame;
use triquint_sim::socketcan_port::{SocketCanError, SocketCanPort};

use super::{CanPort, PortError, Received};

/// Opens `iface` for the host (classic CAN, or CAN-FD with `fd`).
pub fn open_host(iface: &str, fd: bool) -> Result<SocketCanPort, SocketCanError> {
    SocketCanPort::open(iface, fd, true, SystemTime::now())
}

impl CanPort for SocketCanPort {
    fn now_us(&mut self) -> u64 {
        self.now_ns() / 1000
    }
    fn send(&mut self, frame: &Frame) -> Result<bool, PortError> {
        SocketCanPort::send(self, frame).map_err(|e| PortError(e.to_string()))
    }
    fn recv(&mut self) -> Result<Option<Received>, PortError> {
        Ok(SocketCanPort::recv(self)
            .map_err(|e| PortError(e.to_string()))?
            .map(|r| Received {
                frame: r.frame,
                t_us: r.t_ns / 1000,
                own: r.own,
            }))
    }
}
