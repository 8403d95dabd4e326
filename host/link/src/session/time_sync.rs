//! The time-sync master: a TimeSync broadcast every `sync_period_us`
//! (every `fast_sync_period_us` until every node reports a valid sync),
//! each carrying the transmit time of the previous one as the kernel (or
//! the bus) confirmed it. A node's sync status counts only from a heartbeat
//! after [`SYNCS_TO_FOLLOW`] syncs went out since the session's Reset: before,
//! it may be of the time base of an earlier session (another process,
//! another clock), which an idle node follows only after outliers.

use triquint_shared::protocol::{SYNCS_TO_FOLLOW, TimeSync};

use super::SessionOptions;
use super::outbox::Outbox;
use crate::Received;

#[derive(Clone, Debug, Default)]
pub(crate) struct TimeSyncMaster {
    seq: u8,
    next_us: u64,
    /// Confirmed transmit time (µs) of the latest sync, sent in the next.
    last_tx_us: u32,
    /// Syncs confirmed, up to [`SYNCS_TO_FOLLOW`].
    confirmed: u32,
    /// When the [`SYNCS_TO_FOLLOW`]th was confirmed (host µs).
    followable_from_us: Option<u64>,
}

impl TimeSyncMaster {
    /// The host's own frame came back: a sync's confirmation gives its time.
    pub fn confirmed(&mut self, rx: &Received) {
        if rx.frame.id == TimeSync::DEF.addr.id(0) {
            self.last_tx_us = rx.t_us as u32;
            if self.confirmed < SYNCS_TO_FOLLOW {
                self.confirmed += 1;
                if self.confirmed == SYNCS_TO_FOLLOW {
                    self.followable_from_us = Some(rx.t_us);
                }
            }
        }
    }

    /// Counts the syncs to follow again: a node with motion loaded (by a
    /// session that ended before Arm) keeps its time base until the Reset
    /// this session sends it.
    pub fn follow_from_now(&mut self) {
        self.confirmed = 0;
        self.followable_from_us = None;
    }

    /// Whether a heartbeat received at host time `t_us` reports a node's
    /// sync to this session's time base (see the module's text).
    pub fn of_this_session(&self, t_us: u64) -> bool {
        self.followable_from_us.is_some_and(|f| t_us > f)
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
