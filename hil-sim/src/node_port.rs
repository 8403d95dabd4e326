//! A virtual drive's view of a SocketCAN bus: the firmware's `CanBus` over
//! the shared socket of `triquint-link` ([`SocketCanPort`]), with the
//! frames received this pass timestamped on the drive's own clock.

use triquint_firmware::{CanBus, RxFrame};
use triquint_link::socketcan::{SocketCanError, SocketCanPort, SocketRx};
use triquint_shared::protocol::{Frame, TimeSync};

use crate::sim::LocalClock;

/// The firmware's view of the bus for one drive: the frames received this
/// pass (timestamps on the drive's own offset, drifting clock) and the shared
/// socket for transmission, so `firmware::hal::service` runs unchanged.
pub struct NodePort<'a> {
    pub port: &'a mut SocketCanPort,
    pub rx: &'a [SocketRx],
    pub next: usize,
    pub clock: LocalClock,
    /// True time (ns) of the tick this pass runs.
    pub tick_ns: u64,
    /// The first transport error, kept for the caller (the firmware's
    /// `CanBus` has no error path: a real controller just stops).
    pub error: Option<SocketCanError>,
}

impl CanBus for NodePort<'_> {
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
            timestamp_us: self
                .clock
                .local_us(stamp_ns(&r.frame, r.t_ns, self.tick_ns)),
        })
    }
}

/// The receive time a drive sees for a frame that arrived at `t_ns`, handed
/// over by the tick at `tick_ns`. A late tick (the catch-up after a stall)
/// takes frames that arrived after its own time, which never happens on a
/// board: a command applied "on receipt" would date its σ transition in the
/// drive's future and the reference would jump ahead by the lag (≈ 100 mm
/// at 0.3 m/s and a 300 ms lag). Such frames are stamped at the tick, as a
/// drive keeping up would have had them by then; a TimeSync keeps its true
/// time, which the time base is estimated from.
pub(crate) fn stamp_ns(frame: &Frame, t_ns: u64, tick_ns: u64) -> u64 {
    if frame.id == TimeSync::DEF.addr.id(0) {
        t_ns
    } else {
        t_ns.min(tick_ns)
    }
}

#[cfg(test)]
mod tests {
    use super::stamp_ns;
    use triquint_shared::protocol::{Frame, TimeSync};

    #[test]
    fn a_late_tick_stamps_frames_at_its_own_time_but_time_syncs_at_theirs() {
        let command = Frame::with_payload(0x030, &[0; 8], false);
        let sync = TimeSync {
            seq: 1,
            prev_tx_us: 0,
        }
        .to_frame(0);
        // Arrived 300 ms after the tick that hands it over.
        assert_eq!(
            stamp_ns(&command, 1_300_000_000, 1_000_000_000),
            1_000_000_000
        );
        assert_eq!(stamp_ns(&sync, 1_300_000_000, 1_000_000_000), 1_300_000_000);
        // Arrived before its tick: its own time.
        assert_eq!(stamp_ns(&command, 900_000_000, 1_000_000_000), 900_000_000);
    }
}
