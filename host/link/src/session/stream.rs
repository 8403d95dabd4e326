//! Flow-controlled streaming: at most `window` segments unacknowledged, and
//! never more than every node's queue takes (its credit); a segment not
//! acknowledged by every node within `retransmit_timeout_us` is sent again
//! (at most `max_retransmits` times), and one a node rejected as corrupt,
//! out of order or incomplete is resent at once without using up a try.
//! A timeout uses up a try only of a segment some node still needs next
//! and did not answer: one queued behind a missing segment cannot be
//! taken, and one a node refused as damaged reached a live node (a
//! reordered or corrupted copy). Those resends are bounded too
//! ([`RESENDS_PER_TRY`] times the tries).
//! Segments go compact when the segment sent just before is their
//! predecessor (`protocol::compact`), in full otherwise; a resend always
//! goes in full (a node may hold another version of its predecessor than
//! the one sent last: a pair resent compact would be refused again), and
//! the segment after it re-anchors the chain; a node that does not hold the
//! predecessor a compact segment was built on answers `NoPredecessor` and
//! gets it in full.

use triquint_shared::protocol::compact::Chain;
use triquint_shared::protocol::{Reject, SegmentAck, WireSegment};

use super::nodes::{AXES, Nodes};
use super::outbox::Outbox;
use super::{SessionOptions, UploadError};
use crate::Drive;

/// A segment is resent on a rejection only if its last transmission is older
/// than this: a full window of classic segments takes about 11 ms on the wire.
const RESEND_GUARD_US: u64 = 15_000;

/// The transmit queue is not filled beyond this many frames.
const OUTBOX_LIMIT: usize = 64;

/// Transmissions of one segment that use up no try, per try allowed: a
/// node that refuses every copy still ends the upload.
pub(crate) const RESENDS_PER_TRY: u32 = 4;

/// A segment sent and not yet acknowledged by every node.
#[derive(Clone, Debug)]
struct InFlight {
    seq: usize,
    sent_at: u64,
    tries: u32,
    /// Transmissions, tried or not.
    sends: u32,
    acked: [bool; AXES],
    /// Resend requested by a rejection (not counted as a try).
    early: bool,
    /// A node refused this segment as damaged since it was last sent.
    refused: bool,
}

#[derive(Clone, Debug)]
pub(crate) struct Stream {
    pub segments: Vec<WireSegment>,
    fd: bool,
    compact: bool,
    next_to_send: usize,
    in_flight: Vec<InFlight>,
    /// How segments go on the bus (full or compact).
    chain: Chain,
    /// Every version of a segment sent: (sequence number, body CRC of the
    /// segment receivers hold once they take it in).
    pub versions: Vec<(u16, u32)>,
    /// Segment frames queued, segments sent (compact of them), retransmissions, rejections seen.
    pub segment_frames: u64,
    pub segments_sent: u64,
    pub compact_sent: u64,
    pub retransmits: u64,
    pub rejects_seen: u64,
}

impl Stream {
    pub fn new(segments: Vec<WireSegment>, fd: bool, compact: bool) -> Self {
        Self {
            segments,
            fd,
            compact,
            next_to_send: 0,
            in_flight: Vec::new(),
            chain: Chain::default(),
            versions: Vec::new(),
            segment_frames: 0,
            segments_sent: 0,
            compact_sent: 0,
            retransmits: 0,
            rejects_seen: 0,
        }
    }

    /// Plan duration (µs).
    pub fn plan_end_us(&self) -> u64 {
        self.segments.iter().map(|s| s.duration_us as u64).sum()
    }

    /// Segments every node has acknowledged.
    pub fn acked(&self) -> usize {
        self.next_to_send.saturating_sub(self.in_flight.len())
    }

    /// Every node acknowledged segments `0..n`.
    pub fn all_acked_through(&self, n: usize) -> bool {
        self.next_to_send >= n && self.in_flight.iter().all(|f| f.seq >= n)
    }

    /// A SegmentAck from node index `i` (its view already updated), received at `t_us`.
    pub fn acknowledged(
        &mut self,
        i: usize,
        node: Drive,
        a: &SegmentAck,
        t_us: u64,
    ) -> Result<(), UploadError> {
        match Reject::from_u8(a.result) {
            Some(Reject::Accepted) | Some(Reject::Duplicate) => {
                if let Some(f) = self.in_flight.iter_mut().find(|f| f.seq == a.seq as usize) {
                    f.acked[i] = true;
                }
            }
            Some(
                Reject::BadCrc | Reject::OutOfOrder | Reject::Incomplete | Reject::NoPredecessor,
            ) => {
                self.rejects_seen += 1;
                if let Some(f) = self.in_flight.iter_mut().find(|f| f.seq == a.seq as usize) {
                    f.refused = true;
                }
                // Resend at once the segment this node needs next (the
                // rejected one may only be queued behind a lost one),
                // unless it went out moments ago and may be on its way.
                // A resend on a rejection is not a timeout: it does not
                // use up the segment's tries.
                let need = a.next_seq as usize;
                if let Some(f) = self.in_flight.iter_mut().find(|f| f.seq == need)
                    && !f.acked[i]
                    && t_us.saturating_sub(f.sent_at) > RESEND_GUARD_US
                {
                    f.sent_at = 0;
                    f.early = true;
                }
            }
            Some(Reject::QueueFull) => {
                self.rejects_seen += 1;
            }
            other => {
                return Err(UploadError::Rejected {
                    node,
                    seq: a.seq,
                    reason: other,
                });
            }
        }
        Ok(())
    }

    /// Queues segment `seq`: a resend always in full (a node may hold
    /// another version of its predecessor than the one sent before it).
    fn queue(&mut self, seq: usize, resend: bool, out: &mut Outbox) {
        if let Some(s) = self.segments.get(seq) {
            let sent = if self.compact && !resend {
                self.chain.next(s, self.segments.get(seq + 1))
            } else {
                self.chain.full(s)
            };
            for f in sent.frames(self.fd) {
                out.push_back(f);
                self.segment_frames += 1;
            }
            self.segments_sent += 1;
            self.compact_sent += sent.is_compact() as u64;
            let v = (s.seq, sent.held().body_crc());
            if !self.versions.contains(&v) {
                self.versions.push(v);
            }
        }
    }

    /// Retransmits what timed out, then sends what the window and every
    /// node's credit allow (up to `stall_after` segments).
    pub fn poll(
        &mut self,
        now: u64,
        nodes: &Nodes,
        opts: &SessionOptions,
        out: &mut Outbox,
    ) -> Result<(), UploadError> {
        self.in_flight.retain(|f| !f.acked.iter().all(|a| *a));
        for k in 0..self.in_flight.len() {
            let f = &self.in_flight[k];
            if now.saturating_sub(f.sent_at) > opts.retransmit_timeout_us
                && out.len() < OUTBOX_LIMIT
            {
                // A node that needs this segment next and did not refuse
                // it: the copy was lost (or the node is gone).
                let lost = (0..AXES).any(|i| !f.acked[i] && nodes.0[i].next_seq == f.seq as u16)
                    && !f.refused;
                let tries = f.tries + u32::from(lost && !f.early);
                if tries > opts.max_retransmits
                    || f.sends > RESENDS_PER_TRY * (opts.max_retransmits + 1)
                {
                    let node = nodes.drive((0..AXES).find(|&i| !f.acked[i]).unwrap_or(0));
                    return Err(UploadError::Retransmits {
                        node,
                        seq: f.seq,
                        tries: f.sends,
                    });
                }
                let seq = f.seq;
                let f = &mut self.in_flight[k];
                f.tries = tries;
                f.sends += 1;
                f.early = false;
                f.refused = false;
                f.sent_at = now;
                self.retransmits += 1;
                self.queue(seq, true, out);
            }
        }
        let limit = opts
            .stall_after
            .unwrap_or(usize::MAX)
            .min(self.segments.len());
        while self.next_to_send < limit
            && self.in_flight.len() < opts.window
            && self.next_to_send < nodes.credit()
            && out.len() < OUTBOX_LIMIT
        {
            let seq = self.next_to_send;
            self.queue(seq, false, out);
            self.in_flight.push(InFlight {
                seq,
                sent_at: now,
                tries: 1,
                sends: 1,
                acked: [false; AXES],
                early: false,
                refused: false,
            });
            self.next_to_send += 1;
        }
        Ok(())
    }
}
