//! The bus's host time, learnt by a process that is not the time-sync
//! master (`triquint hold` while `triquint upload` runs): each TimeSync
//! carries the host time the previous one was sent at, so pairing it with
//! this process's receive time of that previous sync gives the offset from
//! this process's clock to the host time the drives follow.

use triquint_shared::protocol::{Msg, decode};

use crate::Received;

/// Host time from the TimeSync frames on the bus.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HostClock {
    /// The latest sync: its sequence number and our receive time (µs).
    last: Option<(u8, u64)>,
    /// Host time minus our time (µs, wrapping 32-bit like the wire).
    offset: Option<u32>,
}

impl HostClock {
    /// Takes in a received frame (only another station's TimeSync counts).
    pub fn take(&mut self, rx: &Received) {
        if rx.own {
            return;
        }
        let Ok((Msg::TimeSync(s), _)) = decode(&rx.frame) else {
            return;
        };
        if let Some((seq, at)) = self.last
            && s.seq == seq.wrapping_add(1)
            && s.prev_tx_us != 0
        {
            self.offset = Some(s.prev_tx_us.wrapping_sub(at as u32));
        }
        self.last = Some((s.seq, rx.t_us));
    }

    /// Whether the host time is known (two consecutive syncs seen).
    pub fn known(&self) -> bool {
        self.offset.is_some()
    }

    /// Host time (µs, wrapping as on the wire) at our time `local_us`.
    pub fn host_us(&self, local_us: u64) -> Option<u32> {
        self.offset.map(|o| (local_us as u32).wrapping_add(o))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use triquint_shared::protocol::TimeSync;

    fn sync(seq: u8, prev_tx_us: u32, t_us: u64) -> Received {
        Received {
            frame: TimeSync { seq, prev_tx_us }.to_frame(0),
            t_us,
            own: false,
        }
    }

    #[test]
    fn two_consecutive_syncs_give_the_host_time() {
        let mut c = HostClock::default();
        // The master's clock reads 5_000_000 µs more than ours.
        c.take(&sync(7, 0, 1_000));
        assert!(!c.known());
        c.take(&sync(8, 5_001_000, 101_000));
        assert_eq!(c.host_us(150_000), Some(5_150_000));
        // A gap in the sequence (a lost sync) does not pair wrong syncs.
        let mut c = HostClock::default();
        c.take(&sync(1, 0, 1_000));
        c.take(&sync(3, 9, 201_000));
        assert!(!c.known());
        // Wrapping: the host time near 2³².
        c.take(&sync(4, u32::MAX - 10, 301_000));
        assert_eq!(c.host_us(201_020), Some(9));
    }
}
