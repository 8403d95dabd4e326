//! Filing a checked segment: the cheap, state-dependent checks (state,
//! sequence, queue room, the predecessor a compact segment was rebuilt on,
//! C3 continuity with the previous segment), its place
//! in plan time, and the SegmentAck that answers it.

use triquint_shared::protocol::contract::{
    MAX_DURATION_US, MAX_POSITION_JUMP_M, RELATIVE_LIMIT_MARGIN,
};
use triquint_shared::protocol::{DriveConfig, Reject, SegmentAck, State};
use triquint_shared::quintic::JointMotion;

use super::Drive;
use crate::inbox::CheckedSegment;

/// The new segment starts where the previous one ended, in position (within
/// [`MAX_POSITION_JUMP_M`]) and in velocity, acceleration and jerk (within
/// [`RELATIVE_LIMIT_MARGIN`] of the limits): C3 continuity.
fn c3_continuous(prev: &JointMotion<f32>, next: &JointMotion<f32>, cfg: &DriveConfig) -> bool {
    (prev.q - next.q).amax() <= MAX_POSITION_JUMP_M
        && (prev.qd - next.qd).amax() <= RELATIVE_LIMIT_MARGIN * cfg.max_velocity
        && (prev.qdd - next.qdd).amax() <= RELATIVE_LIMIT_MARGIN * cfg.max_acceleration
        && (prev.qddd - next.qddd).amax() <= RELATIVE_LIMIT_MARGIN * cfg.max_jerk
}

fn seq_diff(a: u16, b: u16) -> i16 {
    a.wrapping_sub(b) as i16
}

impl<const Q: usize> Drive<Q> {
    pub(super) fn count_reject(&mut self, r: Reject) -> u8 {
        self.stats.rejects = self.stats.rejects.saturating_add(1);
        self.stats.last_reject = r as u8;
        let slot = self.stats.reason_counts.get_mut(r as usize);
        match slot {
            Some(c) => {
                *c = c.saturating_add(1);
                *c
            }
            None => 0,
        }
    }

    pub(super) fn ack(&mut self, seq: u16, result: Reject, reason_count: u8) {
        let a = SegmentAck {
            seq,
            result: result as u8,
            depth: self.queue.len() as u8,
            next_seq: self.next_seq,
            capacity: Q as u8,
            reason_count,
        };
        let f = a.to_frame(self.node_id);
        self.send(f);
    }

    /// Files a checked segment: the cheap, state-dependent checks (state,
    /// sequence, queue room, C3 continuity with the previous segment) and
    /// its place in plan time. The receive side did the expensive ones.
    // Out of line: once a segment, and the tick's own code must fit the
    // ESC1's CCM SRAM.
    #[inline(never)]
    pub(super) fn accept(&mut self, c: &CheckedSegment) -> Result<(), Reject> {
        if !self.homed {
            return Err(Reject::NotHomed);
        }
        if !matches!(
            self.state,
            State::Idle | State::Loaded | State::Armed | State::Running
        ) || self.active.is_none()
        {
            return Err(Reject::WrongState);
        }
        let seg = &c.seg;
        let d = seq_diff(seg.seq, self.next_seq);
        if d < 0 {
            return Err(Reject::Duplicate);
        }
        if d > 0 {
            return Err(Reject::OutOfOrder);
        }
        let max_ns = MAX_DURATION_US as i64 * 1000;
        if seg.duration_ns() == 0 || seg.duration_ns() > max_ns || seg.first != (seg.seq == 0) {
            return Err(Reject::Invalid);
        }
        if self.queue.is_full() {
            return Err(Reject::QueueFull);
        }
        // Checked against another configuration (a commit in between).
        if c.config_crc != self.config_crc() {
            return Err(Reject::WrongState);
        }
        c.verdict?;
        // A continuation was rebuilt on a predecessor: it must be the one
        // this node accepted last, bit for bit.
        if let Some(p) = c.pred_crc
            && (self.prev_end.is_none() || self.prev_crc != p)
        {
            return Err(Reject::NoPredecessor);
        }
        if let Some(prev) = self.prev_end
            && !seg.first
            && !c3_continuous(&prev, &c.begin, &self.cfg)
        {
            return Err(Reject::Discontinuous);
        }
        let start_ns = if seg.first { 0 } else { self.queued_end_ns };
        if self.queue.push_back(*seg).is_err() {
            return Err(Reject::QueueFull);
        }
        if let Some(s) = self.queue.back_mut() {
            s.start_ns = start_ns;
            self.queued_end_ns = s.end_ns();
        }
        self.ramps_joined(seg);
        self.prev_end = Some(c.end);
        self.prev_crc = seg.crc;
        self.next_seq = self.next_seq.wrapping_add(1);
        if self.state == State::Idle {
            self.state = State::Loaded;
        }
        Ok(())
    }
}
