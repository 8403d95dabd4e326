//! Receiving segments in both forms: full segments (the anchors of the
//! chain) and compact continuations, rebuilt from the last segment this
//! receiver completed. Drives, simulators and monitors use it alike. No
//! allocation.

use super::compact::{Compact, CompactAssembler, CompactEvent, Held};
use super::segment::{PartEvent, Reassembler, WireSegment};
use super::{MsgKind, Reject};

/// What one segment frame did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SegmentEvent {
    /// Stored; more parts to come.
    Pending,
    /// A whole segment: `crc` is its full body's CRC-32 (what identifies it,
    /// bit for bit); `pred_crc` the CRC of the predecessor it was rebuilt
    /// on, for a continuation (its receiver must hold exactly that one).
    Complete {
        segment: WireSegment,
        crc: u32,
        pred_crc: Option<u32>,
    },
    /// A (partial) segment was dropped; `seq` if known.
    Rejected { seq: Option<u16>, reason: Reject },
    /// The part itself was ignored; the segment continues.
    Ignored(Reject),
}

/// Reassembly of both forms, and the predecessor a continuation is rebuilt on.
#[derive(Clone, Debug, Default)]
pub struct SegmentRx {
    full: Reassembler,
    compact: CompactAssembler,
    /// The last segment completed and its body CRC.
    last: Option<(Held, u32)>,
}

impl SegmentRx {
    /// Drops partial segments and the predecessor (a flushed queue).
    pub fn clear(&mut self) {
        self.full.clear();
        self.compact.clear();
        self.last = None;
    }

    /// Feeds the payload of a frame of `kind`; `None` if it is not a segment frame.
    pub fn push(&mut self, kind: MsgKind, payload: &[u8]) -> Option<SegmentEvent> {
        Some(match kind {
            MsgKind::SegmentPart | MsgKind::SegmentPartFd => {
                match self.full.push(payload, kind == MsgKind::SegmentPartFd) {
                    PartEvent::Pending => SegmentEvent::Pending,
                    PartEvent::Ignored(r) => SegmentEvent::Ignored(r),
                    PartEvent::Rejected { seq, reason } => SegmentEvent::Rejected { seq, reason },
                    PartEvent::Complete(segment) => {
                        let crc = segment.body_crc();
                        self.last = Some((Held::from(segment), crc));
                        SegmentEvent::Complete {
                            segment,
                            crc,
                            pred_crc: None,
                        }
                    }
                }
            }
            MsgKind::SegmentCompact | MsgKind::SegmentCompactFd => {
                match self
                    .compact
                    .push(payload, kind == MsgKind::SegmentCompactFd)
                {
                    CompactEvent::Pending => SegmentEvent::Pending,
                    CompactEvent::Ignored(r) => SegmentEvent::Ignored(r),
                    CompactEvent::Rejected { seq, reason } => {
                        SegmentEvent::Rejected { seq, reason }
                    }
                    CompactEvent::Complete(c) => self.continuation(&c),
                }
            }
            _ => return None,
        })
    }

    fn continuation(&mut self, c: &Compact) -> SegmentEvent {
        // One starting at rest continues nothing: an anchor, as a full one.
        let rebuilt = match &self.last {
            _ if c.is_at_rest() => c.from_rest().map(|s| (s, None)),
            Some((pred, pred_crc)) => c.reconstruct(pred, *pred_crc).map(|s| (s, Some(*pred_crc))),
            None => Err(Reject::NoPredecessor),
        };
        match rebuilt {
            Ok((held, pred_crc)) => {
                let segment = held.segment;
                let crc = segment.body_crc();
                self.last = Some((held, crc));
                SegmentEvent::Complete {
                    segment,
                    crc,
                    pred_crc,
                }
            }
            Err(reason) => SegmentEvent::Rejected {
                seq: Some(c.seq),
                reason,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::compact::DeviationBound;
    use crate::protocol::segment::FLAG_FIRST;
    use crate::quintic::Quintic;

    fn segs() -> [WireSegment; 3] {
        // x(t) = 0.3 + 0.1 t³ on three segments of 0.2 s.
        let at = |t0: f64, seq: u16, flags: u16| {
            let c = [
                0.3 + 0.1 * t0 * t0 * t0,
                0.3 * t0 * t0,
                0.3 * t0,
                0.1,
                0.0,
                0.0,
            ];
            let q = Quintic {
                coeffs: [c; 3],
                duration: 0.2,
            };
            WireSegment::from_quintic(seq, &q, flags).unwrap()
        };
        [at(0.0, 0, FLAG_FIRST), at(0.2, 1, 0), at(0.4, 2, 0)]
    }

    fn feed(
        rx: &mut SegmentRx,
        frames: impl Iterator<Item = crate::protocol::Frame>,
    ) -> SegmentEvent {
        let mut last = SegmentEvent::Pending;
        for f in frames {
            let (msg, _) = crate::protocol::decode(&f).unwrap();
            last = rx.push(msg.kind(), f.payload()).unwrap();
        }
        last
    }

    #[test]
    fn continuations_need_the_predecessor_they_were_built_on() {
        let [a, b, c] = segs();
        let bound = DeviationBound::DEFAULT;
        let (cb, rb) = Compact::continuing(&a.into(), &b, Some(&c), &bound).unwrap();
        let (cc, _) = Compact::continuing(&rb, &c, None, &bound).unwrap();
        let mut rx = SegmentRx::default();
        // Without a predecessor.
        assert_eq!(
            feed(&mut rx, cb.frames(false)),
            SegmentEvent::Rejected {
                seq: Some(1),
                reason: Reject::NoPredecessor
            }
        );
        assert!(matches!(
            feed(&mut rx, a.frames(false)),
            SegmentEvent::Complete { pred_crc: None, .. }
        ));
        // Skipping one: refused.
        assert!(matches!(
            feed(&mut rx, cc.frames(true)),
            SegmentEvent::Rejected {
                reason: Reject::NoPredecessor,
                ..
            }
        ));
        assert_eq!(
            feed(&mut rx, cb.frames(true)),
            SegmentEvent::Complete {
                segment: rb.segment,
                crc: rb.segment.body_crc(),
                pred_crc: Some(a.body_crc())
            }
        );
        assert!(matches!(
            feed(&mut rx, cc.frames(false)),
            SegmentEvent::Complete { .. }
        ));
        // After a clear, nothing to continue.
        rx.clear();
        assert!(matches!(
            feed(&mut rx, cc.frames(false)),
            SegmentEvent::Rejected {
                reason: Reject::NoPredecessor,
                ..
            }
        ));
    }
}
