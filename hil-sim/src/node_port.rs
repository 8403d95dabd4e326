//! A virtual drive's view of a SocketCAN bus: the firmware's `CanPort` over
//! the shared socket of `triquint-link` ([`SocketCanPort`]), with the
//! frames received this pass timestamped on the drive's own clock.

use triquint_firmware::{CanPort, RxFrame};
use triquint_link::socketcan::{SocketCanError, SocketCanPort, SocketRx};
use triquint_shared::protocol::Frame;

use crate::sim::LocalClock;

/// The firmware's view of the bus for one drive: the frames received this
/// pass (timestamps on the drive's own offset, drifting clock) and the shared
/// socket for transmission, so `firmware::hal::service` runs unchanged.
pub struct NodePort<'a> {
    pub port: &'a mut SocketCanPort,
    pub rx: &'a [SocketRx],
    pub next: usize,
    pub clock: LocalClock,
    /// The first transport error, kept for the caller (the firmware's
    /// `CanPort` has no error path: a real controller just stops).
    pub error: Option<SocketCanError>,
}

impl CanPort for NodePort<'_> {
    fn transmit(&mut self, frame: &Frame) -> bool {
        match self.port.send(frame) {
            Ok(sent) => sent,
            Err(e) => {
                self.error.get_or_insert(e);
                false
            }
        }
    }
    fn receive(&mut self) -> Option<RxFrame> {
        let r = self.rx.get(self.next)?;
        self.next += 1;
        Some(RxFrame {
            frame: r.frame,
            timestamp_us: self.clock.local_us(r.t_ns),
        })
    }
}
