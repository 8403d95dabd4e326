//! The largest of the queued segments' own stop ramps, kept so that a
//! segment leaving costs the tick a bounded few comparisons however deep
//! the queue: each segment has a slot (its sequence number modulo the
//! capacity), the slots form blocks of [`BLOCK`], and the drive keeps each
//! block's largest and the largest of the blocks. A segment leaving
//! re-reads its own block's segments and the blocks, never the whole queue.
//! A dated stop's check of the queue skips a block none of whose segments
//! has an own ramp above the one carried.

use super::Drive;
use crate::segment::Seg;

/// A block's largest own ramps: whole segments' (µs, controlled and
/// quick) and for stops from σ ≤ 1 (100 µs units, `UnitRamps::largest`).
#[derive(Clone, Copy, Default)]
pub(super) struct BlockRamps {
    us: (u32, u32),
    units: [u16; 2],
}

/// Slots per block.
const BLOCK: usize = 4;
/// Blocks at most: a queue of up to 16 segments.
pub(super) const MAX_BLOCKS: usize = 4;

/// A queue slot's block. The mask keeps the index provably in range (no
/// bounds check, so no panic path, in the tick).
fn block<const Q: usize>(seq: u16) -> usize {
    ((seq as usize & (Q - 1)) / BLOCK) & (MAX_BLOCKS - 1)
}

/// `m` raised to `r`, controlled and quick. Plain comparisons: `max` is a
/// call out of the tick's memory.
fn raise(m: &mut (u32, u32), r: (u32, u32)) {
    if r.0 > m.0 {
        m.0 = r.0;
    }
    if r.1 > m.1 {
        m.1 = r.1;
    }
}

/// The queued segment at index `i` (0 the front) of a queue whose ring
/// halves are `head` and `tail` (`Deque::as_slices`).
pub(super) fn queued<'a>((head, tail): (&'a [Seg], &'a [Seg]), i: usize) -> Option<&'a Seg> {
    match i.checked_sub(head.len()) {
        None => head.get(i),
        Some(j) => tail.get(j),
    }
}

/// `b` raised to segment `s`'s own ramps.
fn raise_block(b: &mut BlockRamps, s: &Seg) {
    raise(&mut b.us, s.ramps_us);
    let u = s.unit_ramps.largest;
    if u[0] > b.units[0] {
        b.units[0] = u[0];
    }
    if u[1] > b.units[1] {
        b.units[1] = u[1];
    }
}

impl<const Q: usize> Drive<Q> {
    /// Slots from sequence numbers: the capacity divides 2^16 (so slots
    /// survive the sequence number's wrap) and fills whole blocks.
    const SLOTS_FIT: () = assert!(
        Q.is_power_of_two() && Q >= BLOCK && Q / BLOCK <= MAX_BLOCKS,
        "queue capacity: a power of two from 4 to 16"
    );

    /// Segment `s` joined the back of the queue.
    pub(super) fn ramps_joined(&mut self, s: &Seg) {
        let () = Self::SLOTS_FIT;
        raise_block(&mut self.block_ramps[block::<Q>(s.seq)], s);
        raise(&mut self.queue_ramps_us, s.ramps_us);
    }

    /// Segment `seq` with own ramps `r` and `units` left the front of the
    /// queue: its block again from the segments queued in it, then the
    /// largest of the blocks (only when it was one of its block's largest).
    pub(super) fn ramps_left(&mut self, seq: u16, r: (u32, u32), units: [u16; 2]) {
        let b = block::<Q>(seq);
        let had = self.block_ramps[b];
        if r.0 < had.us.0 && r.1 < had.us.1 && units[0] < had.units[0] && units[1] < had.units[1] {
            return;
        }
        self.reread_block(b);
    }

    /// The largest own ramp for a stop from σ ≤ 1 (`k`: 0 controlled, 1
    /// quick) of the queued segments in segment `seq`'s block.
    pub(super) fn block_largest(&self, seq: u16, k: usize) -> u16 {
        self.block_ramps[block::<Q>(seq)].units[k & 1]
    }

    /// For a scan that needs only the segments whose own ramp for a stop
    /// from σ ≤ 1 (`k`: 0 controlled, 1 quick) is above `floor`: how many
    /// it may skip from segment `seq` on (the rest of its block), if none
    /// in its block is.
    pub(super) fn block_at_most(&self, seq: u16, k: usize, floor: u16) -> Option<usize> {
        (self.block_largest(seq, k) <= floor).then_some(BLOCK - seq as usize % BLOCK)
    }

    // Cold, out of line: once a segment at most.
    #[cold]
    #[inline(never)]
    fn reread_block(&mut self, b: usize) {
        let mut m = BlockRamps::default();
        if let Some(front) = self.queue.front() {
            let f = front.seq as usize;
            let halves = self.queue.as_slices();
            for k in 0..BLOCK {
                // The queue index of the segment in slot b·BLOCK + k, if any.
                if let Some(s) = queued(halves, (b * BLOCK + k).wrapping_sub(f) & (Q - 1)) {
                    raise_block(&mut m, s);
                }
            }
        }
        self.block_ramps[b] = m;
        let mut all = (0, 0);
        for x in &self.block_ramps {
            raise(&mut all, x.us);
        }
        self.queue_ramps_us = all;
    }

    /// The queue was emptied.
    pub(super) fn ramps_cleared(&mut self) {
        self.queue_ramps_us = (0, 0);
        self.block_ramps = [BlockRamps::default(); MAX_BLOCKS];
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drive::QUEUE_CAPACITY;
    use crate::segment::UnitRamps;
    use triquint_shared::protocol::segment_maxima::PIECES;

    fn seg(seq: u16, x: u32) -> Seg {
        // Ramps that differ between the four kinds, with ties.
        let (a, b) = ((x % 7) * 1000, (x % 5) * 700);
        Seg {
            seq,
            start_ns: 0,
            duration_us: 1,
            inv_h: 1.0,
            b: [[0.0; 6]; 3],
            first: false,
            last: false,
            crc: 0,
            ramps_us: (a, b),
            unit_ramps: UnitRamps {
                pieces: [0; PIECES],
                largest: [(x % 11) as u16, (x % 3) as u16],
            },
        }
    }

    /// After every push and pop, across the sequence number's wrap: the
    /// queue's largest is the brute-force one, every block holds exactly
    /// its queued segments' largest, and a block is skipped for a floor
    /// only if none of its segments is above it.
    #[test]
    fn blocks_hold_exactly_their_queued_segments_largest() {
        let mut d: Drive = Drive::new(1);
        let mut seq: u16 = 65_500;
        let mut x: u32 = 12_345;
        for step in 0..4_000 {
            x = x.wrapping_mul(1_103_515_245).wrapping_add(12_345) >> 1;
            let push = d.queue.is_empty() || (!d.queue.is_full() && x % 3 != 0);
            if push {
                let s = seg(seq, x >> 8);
                d.queue.push_back(s).unwrap();
                d.ramps_joined(&s);
                seq = seq.wrapping_add(1);
            } else {
                let f = d.queue.pop_front().unwrap();
                d.ramps_left(f.seq, f.ramps_us, f.unit_ramps.largest);
            }
            if step % 500 == 499 {
                d.queue.clear();
                d.ramps_cleared();
            }
            let mut all = (0, 0);
            for s in d.queue.iter() {
                all = (all.0.max(s.ramps_us.0), all.1.max(s.ramps_us.1));
            }
            assert_eq!(d.queue_ramps_us, all, "step {step}");
            for b in 0..MAX_BLOCKS {
                let mut m = BlockRamps::default();
                for s in d
                    .queue
                    .iter()
                    .filter(|s| block::<QUEUE_CAPACITY>(s.seq) == b)
                {
                    raise_block(&mut m, s);
                }
                let got = d.block_ramps[b];
                assert_eq!(
                    (got.us, got.units),
                    (m.us, m.units),
                    "step {step}, block {b}"
                );
            }
            let halves = d.queue.as_slices();
            for (i, s) in d.queue.iter().enumerate() {
                assert_eq!(queued(halves, i).map(|q| q.seq), Some(s.seq));
                for k in 0..2 {
                    for floor in 0..12 {
                        if let Some(n) = d.block_at_most(s.seq, k, floor) {
                            for t in d.queue.iter().skip(i).take(n) {
                                assert!(t.unit_ramps.largest[k] <= floor, "step {step}");
                                assert_eq!(
                                    block::<QUEUE_CAPACITY>(t.seq),
                                    block::<QUEUE_CAPACITY>(s.seq)
                                );
                            }
                        }
                    }
                }
            }
            assert!(queued(halves, d.queue.len()).is_none());
        }
    }
}
