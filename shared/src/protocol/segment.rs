//! Segments on the wire: one quintic segment of all three axes, split into
//! parts and reassembled.
//!
//! The segment body is 20 six-byte words (120 bytes):
//! - word 0: `seq` u16, `duration_us` u32;
//! - words 1–18: coefficient k of axis j at word 1 + 6j + k, an i48 in units
//!   of 2⁻⁴⁰ m. Coefficients are in *normalised* time τ = t/h ∈ [0, 1]:
//!   q_j(τ) = Σ_k b_jk τ^k with b_jk = c_jk h^k, so every value is a length
//!   (m), f32 evaluation never sees a large time, and 2⁻⁴⁰ m ≈ 1 pm resolution
//!   over ±128 m;
//! - word 19: `flags` u16 (bit 0 first segment of the plan, bit 1 last), then
//!   `crc` u32: CRC-32 of body bytes 0–115.
//!
//! A part frame carries byte 0 = part index (the DBC multiplexor), byte 1 =
//! low byte of `seq`, then whole words: one word per classic 8-byte frame
//! (20 parts), ten words per 64-byte CAN-FD frame (2 parts). A segment is
//! accepted only when all parts arrived in order and the CRC matches.

use super::Frame;
use super::crc::crc32;
use super::messages::Reject;
use super::wire::{Addr, FieldDef, I48_MAX, MessageDef, WireType, get_i48, put_i48, spec_text};
use crate::quintic::Quintic;

pub const WORD_LEN: usize = 6;
pub const BODY_WORDS: usize = 20;
pub const BODY_LEN: usize = WORD_LEN * BODY_WORDS;
/// Offset of the CRC in the body; it covers bytes 0..CRC_OFFSET.
pub const CRC_OFFSET: usize = BODY_LEN - 4;
/// Coefficient unit (m): 2⁻⁴⁰.
pub const COEFF_SCALE: f64 = 1.0 / 1_099_511_627_776.0;
/// Flag: the first segment of a plan (plan time restarts at 0).
pub const FLAG_FIRST: u16 = 1;
/// Flag: the last segment of a plan (no underrun at its end).
pub const FLAG_LAST: u16 = 2;
/// Longest segment accepted (µs).
pub const MAX_DURATION_US: u32 = 60_000_000;

/// Words per part frame.
pub const fn words_per_part(fd: bool) -> usize {
    if fd { 10 } else { 1 }
}
/// Part frames per segment: 20 classic, 2 CAN-FD.
pub const fn parts_per_segment(fd: bool) -> usize {
    BODY_WORDS / words_per_part(fd)
}
/// Payload length of a part frame.
pub const fn part_len(fd: bool) -> usize {
    if fd { 64 } else { 8 }
}

/// Classic segment part (DLC 8).
pub const SEGMENT_PART: MessageDef = MessageDef {
    name: "SegmentPart",
    addr: Addr::Broadcast(0x100),
    len: 8,
    sender: "host",
    period: "streamed",
    doc: spec_text!(" One word of a segment body; 20 parts per segment."),
    mux: Some("part"),
    fd: false,
    fields: &PART_FIELDS,
};

/// CAN-FD segment part (64 bytes).
pub const SEGMENT_PART_FD: MessageDef = MessageDef {
    name: "SegmentPartFd",
    addr: Addr::Broadcast(0x110),
    len: 64,
    sender: "host",
    period: "streamed",
    doc: spec_text!(" Ten words of a segment body; 2 parts per segment (CAN-FD, BRS)."),
    mux: Some("part"),
    fd: true,
    fields: &PART_FIELDS,
};

const PART_FIELDS: [FieldDef; 2] = [
    FieldDef {
        name: "part",
        offset: 0,
        ty: WireType::U8,
        scale: 1.0,
        unit: "",
        doc: spec_text!(" Part index (multiplexor)."),
        values: None,
    },
    FieldDef {
        name: "seq8",
        offset: 1,
        ty: WireType::U8,
        scale: 1.0,
        unit: "",
        doc: spec_text!(" Low byte of the segment sequence number."),
        values: None,
    },
];

/// One field of a body word (offset relative to the word).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WordField {
    pub name: &'static str,
    pub offset: usize,
    pub ty: WireType,
    pub scale: f64,
    pub unit: &'static str,
    pub doc: &'static str,
}

const COEFF_NAMES: [[&str; 6]; 3] = [
    ["b1_0", "b1_1", "b1_2", "b1_3", "b1_4", "b1_5"],
    ["b2_0", "b2_1", "b2_2", "b2_3", "b2_4", "b2_5"],
    ["b3_0", "b3_1", "b3_2", "b3_3", "b3_4", "b3_5"],
];

/// The fields of body word `w` (the declaration of the segment layout).
pub fn word_fields(w: usize) -> [Option<WordField>; 2] {
    match w {
        0 => [
            Some(WordField {
                name: "seq",
                offset: 0,
                ty: WireType::U16,
                scale: 1.0,
                unit: "",
                doc: spec_text!(" Segment sequence number (0 = first after Reset)."),
            }),
            Some(WordField {
                name: "duration_us",
                offset: 2,
                ty: WireType::U32,
                scale: 1.0,
                unit: "us",
                doc: spec_text!(" Segment duration h."),
            }),
        ],
        1..=18 => {
            let (j, k) = ((w - 1) / 6, (w - 1) % 6);
            [
                Some(WordField {
                    name: COEFF_NAMES[j][k],
                    offset: 0,
                    ty: WireType::I48,
                    scale: COEFF_SCALE,
                    unit: "m",
                    doc: spec_text!(" Normalised coefficient b_jk = c_jk h^k of axis j, power k."),
                }),
                None,
            ]
        }
        _ => [
            Some(WordField {
                name: "flags",
                offset: 0,
                ty: WireType::U16,
                scale: 1.0,
                unit: "",
                doc: spec_text!(" Bit 0: first segment of the plan; bit 1: last."),
            }),
            Some(WordField {
                name: "crc",
                offset: 2,
                ty: WireType::U32,
                scale: 1.0,
                unit: "",
                doc: spec_text!(" CRC-32 of body bytes 0-115."),
            }),
        ],
    }
}

/// A segment as carried on the wire.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WireSegment {
    pub seq: u16,
    pub duration_us: u32,
    pub flags: u16,
    /// Normalised coefficients b_jk in units of [`COEFF_SCALE`].
    pub coeffs: [[i64; 6]; 3],
}

/// A segment the host cannot put on the wire.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
pub enum SegmentError {
    #[error("segment duration {0} s is not a whole number of microseconds in 1 µs..60 s")]
    Duration(f64),
    #[error("segment coefficient {0} m (normalised) is outside ±128 m or not finite")]
    Range(f64),
    #[error("{0} segments: a plan has at most 65535 (16-bit segment numbers)")]
    TooMany(usize),
}

impl WireSegment {
    /// Encodes a plan segment (coefficients in seconds) as normalised integers.
    pub fn from_quintic(seq: u16, q: &Quintic<f64>, flags: u16) -> Result<Self, SegmentError> {
        let us = libm::round(q.duration * 1e6);
        if !(us >= 1.0 && us <= MAX_DURATION_US as f64) || (us - q.duration * 1e6).abs() > 1e-3 {
            return Err(SegmentError::Duration(q.duration));
        }
        let h = us * 1e-6;
        let mut coeffs = [[0i64; 6]; 3];
        for (row, src) in coeffs.iter_mut().zip(q.coeffs.iter()) {
            let mut hk = 1.0;
            for (c, x) in row.iter_mut().zip(src.iter()) {
                let b = x * hk;
                let raw = libm::round(b / COEFF_SCALE);
                if !raw.is_finite() || raw.abs() > I48_MAX as f64 {
                    return Err(SegmentError::Range(b));
                }
                *c = raw as i64;
                hk *= h;
            }
        }
        Ok(Self {
            seq,
            duration_us: us as u32,
            flags,
            coeffs,
        })
    }

    /// Normalised coefficients in metres, f64 (host side).
    pub fn normalised_f64(&self) -> [[f64; 6]; 3] {
        self.coeffs.map(|r| r.map(|x| x as f64 * COEFF_SCALE))
    }

    /// Normalised coefficients in metres, f32 (drive side; exact power-of-two scaling).
    pub fn normalised_f32(&self) -> [[f32; 6]; 3] {
        self.coeffs
            .map(|r| r.map(|x| x as f32 * (COEFF_SCALE as f32)))
    }

    /// The 120-byte body with its CRC.
    pub fn encode_body(&self) -> [u8; BODY_LEN] {
        let mut b = [0u8; BODY_LEN];
        b[0..2].copy_from_slice(&self.seq.to_le_bytes());
        b[2..6].copy_from_slice(&self.duration_us.to_le_bytes());
        for j in 0..3 {
            for k in 0..6 {
                put_i48(self.coeffs[j][k], &mut b, WORD_LEN * (1 + 6 * j + k));
            }
        }
        b[114..116].copy_from_slice(&self.flags.to_le_bytes());
        let crc = crc32(&b[..CRC_OFFSET]);
        b[CRC_OFFSET..].copy_from_slice(&crc.to_le_bytes());
        b
    }

    /// CRC-32 of the encoded body (the value carried in word 19): identifies
    /// exactly which bits a node received.
    pub fn body_crc(&self) -> u32 {
        crc32(&self.encode_body()[..CRC_OFFSET])
    }

    /// Decodes a body, checking its CRC.
    pub fn decode_body(b: &[u8; BODY_LEN]) -> Result<Self, Reject> {
        let crc = u32::from_le_bytes([b[116], b[117], b[118], b[119]]);
        if crc32(&b[..CRC_OFFSET]) != crc {
            return Err(Reject::BadCrc);
        }
        let mut coeffs = [[0i64; 6]; 3];
        for (j, row) in coeffs.iter_mut().enumerate() {
            for (k, c) in row.iter_mut().enumerate() {
                *c = get_i48(b, WORD_LEN * (1 + 6 * j + k));
            }
        }
        Ok(Self {
            seq: u16::from_le_bytes([b[0], b[1]]),
            duration_us: u32::from_le_bytes([b[2], b[3], b[4], b[5]]),
            flags: u16::from_le_bytes([b[114], b[115]]),
            coeffs,
        })
    }

    /// Part frame `part` of an encoded body.
    pub fn part_frame(body: &[u8; BODY_LEN], part: usize, fd: bool) -> Frame {
        let wpp = words_per_part(fd);
        let def = if fd { &SEGMENT_PART_FD } else { &SEGMENT_PART };
        let mut f = Frame::new(def.addr.id(0), part_len(fd), fd);
        f.data[0] = part as u8;
        f.data[1] = body[0];
        let start = (part * wpp * WORD_LEN).min(BODY_LEN);
        let end = ((part + 1) * wpp * WORD_LEN).min(BODY_LEN);
        f.data[2..2 + (end - start)].copy_from_slice(&body[start..end]);
        f
    }

    /// All part frames of this segment, in order.
    pub fn frames(&self, fd: bool) -> impl Iterator<Item = Frame> {
        let body = self.encode_body();
        (0..parts_per_segment(fd)).map(move |p| Self::part_frame(&body, p, fd))
    }
}

/// What one part frame did to the reassembly.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PartEvent {
    /// Stored; more parts to come.
    Pending,
    /// The last part arrived and the CRC matches.
    Complete(WireSegment),
    /// A (partial) segment was dropped; `seq` is known once part 0 arrived.
    Rejected { seq: Option<u16>, reason: Reject },
    /// The part itself was ignored (a duplicate part); the segment continues.
    Ignored(Reject),
}

/// Reassembles the parts of one segment at a time. No allocation.
#[derive(Clone, Debug)]
pub struct Reassembler {
    body: [u8; BODY_LEN],
    next_part: usize,
    active: bool,
    fd: bool,
}

impl Default for Reassembler {
    fn default() -> Self {
        Self {
            body: [0; BODY_LEN],
            next_part: 0,
            active: false,
            fd: false,
        }
    }
}

impl Reassembler {
    fn seq(&self) -> u16 {
        u16::from_le_bytes([self.body[0], self.body[1]])
    }

    /// Drops any partial segment.
    pub fn clear(&mut self) {
        self.active = false;
        self.next_part = 0;
    }

    /// Feeds one part frame (payload of a SegmentPart or SegmentPartFd).
    pub fn push(&mut self, data: &[u8], fd: bool) -> PartEvent {
        // Checked accesses only (`get`, `zip`): a drive's receive path has no panic.
        let n_parts = parts_per_segment(fd);
        let wbytes = words_per_part(fd) * WORD_LEN;
        let (Some(&part), Some(&seq8), Some(words)) =
            (data.first(), data.get(1), data.get(2..2 + wbytes))
        else {
            return PartEvent::Ignored(Reject::Invalid);
        };
        let part = part as usize;
        if part >= n_parts {
            return PartEvent::Ignored(Reject::Invalid);
        }
        if part == 0 {
            let abandoned = self.active;
            let old = self.seq();
            self.active = true;
            self.fd = fd;
            self.store(0, words);
            self.next_part = 1;
            if self.body[0] != seq8 {
                // Header and body disagree: a damaged frame, worth a retransmission.
                self.clear();
                return PartEvent::Rejected {
                    seq: None,
                    reason: Reject::OutOfOrder,
                };
            }
            if abandoned {
                // The previous segment never completed: report it.
                return PartEvent::Rejected {
                    seq: Some(old),
                    reason: Reject::Incomplete,
                };
            }
            return self.maybe_complete(n_parts);
        }
        if !self.active || self.fd != fd {
            return PartEvent::Rejected {
                seq: None,
                reason: Reject::OutOfOrder,
            };
        }
        if seq8 != self.body[0] || part > self.next_part {
            let seq = self.seq();
            self.clear();
            return PartEvent::Rejected {
                seq: Some(seq),
                reason: Reject::OutOfOrder,
            };
        }
        if part < self.next_part {
            return PartEvent::Ignored(Reject::Duplicate);
        }
        self.store(part * wbytes, words);
        self.next_part += 1;
        self.maybe_complete(n_parts)
    }

    /// Copies a part's words into the body at byte `start` (what does not fit is dropped).
    fn store(&mut self, start: usize, words: &[u8]) {
        for (d, s) in self.body.iter_mut().skip(start).zip(words) {
            *d = *s;
        }
    }

    fn maybe_complete(&mut self, n_parts: usize) -> PartEvent {
        if self.next_part < n_parts {
            return PartEvent::Pending;
        }
        let seq = self.seq();
        self.clear();
        match WireSegment::decode_body(&self.body) {
            Ok(s) => PartEvent::Complete(s),
            Err(reason) => PartEvent::Rejected {
                seq: Some(seq),
                reason,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    pub(crate) fn sample() -> WireSegment {
        let q = Quintic {
            coeffs: [
                [0.37668, 0.01, -0.2, 0.3, -0.1, 0.02],
                [0.24416, -0.05, 0.1, 0.0, 0.05, -0.01],
                [0.33613, 0.0, 0.0, 0.4, -0.3, 0.06],
            ],
            duration: 0.512_345,
        };
        WireSegment::from_quintic(258, &q, FLAG_FIRST).unwrap()
    }

    #[test]
    fn body_round_trip_and_part_counts() {
        let s = sample();
        assert_eq!(WireSegment::decode_body(&s.encode_body()), Ok(s));
        for fd in [false, true] {
            let mut r = Reassembler::default();
            let frames: heapless::Vec<Frame, 20> = s.frames(fd).collect();
            assert_eq!(frames.len(), if fd { 2 } else { 20 });
            let mut out = None;
            for (i, f) in frames.iter().enumerate() {
                match r.push(f.payload(), fd) {
                    PartEvent::Pending => assert!(i + 1 < frames.len()),
                    PartEvent::Complete(x) => out = Some(x),
                    e => panic!("{e:?}"),
                }
            }
            assert_eq!(out, Some(s));
        }
    }

    #[test]
    fn normalised_coefficients_evaluate_like_the_plan() {
        let s = sample();
        let b = s.normalised_f64();
        let h = s.duration_us as f64 * 1e-6;
        let c0 = [0.37668, 0.01, -0.2, 0.3, -0.1, 0.02];
        for i in 0..=10 {
            let t = h * i as f64 / 10.0;
            let direct: f64 = (0..6).map(|k| c0[k] * t.powi(k as i32)).sum();
            let tau = t / h;
            let norm: f64 = (0..6).map(|k| b[0][k] * tau.powi(k as i32)).sum();
            assert!((direct - norm).abs() < 1e-11);
        }
    }

    #[test]
    fn corrupted_part_fails_crc() {
        let s = sample();
        let mut r = Reassembler::default();
        let mut last = PartEvent::Pending;
        for (i, mut f) in s.frames(false).enumerate() {
            if i == 7 {
                f.data[4] ^= 0x10;
            }
            last = r.push(f.payload(), false);
        }
        assert_eq!(
            last,
            PartEvent::Rejected {
                seq: Some(258),
                reason: Reject::BadCrc
            }
        );
    }

    #[test]
    fn duplicate_and_out_of_order_parts() {
        let s = sample();
        let frames: heapless::Vec<Frame, 20> = s.frames(false).collect();
        let mut r = Reassembler::default();
        assert_eq!(r.push(frames[0].payload(), false), PartEvent::Pending);
        assert_eq!(r.push(frames[1].payload(), false), PartEvent::Pending);
        // The same part again: ignored, counted as a duplicate, assembly continues.
        assert_eq!(
            r.push(frames[1].payload(), false),
            PartEvent::Ignored(Reject::Duplicate)
        );
        // Skipping part 2: the partial segment is dropped.
        assert_eq!(
            r.push(frames[3].payload(), false),
            PartEvent::Rejected {
                seq: Some(258),
                reason: Reject::OutOfOrder
            }
        );
        // A part without its header.
        assert_eq!(
            r.push(frames[4].payload(), false),
            PartEvent::Rejected {
                seq: None,
                reason: Reject::OutOfOrder
            }
        );
        // A new header while one is pending: the old one is reported incomplete.
        assert_eq!(r.push(frames[0].payload(), false), PartEvent::Pending);
        assert_eq!(
            r.push(frames[0].payload(), false),
            PartEvent::Rejected {
                seq: Some(258),
                reason: Reject::Incomplete
            }
        );
        // And the restarted segment still completes.
        let mut last = PartEvent::Pending;
        for f in &frames[1..] {
            last = r.push(f.payload(), false);
        }
        assert_eq!(last, PartEvent::Complete(s));
    }

    #[test]
    fn durations_must_be_whole_microseconds() {
        let q = Quintic {
            coeffs: [[0.0; 6]; 3],
            duration: 0.1234567,
        };
        assert!(matches!(
            WireSegment::from_quintic(0, &q, 0),
            Err(SegmentError::Duration(_))
        ));
    }
}
