//! The time-sync master: a TimeSync broadcast every `sync_period_us`
//! (every `fast_sync_period_us` until every node reports a valid sync),
//! each carrying the transmit time of the previous one as the kernel (or
//! the bus) confirmed it.

use triquint_shared::protocol::TimeSync;

use super::SessionOptions;
use super::outbox::Outbox;
use crate::Received;

#[derive(Clone, Debug, Default)]
pub(crate) struct TimeSyncMaster {
    seq: u8,
    next_us: u64,
    /// Confirmed transmit time (µs) of the latest sync, sent in the next.
    last_tx_us: u32,
}

impl TimeSyncMaster {
    /// The host's own frame came back: a sync's confirmation gives its time.
    pub fn confirmed(&mut self, rx: &Received) {
        if rx.frame.id == TimeSync::DEF.addr.id(0) {
            self.last_tx_us = rx.t_us as u32;
        }
    }

    /// Queues a sync, ahead of everything else, when one is due.
    pub fn poll(&mut self, now: u64, all_synced: bool, opts: &SessionOptions, out: &mut Outbox) {
        if now < self.next_us {
            return;
        }
        self.seq = self.seq.wrapping_add(1);
        let s = TimeSync {
            seq: self.seq,
            prev_tx_us: self.last_tx_us,
        };
        out.push_front(s.to_frame(0));
        self.next_us = now
            + if all_synced {
                opts.sync_period_us
            } else {
                opts.fast_sync_period_us
            };
    }
}
