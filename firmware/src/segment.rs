//! Queued segments in drive precision (f32, normalised time) and their evaluation.

use nalgebra::Vector3;

use crate::f32_cast::to_f32;
use triquint_shared::protocol::WireSegment;
use triquint_shared::protocol::segment::{FLAG_FIRST, FLAG_LAST};
use triquint_shared::protocol::segment_maxima::{PIECES, inv_h};
use triquint_shared::quintic::{JointMotion, eval_poly};

/// One queued segment.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Seg {
    pub seq: u16,
    /// Plan time at the segment start (ns).
    pub start_ns: i64,
    /// Duration h (µs): 120 bytes a queue slot, not 136 with h in ns and
    /// 1/h² and 1/h³ stored.
    pub duration_us: u32,
    /// 1/h (s⁻¹).
    pub inv_h: f32,
    /// Normalised coefficients b_jk (m).
    pub b: [[f32; 6]; 3],
    pub first: bool,
    pub last: bool,
    /// CRC-32 of the received body: which segment, bit for bit, this is.
    pub crc: u32,
    /// The drive's own stop ramps for it, controlled and quick (µs;
    /// `Maxima::ramps_us`, set on the receive side).
    pub ramps_us: (u32, u32),
    /// Its own ramps for a stop from σ ≤ 1 (`Maxima::ramps_and_units`):
    /// what a stop carrying a ramp for the path ahead is held to where it
    /// passes each piece.
    pub unit_ramps: UnitRamps,
}

/// A segment's own ramps for a stop along the path from σ ≤ 1 (100 µs
/// units, rounded up; `u16::MAX`: none keeps it within the ceilings).
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct UnitRamps {
    /// Each piece's, controlled, in plan order.
    pub pieces: [u16; PIECES],
    /// The largest over its pieces: controlled, quick (a quick stop is held
    /// to the whole segment's).
    pub largest: [u16; 2],
}

impl Seg {
    pub fn from_wire(w: &WireSegment, start_ns: i64) -> Self {
        Self {
            seq: w.seq,
            start_ns,
            duration_us: w.duration_us,
            inv_h: inv_h(w.duration_us),
            b: w.normalised_f32(),
            first: w.flags & FLAG_FIRST != 0,
            last: w.flags & FLAG_LAST != 0,
            crc: w.body_crc(),
            ramps_us: (0, 0),
            unit_ramps: UnitRamps::default(),
        }
    }

    pub fn duration_ns(&self) -> i64 {
        self.duration_us as i64 * 1000
    }

    pub fn end_ns(&self) -> i64 {
        self.start_ns + self.duration_ns()
    }

    /// Positions at the start (τ = 0).
    pub fn start_q(&self) -> Vector3<f32> {
        Vector3::new(self.b[0][0], self.b[1][0], self.b[2][0])
    }

    /// Positions at the end (τ = 1).
    pub fn end_q(&self) -> Vector3<f32> {
        Vector3::from_fn(|j, _| self.b[j].iter().sum())
    }

    /// The three joints' positions at u = t/h (u in [0, 1]).
    pub fn positions(&self, u: f32) -> [f32; 3] {
        self.b
            .map(|b| b.iter().rev().fold(0.0, |acc, c| acc * u + c))
    }

    /// q, q', q'', q''' (derivatives with respect to plan time) at plan time `s_ns`,
    /// clamped into the segment.
    pub fn eval(&self, s_ns: i64) -> JointMotion<f32> {
        // max/min, not clamp: clamp has a panic path (min > max).
        let dur = self.duration_ns();
        let d = (s_ns - self.start_ns).max(0).min(dur);
        let tau = if dur > 0 {
            to_f32(d) / to_f32(dur)
        } else {
            0.0
        };
        let ih = self.inv_h;
        let inv_h = [ih, ih * ih, ih * ih * ih];
        let mut m = JointMotion::default();
        for j in 0..3 {
            let [p, v, a, jk] = eval_poly(&self.b[j], tau);
            m.q[j] = p;
            m.qd[j] = v * inv_h[0];
            m.qdd[j] = a * inv_h[1];
            m.qddd[j] = jk * inv_h[2];
        }
        m
    }
}

/// Applies a time-scaling σ to path derivatives: q̇ = q'σ, q̈ = q''σ² + q'σ̇,
/// jerk = q'''σ³ + 3q''σσ̇ + q'σ̈.
pub fn scale(m: &JointMotion<f32>, sigma: f32, sigma_d: f32, sigma_dd: f32) -> JointMotion<f32> {
    JointMotion {
        q: m.q,
        qd: m.qd * sigma,
        qdd: m.qdd * (sigma * sigma) + m.qd * sigma_d,
        qddd: m.qddd * (sigma * sigma * sigma) + m.qdd * (3.0 * sigma * sigma_d) + m.qd * sigma_dd,
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn a_queue_slot_is_120_bytes() {
        assert_eq!(core::mem::size_of::<super::Seg>(), 120);
    }
}
