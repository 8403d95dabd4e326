//! Compact segments: a segment sent as the continuation of the one before.
//!
//! A plan is C3: a segment starts with the position, velocity, acceleration
//! and jerk its predecessor ends with. A continuation carries only what the
//! predecessor does not fix: the duration and the coefficients of τ⁴ and τ⁵
//! of every axis, as six 24-bit mantissas m_jk sharing one exponent e:
//! b_jk = m_jk · 2^e fine units of 2⁻⁴⁸ m. The receiver rebuilds the full
//! segment from the predecessor it holds, in the predecessor's exact
//! integer form ([`Compact::reconstruct`], the same arithmetic on host and
//! drive, so the host knows every bit the drive will hold):
//!
//! b_m = round(S_m · (h/h')^m), m = 0..3, with S_m = Σ_k C(k, m) b'_k,
//!
//! the Taylor coefficient of order m at the predecessor's end (b' its
//! normalised coefficients, h' its duration). A deviation the chain
//! carries on (a jerk error persists and is integrated) is corrected by
//! the next continuation: the host picks the mantissas so that the rebuilt
//! segment ends where the plan's next one starts ([`Compact::continuing`]).
//! It sends a segment compact only if what the drive rebuilds stays within
//! [`DeviationBound::DEFAULT`] of the plan's segment; otherwise, and
//! whenever the previous segment on the bus is not the predecessor (the
//! first segment, a retransmission), it sends the full segment, which
//! re-anchors the chain exactly.
//!
//! The body is 28 bytes: `seq` u16, `duration_us` u24, `form` u8 (bits
//! 0–1 the flags, bits 2–7 the exponent e), the mantissas m_j4, m_j5 (i24)
//! for j = 1..3, and `crc` u32: the CRC-32 of the predecessor's body CRC
//! (little-endian) followed by body bytes 0–23. A receiver holding another
//! predecessor (or none) computes another CRC and answers
//! [`Reject::NoPredecessor`]; the host then sends the full segment. Four
//! classic frames of seven body bytes (byte 0 the part index), or one
//! CAN-FD frame of 32 bytes.

use super::Frame;
use super::crc::Crc32;
use super::messages::Reject;
use super::segment::{COEFF_SCALE, FLAG_FIRST, FLAG_LAST, WireSegment};
use super::wire::{Addr, FieldDef, I48_MAX, MessageDef, WireType};

/// Body length (bytes).
pub const COMPACT_LEN: usize = 28;
/// Body bytes per classic part frame.
pub const CLASSIC_CHUNK: usize = 7;
/// Payload length of the CAN-FD frame (a valid CAN-FD length ≥ 1 + body).
pub const FD_LEN: usize = 32;
/// Offset of the `form` byte (flags and exponent) in the body.
const FORM: usize = 5;
/// Offset of the first mantissa in the body.
const MANTISSAS: usize = 6;
/// Bits of `form` that are flags; the exponent is above them.
const FLAG_MASK: u8 = 0b11;
/// Largest mantissa magnitude (i24, symmetric).
const MANTISSA_MAX: i64 = (1 << 23) - 1;
/// Largest exponent: the largest coefficient (2⁵⁵ fine units) has one, and
/// a mantissa times 2^e stays within 2⁵⁶.
const EXP_MAX: u8 = 33;
/// Longest continuation (µs): the u24 duration; a longer segment goes in full.
pub const COMPACT_MAX_DURATION_US: u32 = (1 << 24) - 1;

/// Bits below a unit ([`COEFF_SCALE`]) of the coefficients a chain
/// continues from: the start of a continuation is rebuilt from its
/// predecessor's end in these finer units, so a short segment's end
/// (jerk to 6 units / h³ in its own units) does not fix its successor's
/// start only to that (magnified by (h/h')³ there).
pub const FINE_BITS: u32 = 8;

/// A segment as a receiver holds it once taken in, and what a continuation
/// of it is rebuilt from: its coefficients in units of 2⁻⁸ of
/// [`COEFF_SCALE`] (those of a full segment are its own, exactly; those of
/// a continuation as rebuilt, before rounding to the wire's units).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Held {
    pub segment: WireSegment,
    fine: [[i64; 6]; 3],
}

impl From<WireSegment> for Held {
    fn from(segment: WireSegment) -> Self {
        Self {
            segment,
            fine: segment.coeffs.map(|r| r.map(|x| x << FINE_BITS)),
        }
    }
}

/// x / 2^FINE_BITS rounded half away from zero.
fn unfine(x: i64) -> i64 {
    let half = 1i64 << (FINE_BITS - 1);
    if x < 0 {
        -((-x + half) >> FINE_BITS)
    } else {
        (x + half) >> FINE_BITS
    }
}

/// Flag: the segment starts at rest at `pose` (a plan's first segment):
/// it continues no predecessor, its CRC chains on 0.
pub const FLAG_AT_REST: u8 = 1;
/// The longest body (a plan's first segment): the continuation's 28 bytes
/// and the start pose (3 × i48).
pub const COMPACT_MAX: usize = COMPACT_LEN + 18;
/// Payload length of a CAN-FD frame carrying a body longer than 31 bytes.
pub const FD_LEN_MAX: usize = 48;

/// Body length of a compact segment with `flags`: the continuation's
/// 28 bytes, plus the start pose (3 × i48) when it starts at rest.
pub const fn body_len(flags: u8) -> usize {
    if flags & FLAG_AT_REST != 0 {
        COMPACT_MAX
    } else {
        COMPACT_LEN
    }
}

/// Part frames of a compact segment with `flags`: 4 or 7 classic, 1 CAN-FD.
pub const fn compact_parts(flags: u8, fd: bool) -> usize {
    if fd {
        1
    } else {
        body_len(flags).div_ceil(CLASSIC_CHUNK)
    }
}

/// Classic compact part (DLC 8).
pub const SEGMENT_COMPACT: MessageDef = MessageDef {
    name: "SegmentCompact",
    addr: Addr::Broadcast(0x108),
    len: 8,
    sender: "host",
    period: "streamed",
    doc: " Seven bytes of a compact (continuation) segment body; 4 parts per segment (7 from rest).",
    mux: Some("part"),
    fd: false,
    fields: &PART_FIELD,
};

/// CAN-FD compact segment (32 bytes; 48 from rest).
pub const SEGMENT_COMPACT_FD: MessageDef = MessageDef {
    name: "SegmentCompactFd",
    addr: Addr::Broadcast(0x118),
    len: FD_LEN,
    sender: "host",
    period: "streamed",
    doc: " A whole compact (continuation) segment body in one frame (CAN-FD, BRS; 48 bytes from rest).",
    mux: Some("part"),
    fd: true,
    fields: &PART_FIELD,
};

const PART_FIELD: [FieldDef; 1] = [FieldDef {
    name: "part",
    offset: 0,
    ty: WireType::U8,
    scale: 1.0,
    unit: "",
    doc: " Part index (multiplexor).",
    values: None,
}];

/// One field of the compact body (offset in the body).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BodyField {
    pub name: &'static str,
    pub offset: usize,
    pub ty: WireType,
    pub unit: &'static str,
    pub doc: &'static str,
}

const fn mantissa(name: &'static str, offset: usize) -> BodyField {
    BodyField {
        name,
        offset,
        ty: WireType::I24,
        unit: "",
        doc: " Mantissa m_jk of the normalised coefficient b_jk = c_jk h^k = m_jk 2^(e-48) m (k = 4, 5).",
    }
}

/// The compact body, field by field (the declaration of its layout).
pub const COMPACT_FIELDS: [BodyField; 10] = [
    BodyField {
        name: "seq",
        offset: 0,
        ty: WireType::U16,
        unit: "",
        doc: " Segment sequence number (0 only from rest).",
    },
    BodyField {
        name: "duration_us",
        offset: 2,
        ty: WireType::U24,
        unit: "us",
        doc: " Segment duration h (a longer segment than 16.777215 s goes in full).",
    },
    BodyField {
        name: "form",
        offset: FORM,
        ty: WireType::U8,
        unit: "",
        doc: " Bit 0: starts at rest (the start pose, 3 x i48 in units of 2^-40 m, follows the mantissas); bit 1: last segment of the plan; bits 2-7: exponent e (0-33) of the mantissas.",
    },
    mantissa("m1_4", MANTISSAS),
    mantissa("m1_5", MANTISSAS + 3),
    mantissa("m2_4", MANTISSAS + 6),
    mantissa("m2_5", MANTISSAS + 9),
    mantissa("m3_4", MANTISSAS + 12),
    mantissa("m3_5", MANTISSAS + 15),
    BodyField {
        name: "crc",
        offset: COMPACT_LEN - 4,
        ty: WireType::U32,
        unit: "",
        doc: " CRC-32 of the predecessor's body CRC (4 bytes, little-endian; 0 from rest), then body bytes 0-23 (0-41 from rest; the CRC at 42).",
    },
];

/// How far a rebuilt segment may deviate from the plan's, per derivative,
/// bounded over the whole segment by the coefficient differences δb_k:
/// |δq| ≤ Σ|δb_k|, |δq'| ≤ Σ k|δb_k|/h, |δq''| ≤ Σ k(k−1)|δb_k|/h²,
/// |δq'''| ≤ Σ k(k−1)(k−2)|δb_k|/h³.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DeviationBound {
    /// Position (m).
    pub position: f64,
    /// Velocity (m/s).
    pub velocity: f64,
    /// Acceleration (m/s²).
    pub acceleration: f64,
    /// Jerk (m/s³).
    pub jerk: f64,
}

impl DeviationBound {
    /// What the host allows: well inside what a drive absorbs between
    /// segments (10 µm, 1 % of its limits) and below an encoder count.
    pub const DEFAULT: Self = Self {
        position: 0.1e-6,
        velocity: 10e-6,
        acceleration: 1e-3,
        jerk: 0.1,
    };

    /// The largest deviation of `a` from `b` (same duration), per derivative.
    pub fn between(a: &WireSegment, b: &WireSegment) -> Self {
        let h = a.duration_us as f64 * 1e-6;
        let mut d = Self {
            position: 0.0,
            velocity: 0.0,
            acceleration: 0.0,
            jerk: 0.0,
        };
        for (ra, rb) in a.coeffs.iter().zip(&b.coeffs) {
            let mut s = [0.0f64; 4];
            for k in 0..6 {
                let e = (ra[k] - rb[k]).unsigned_abs() as f64 * COEFF_SCALE;
                let kf = k as f64;
                s[0] += e;
                s[1] += kf * e;
                s[2] += kf * (kf - 1.0) * e;
                s[3] += kf * (kf - 1.0) * (kf - 2.0) * e;
            }
            d.position = d.position.max(s[0]);
            d.velocity = d.velocity.max(s[1] / h);
            d.acceleration = d.acceleration.max(s[2] / (h * h));
            d.jerk = d.jerk.max(s[3] / (h * h * h));
        }
        d
    }

    /// Every figure of `self` within `bound`.
    pub fn within(&self, bound: &Self) -> bool {
        self.position <= bound.position
            && self.velocity <= bound.velocity
            && self.acceleration <= bound.acceleration
            && self.jerk <= bound.jerk
    }
}

/// A continuation segment as carried on the wire.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Compact {
    pub seq: u16,
    pub duration_us: u32,
    /// [`FLAG_AT_REST`], and bit 1 last segment of the plan.
    pub flags: u8,
    /// The exponent e of the mantissas: b_jk = m_jk · 2^e fine units (2⁻⁴⁸ m).
    pub exp: u8,
    /// m_j4, m_j5 (i24).
    pub mantissas: [[i32; 2]; 3],
    /// b_j0 (units of [`COEFF_SCALE`]); sent only with [`FLAG_AT_REST`].
    pub pose: [i64; 3],
    pub crc: u32,
}

/// `C(k, m)` for k = 0..5, m = 0..3.
const BINOMIAL: [[i64; 6]; 4] = [
    [1, 1, 1, 1, 1, 1],
    [0, 1, 2, 3, 4, 5],
    [0, 0, 1, 3, 6, 10],
    [0, 0, 0, 1, 4, 10],
];

/// x·h/d rounded half away from zero (d > 0): in i64 when the product
/// fits (the common case; a 128-bit division costs a drive's receive side
/// about ten times more), else in i128. Both give the same result.
fn scale_round(x: i128, h: i128, d: i128) -> Option<i128> {
    if let (Ok(x), Ok(h), Ok(d)) = (i64::try_from(x), i64::try_from(h), i64::try_from(d))
        && let Some(n) = x.checked_mul(h)
        && let Some(r) = n
            .checked_add(if n < 0 { -d / 2 } else { d / 2 })
            .and_then(|m| m.checked_div(d))
    {
        return Some(r as i128);
    }
    let n = x.checked_mul(h)?;
    let half = if n < 0 { -d / 2 } else { d / 2 };
    n.checked_add(half)?.checked_div(d)
}

/// A mantissa with exponent `e` in fine units (2⁻⁴⁸ m); `None` outside
/// the declared ranges. Integers only: the same on every receiver. Not
/// inlined: six call sites in a drive's tight flash.
#[inline(never)]
fn coefficient(m: i32, e: u8) -> Option<i64> {
    let m = m as i64;
    (e <= EXP_MAX && m.abs() <= MANTISSA_MAX).then(|| m << e)
}

/// v / 2^e rounded half away from zero.
fn shift_round(v: i64, e: u8) -> i64 {
    if e == 0 {
        return v;
    }
    let half = 1i64 << (e - 1);
    if v < 0 {
        -((-v + half) >> e)
    } else {
        (v + half) >> e
    }
}

/// The smallest exponent whose mantissas hold `max_abs` (fine units) with
/// a step to spare either side.
fn exponent_for(max_abs: f64) -> Option<u8> {
    (0..=EXP_MAX).find(|&e| libm::round(max_abs / powi(2.0, e as usize)) < MANTISSA_MAX as f64)
}

/// The chained CRC of a body (all but its last 4 bytes) after predecessor CRC `pred_crc`.
fn chained_crc(pred_crc: u32, body: &[u8]) -> u32 {
    let mut c = Crc32::new();
    c.update(&pred_crc.to_le_bytes());
    c.update(body.get(..body.len().saturating_sub(4)).unwrap_or(&[]));
    c.finish()
}

/// Choosing one axis's b_4, b_5 (host side): the rebuilt segment's end,
/// in fine units, against the end it should have.
struct EndFit {
    /// The plan's b_4, b_5 (fine units).
    plan45: [i64; 2],
    /// Target end minus the rebuilt end with the plan's b_4, b_5: the
    /// Taylor coefficients of order m = 0..3 (fine units, `next`'s normalisation).
    gap: [f64; 4],
    /// Weight of order m: the longer segment's normalisation, f^m.
    weight: [f64; 4],
}

impl EndFit {
    /// `start`: the rebuilt b_0..b_3 (fine units); the rest in fine units too.
    fn new(start: &[i64; 4], next: &WireSegment, after: Option<&WireSegment>, j: usize) -> Self {
        let fine = (1i64 << FINE_BITS) as f64;
        let p = next.coeffs[j].map(|x| x << FINE_BITS);
        // Where the rebuilt segment should end, relative to where the plan's
        // segment ends (fine units): the successor's start scaled into this
        // segment's normalisation, less this segment's end (both < 2⁵³ in
        // units, exact in f64 before the scaling).
        let (rho, target) = match after {
            Some(a) => {
                let rho = a.duration_us as f64 / next.duration_us as f64;
                (
                    rho,
                    core::array::from_fn(|m| a.coeffs[j][m] as f64 * fine / powi(rho, m)),
                )
            }
            None => (1.0, [0.0; 4]),
        };
        let gap = core::array::from_fn(|m| {
            let plan_end: i64 = (0..6).map(|k| BINOMIAL[m][k] * p[k]).sum();
            let start_err: i64 = (0..4).map(|k| BINOMIAL[m][k] * (start[k] - p[k])).sum();
            let t = if after.is_some() {
                target[m] - plan_end as f64
            } else {
                0.0
            };
            t - start_err as f64
        });
        let f = if rho > 1.0 { rho } else { 1.0 };
        Self {
            plan45: [p[4], p[5]],
            gap,
            weight: core::array::from_fn(|m| powi(f, m)),
        }
    }

    /// The weighted squared distance of the end with b_4, b_5 = the plan's + `d` (fine units).
    fn cost(&self, d: [f64; 2]) -> f64 {
        (0..4)
            .map(|m| {
                let e = BINOMIAL[m][4] as f64 * d[0] + BINOMIAL[m][5] as f64 * d[1] - self.gap[m];
                let w = self.weight[m] * e;
                w * w
            })
            .sum()
    }

    /// The b_4, b_5 (fine units, real) whose end is closest: the plan's
    /// plus the least-squares correction.
    fn ideal(&self) -> [f64; 2] {
        // Normal equations of min Σ (w_m (C(4,m) d_4 + C(5,m) d_5 − g_m))².
        let (mut a, mut b, mut c, mut r0, mut r1) = (0.0, 0.0, 0.0, 0.0, 0.0);
        for ((row, w), g) in BINOMIAL.iter().zip(&self.weight).zip(&self.gap) {
            let w2 = w * w;
            let (x, y) = (row[4] as f64, row[5] as f64);
            a += w2 * x * x;
            b += w2 * x * y;
            c += w2 * y * y;
            r0 += w2 * x * g;
            r1 += w2 * y * g;
        }
        let det = a * c - b * b;
        let d = if det > 0.0 && det.is_finite() {
            [(c * r0 - b * r1) / det, (a * r1 - b * r0) / det]
        } else {
            [0.0; 2]
        };
        [self.plan45[0] as f64 + d[0], self.plan45[1] as f64 + d[1]]
    }

    /// The mantissa pair (exponent `e`) of least cost among those next to `ideal`.
    fn best(&self, ideal: [f64; 2], e: u8) -> [i32; 2] {
        let step = powi(2.0, e as usize);
        let near = |k: usize| {
            let u = libm::round(ideal[k] / step) as i64;
            [u - 1, u, u + 1].map(|m| m.clamp(-MANTISSA_MAX, MANTISSA_MAX))
        };
        let (c4, c5) = (near(0), near(1));
        let mut best = ([0i32; 2], f64::INFINITY);
        for &m4 in &c4 {
            for &m5 in &c5 {
                let d = [
                    ((m4 << e) - self.plan45[0]) as f64,
                    ((m5 << e) - self.plan45[1]) as f64,
                ];
                let cost = self.cost(d);
                if cost < best.1 {
                    best = ([m4 as i32, m5 as i32], cost);
                }
            }
        }
        best.0
    }
}

/// x^m for small m (no_std: no `powi`).
fn powi(x: f64, m: usize) -> f64 {
    (0..m).fold(1.0, |acc, _| acc * x)
}

impl Compact {
    /// The start of a segment of `duration_us` continuing `pred`: b_0..b_3
    /// in fine units, each scaled by h/h' m times with rounding after each
    /// step (integers only: a drive's receive side uses no f64).
    fn start(pred: &Held, duration_us: u32) -> Option<[[i64; 4]; 3]> {
        let (h, hp) = (duration_us as i128, pred.segment.duration_us as i128);
        if hp == 0 {
            return None;
        }
        let limit = (I48_MAX as u128) << (FINE_BITS + 8);
        let mut out = [[0i64; 4]; 3];
        for (o, row) in out.iter_mut().zip(&pred.fine) {
            for (m, (b, binom)) in o.iter_mut().zip(&BINOMIAL).enumerate() {
                // Exact: |b'_k| < 2⁵⁵ and Σ C(k, m) ≤ 20, so S_m < 2⁶⁰.
                let mut x: i128 = row.iter().zip(binom).map(|(x, c)| (x * c) as i128).sum();
                for _ in 0..m {
                    x = scale_round(x, h, hp)?;
                    if x.unsigned_abs() > limit {
                        return None;
                    }
                }
                *b = i64::try_from(x)
                    .ok()
                    .filter(|v| unfine(v.abs()) <= I48_MAX)?;
            }
        }
        Some(out)
    }

    /// The full segment this compact one stands for, as held: continuing
    /// `pred`, or from rest at its pose ([`FLAG_AT_REST`], no `pred`).
    fn rebuild(&self, pred: Option<&Held>) -> Option<Held> {
        let start = if self.flags & FLAG_AT_REST != 0 {
            if self.pose.iter().any(|p| p.abs() > I48_MAX) {
                return None;
            }
            self.pose.map(|p| [p << FINE_BITS, 0, 0, 0])
        } else {
            Self::start(pred?, self.duration_us)?
        };
        let mut fine = [[0i64; 6]; 3];
        for ((row, s), m) in fine.iter_mut().zip(&start).zip(&self.mantissas) {
            row[..4].copy_from_slice(s);
            row[4] = coefficient(m[0], self.exp)?;
            row[5] = coefficient(m[1], self.exp)?;
            if row.iter().any(|x| unfine(x.abs()) > I48_MAX) {
                return None;
            }
        }
        Some(Held {
            segment: WireSegment {
                seq: self.seq,
                duration_us: self.duration_us,
                flags: (self.flags as u16) & (FLAG_FIRST | FLAG_LAST),
                coeffs: fine.map(|r| r.map(unfine)),
            },
            fine,
        })
    }

    /// Host side: `next` (the plan's segment) as a continuation of `pred`
    /// (the segment the receivers hold before it, as they hold it), and the
    /// segment they will hold once they rebuilt it; `None` if that would
    /// deviate from `next` beyond `bound` (send `next` in full).
    ///
    /// b_4, b_5 are not the plan's rounded to the mantissas but those whose
    /// rebuilt segment ends closest to where the plan's successor `after`
    /// starts (to `next`'s own end for the last segment): the host knows
    /// every bit the receivers rebuild, so each continuation corrects the
    /// deviation its predecessor left (error feedback) instead of passing
    /// it on. The distance is that of the Taylor coefficients b_0..b_3 in
    /// the normalisation of the longer of the two segments: a jerk error
    /// that a short segment leaves is the longer one's to carry.
    pub fn continuing(
        pred: &Held,
        next: &WireSegment,
        after: Option<&WireSegment>,
        bound: &DeviationBound,
    ) -> Option<(Self, Held)> {
        if next.seq != pred.segment.seq.wrapping_add(1) || next.seq == 0 {
            return None;
        }
        let start = Self::start(pred, next.duration_us)?;
        Self::choose(Some(pred), start, [0; 3], next, after, bound)
    }

    /// Host side: `next`, a plan's first segment, sent from rest at its
    /// start pose; `None` if it does not start at rest within `bound`.
    pub fn first(
        next: &WireSegment,
        after: Option<&WireSegment>,
        bound: &DeviationBound,
    ) -> Option<(Self, Held)> {
        if next.seq != 0 {
            return None;
        }
        let pose = next.coeffs.map(|r| r[0]);
        let start = pose.map(|p| [p << FINE_BITS, 0, 0, 0]);
        Self::choose(None, start, pose, next, after, bound)
    }

    /// The form within `bound`: the fitted b_4, b_5, else the plan's own
    /// rounded to the mantissas.
    fn choose(
        pred: Option<&Held>,
        start: [[i64; 4]; 3],
        pose: [i64; 3],
        next: &WireSegment,
        after: Option<&WireSegment>,
        bound: &DeviationBound,
    ) -> Option<(Self, Held)> {
        if next.duration_us > COMPACT_MAX_DURATION_US {
            return None;
        }
        let after = after.filter(|a| a.seq == next.seq.wrapping_add(1) && a.duration_us > 0);
        let fits: [EndFit; 3] = core::array::from_fn(|j| EndFit::new(&start[j], next, after, j));
        let ideal = fits.each_ref().map(EndFit::ideal);
        let max_abs = |v: &[[f64; 2]; 3]| v.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
        let fitted = exponent_for(max_abs(&ideal)).map(|e| {
            let m: [[i32; 2]; 3] = core::array::from_fn(|j| fits[j].best(ideal[j], e));
            (e, m)
        });
        // The plan's own, rounded: when a correction would itself break the
        // bound (a short segment has little room for one).
        let plan = next.coeffs.map(|r| [r[4] << FINE_BITS, r[5] << FINE_BITS]);
        let rounded = exponent_for(max_abs(&plan.map(|p| p.map(|x| x as f64))))
            .map(|e| (e, plan.map(|p| p.map(|x| shift_round(x, e) as i32))));
        let flags =
            (next.flags as u8 & FLAG_LAST as u8) | if pred.is_none() { FLAG_AT_REST } else { 0 };
        let pred_crc = pred.map_or(0, |p| p.segment.body_crc());
        [fitted, rounded]
            .into_iter()
            .flatten()
            .find_map(|(exp, mantissas)| {
                let mut c = Self {
                    seq: next.seq,
                    duration_us: next.duration_us,
                    flags,
                    exp,
                    mantissas,
                    pose: if flags & FLAG_AT_REST != 0 {
                        pose
                    } else {
                        [0; 3]
                    },
                    crc: 0,
                };
                let rebuilt = c.rebuild(pred)?;
                if !DeviationBound::between(&rebuilt.segment, next).within(bound) {
                    return None;
                }
                let (body, len) = c.encode_body();
                c.crc = chained_crc(pred_crc, &body[..len]);
                Some((c, rebuilt))
            })
    }

    /// Receiver side: the full segment, if `pred` (with body CRC `pred_crc`)
    /// is the predecessor the host built this continuation on.
    pub fn reconstruct(&self, pred: &Held, pred_crc: u32) -> Result<Held, Reject> {
        let (body, len) = self.encode_body();
        if self.flags & FLAG_AT_REST != 0
            || pred.segment.seq.wrapping_add(1) != self.seq
            || chained_crc(pred_crc, &body[..len]) != self.crc
        {
            return Err(Reject::NoPredecessor);
        }
        self.rebuild(Some(pred)).ok_or(Reject::Invalid)
    }

    /// Receiver side: a segment that starts at rest ([`FLAG_AT_REST`]),
    /// which continues nothing; `BadCrc` if its CRC fails.
    pub fn from_rest(&self) -> Result<Held, Reject> {
        let (body, len) = self.encode_body();
        if self.flags & FLAG_AT_REST == 0 || self.seq != 0 {
            return Err(Reject::Invalid);
        }
        if chained_crc(0, &body[..len]) != self.crc {
            return Err(Reject::BadCrc);
        }
        self.rebuild(None).ok_or(Reject::Invalid)
    }

    /// Starts at rest: needs no predecessor.
    pub fn is_at_rest(&self) -> bool {
        self.flags & FLAG_AT_REST != 0
    }

    /// The body (with the CRC as it stands) and its length: header,
    /// mantissas, the pose if it starts at rest, CRC.
    pub fn encode_body(&self) -> ([u8; COMPACT_MAX], usize) {
        let mut b = [0u8; COMPACT_MAX];
        b[0..2].copy_from_slice(&self.seq.to_le_bytes());
        b[2..5].copy_from_slice(&self.duration_us.to_le_bytes()[..3]);
        b[FORM] = (self.flags & FLAG_MASK) | (self.exp << 2);
        let mut o = MANTISSAS;
        for m in self.mantissas.iter().flatten() {
            b[o..o + 3].copy_from_slice(&m.to_le_bytes()[..3]);
            o += 3;
        }
        if self.flags & FLAG_AT_REST != 0 {
            for p in &self.pose {
                b[o..o + 6].copy_from_slice(&p.to_le_bytes()[..6]);
                o += 6;
            }
        }
        b[o..o + 4].copy_from_slice(&self.crc.to_le_bytes());
        (b, o + 4)
    }

    /// Decodes a body (its CRC is checked by [`Compact::reconstruct`] or
    /// [`Compact::from_rest`]); its length follows from its flags.
    pub fn decode_body(b: &[u8; COMPACT_MAX]) -> Self {
        let i24 = |o: usize| i32::from_le_bytes([b[o], b[o + 1], b[o + 2], 0]) << 8 >> 8;
        let form = b[FORM];
        let flags = form & FLAG_MASK;
        let mut o = MANTISSAS;
        let mut mantissas = [[0i32; 2]; 3];
        for pair in &mut mantissas {
            *pair = [i24(o), i24(o + 3)];
            o += 6;
        }
        let mut pose = [0i64; 3];
        if flags & FLAG_AT_REST != 0 {
            for p in &mut pose {
                let mut w = [0u8; 8];
                w[..6].copy_from_slice(&b[o..o + 6]);
                // Sign-extend the i48.
                *p = i64::from_le_bytes(w) << 16 >> 16;
                o += 6;
            }
        }
        Self {
            seq: u16::from_le_bytes([b[0], b[1]]),
            duration_us: u32::from_le_bytes([b[2], b[3], b[4], 0]),
            flags,
            exp: form >> 2,
            mantissas,
            pose,
            crc: u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]),
        }
    }

    /// All part frames of this segment, in order.
    pub fn frames(&self, fd: bool) -> impl Iterator<Item = Frame> {
        let (body, len) = self.encode_body();
        (0..compact_parts(self.flags, fd)).map(move |p| {
            let (def, chunk) = if fd {
                (&SEGMENT_COMPACT_FD, COMPACT_MAX)
            } else {
                (&SEGMENT_COMPACT, CLASSIC_CHUNK)
            };
            let dlc = if fd && 1 + len > def.len {
                FD_LEN_MAX
            } else {
                def.len
            };
            let mut f = Frame::new(def.addr.id(0), dlc, fd);
            f.data[0] = p as u8;
            let start = (p * chunk).min(len);
            let end = ((p + 1) * chunk).min(len);
            f.data[1..1 + end - start].copy_from_slice(&body[start..end]);
            f
        })
    }
}

/// A segment as the host sends it: in full, or compact.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outgoing {
    Full(WireSegment),
    /// The continuation and the segment receivers rebuild from it.
    Compact(Compact, WireSegment),
}

impl Outgoing {
    /// Its part frames, in order.
    pub fn frames(&self, fd: bool) -> heapless::Vec<Frame, 20> {
        match self {
            Outgoing::Full(w) => w.frames(fd).collect(),
            Outgoing::Compact(c, _) => c.frames(fd).collect(),
        }
    }

    /// The segment a receiver holds once it took this in.
    pub fn held(&self) -> &WireSegment {
        match self {
            Outgoing::Full(w) | Outgoing::Compact(_, w) => w,
        }
    }

    pub fn is_compact(&self) -> bool {
        matches!(self, Outgoing::Compact(..))
    }
}

/// The sending side of the chain: each segment compact when the segment
/// sent just before is its predecessor and the rebuilt one stays within
/// [`DeviationBound::DEFAULT`], in full otherwise.
#[derive(Clone, Debug, Default)]
pub struct Chain {
    /// The last segment sent, as receivers hold it.
    last: Option<Held>,
}

impl Chain {
    /// How `seg` goes on the bus now (it becomes the last segment sent);
    /// `after` is the plan's segment after it (`None` for the last).
    pub fn next(&mut self, seg: &WireSegment, after: Option<&WireSegment>) -> Outgoing {
        let bound = &DeviationBound::DEFAULT;
        let compact = match &self.last {
            Some(p) => Compact::continuing(p, seg, after, bound),
            None => Compact::first(seg, after, bound),
        };
        let (out, held) = match compact {
            Some((c, held)) => (Outgoing::Compact(c, held.segment), held),
            None => (Outgoing::Full(*seg), Held::from(*seg)),
        };
        self.last = Some(held);
        out
    }

    /// `seg` in full (a resend: receivers may hold another version of its
    /// predecessor than the one sent last).
    pub fn full(&mut self, seg: &WireSegment) -> Outgoing {
        self.last = Some(Held::from(*seg));
        Outgoing::Full(*seg)
    }
}

/// What one compact part frame did.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CompactEvent {
    /// Stored; more parts to come.
    Pending,
    /// The last part arrived (the CRC is not yet checked).
    Complete(Compact),
    /// A partial compact segment was dropped.
    Rejected { seq: Option<u16>, reason: Reject },
    /// The part itself was ignored (a duplicate part).
    Ignored(Reject),
}

/// Reassembles the classic parts of one compact segment (a CAN-FD one is whole).
#[derive(Clone, Debug)]
pub struct CompactAssembler {
    body: [u8; COMPACT_MAX],
    next_part: usize,
}

impl Default for CompactAssembler {
    fn default() -> Self {
        Self {
            body: [0; COMPACT_MAX],
            next_part: 0,
        }
    }
}

impl CompactAssembler {
    /// Drops any partial segment.
    pub fn clear(&mut self) {
        self.next_part = 0;
    }

    fn seq(&self) -> u16 {
        u16::from_le_bytes([self.body[0], self.body[1]])
    }

    /// Feeds one part frame (payload of a SegmentCompact or SegmentCompactFd).
    pub fn push(&mut self, data: &[u8], fd: bool) -> CompactEvent {
        let Some(&part) = data.first() else {
            return CompactEvent::Ignored(Reject::Invalid);
        };
        let part = part as usize;
        // The body's length, from its flags (in part 0, or stored).
        let flags = if part == 0 {
            data.get(1 + FORM).copied()
        } else {
            Some(self.body[FORM])
        };
        let Some(flags) = flags else {
            return CompactEvent::Ignored(Reject::Invalid);
        };
        let total = body_len(flags);
        let chunk = if fd { total } else { CLASSIC_CHUNK };
        let start = part * chunk;
        let len = chunk.min(total.saturating_sub(start));
        let Some(bytes) = data.get(1..1 + len) else {
            return CompactEvent::Ignored(Reject::Invalid);
        };
        if part >= compact_parts(flags, fd) {
            return CompactEvent::Ignored(Reject::Invalid);
        }
        if part == 0 {
            let abandoned = (self.next_part > 0).then(|| self.seq());
            self.next_part = 0;
            if let Some(seq) = abandoned {
                self.store(start, bytes);
                self.next_part = 1;
                return CompactEvent::Rejected {
                    seq: Some(seq),
                    reason: Reject::Incomplete,
                };
            }
        } else if part < self.next_part {
            return CompactEvent::Ignored(Reject::Duplicate);
        } else if part > self.next_part || self.next_part == 0 {
            let seq = (self.next_part > 0).then(|| self.seq());
            self.clear();
            return CompactEvent::Rejected {
                seq,
                reason: Reject::OutOfOrder,
            };
        }
        self.store(start, bytes);
        self.next_part = part + 1;
        if self.next_part < compact_parts(flags, fd) {
            return CompactEvent::Pending;
        }
        self.clear();
        CompactEvent::Complete(Compact::decode_body(&self.body))
    }

    fn store(&mut self, start: usize, bytes: &[u8]) {
        for (d, s) in self.body.iter_mut().skip(start).zip(bytes) {
            *d = *s;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::quintic::Quintic;

    /// Two C3-joined segments of a quintic x(t) = Σ p_k t^k split at t = h0.
    fn pair(h0: f64, h1: f64) -> (WireSegment, WireSegment) {
        let p = [
            [0.31, 0.02, -0.4, 0.9, -0.6, 0.12],
            [0.2, 0.0, 0.3, -0.2, 0.05, 0.01],
            [0.35, -0.1, 0.0, 0.25, -0.3, 0.08],
        ];
        let shifted = |t0: f64| -> [[f64; 6]; 3] {
            p.map(|r| {
                core::array::from_fn(|m| {
                    (m..6)
                        .map(|k| r[k] * choose(k, m) * t0.powi((k - m) as i32))
                        .sum()
                })
            })
        };
        let a = Quintic {
            coeffs: shifted(0.0),
            duration: h0,
        };
        let b = Quintic {
            coeffs: shifted(h0),
            duration: h1,
        };
        (
            WireSegment::from_quintic(4, &a, 0).unwrap(),
            WireSegment::from_quintic(5, &b, FLAG_LAST).unwrap(),
        )
    }

    fn choose(k: usize, m: usize) -> f64 {
        (0..m).fold(1.0, |acc, i| acc * (k - i) as f64 / (i + 1) as f64)
    }

    #[test]
    fn a_continuation_rebuilds_its_segment_within_the_bound() {
        for (h0, h1) in [(0.25, 0.5), (0.002, 0.05), (0.6, 0.002), (0.1, 0.1)] {
            let (a, b) = pair(h0, h1);
            let (c, rebuilt) = Compact::continuing(&a.into(), &b, None, &DeviationBound::DEFAULT)
                .unwrap_or_else(|| panic!("{h0} {h1}: sent in full"));
            let got = c.reconstruct(&a.into(), a.body_crc()).unwrap();
            assert_eq!(got, rebuilt);
            let got = got.segment;
            let d = DeviationBound::between(&got, &b);
            assert!(d.within(&DeviationBound::DEFAULT), "{d:?}");
            // Positions agree with the plan's to the bound (checked pointwise).
            let (nb, ng) = (b.normalised_f64(), got.normalised_f64());
            for i in 0..=20 {
                let tau = i as f64 / 20.0;
                for j in 0..3 {
                    let ev = |c: &[f64; 6]| c.iter().rev().fold(0.0, |acc, x| acc * tau + x);
                    assert!((ev(&nb[j]) - ev(&ng[j])).abs() <= DeviationBound::DEFAULT.position);
                }
            }
        }
    }

    /// `n` C3-joined segments of one quintic, durations cycling through `h` (s).
    fn chain_of(n: usize, h: &[f64]) -> std::vec::Vec<WireSegment> {
        let total: f64 = (0..n).map(|i| h[i % h.len()]).sum();
        // A gentle quintic over the whole run (positions within ±0.4 m).
        let p = [
            [0.31, 0.02, -0.4, 0.9, -0.6, 0.12],
            [0.2, 0.0, 0.3, -0.2, 0.05, 0.01],
            [0.35, -0.1, 0.0, 0.25, -0.3, 0.08],
        ]
        .map(|r| core::array::from_fn::<f64, 6, _>(|k| r[k] / total.powi(k as i32)));
        let mut t0 = 0.0f64;
        (0..n)
            .map(|i| {
                let d = h[i % h.len()];
                let coeffs = p.map(|r| {
                    core::array::from_fn(|m| {
                        (m..6)
                            .map(|k| r[k] * choose(k, m) * t0.powi((k - m) as i32))
                            .sum()
                    })
                });
                t0 += d;
                let flags = if i + 1 == n { FLAG_LAST } else { 0 };
                WireSegment::from_quintic(
                    i as u16,
                    &Quintic {
                        coeffs,
                        duration: d,
                    },
                    flags,
                )
                .unwrap()
            })
            .collect()
    }

    #[test]
    fn continuations_correct_the_deviation_they_inherit() {
        // Without the correction (each b_4, b_5 the plan's rounded to
        // f32) a chain of 50 ms segments re-anchors about every 22nd.
        for h in [
            &[0.05][..],
            &[0.05, 0.05, 0.05, 0.002],
            &[0.03, 0.08, 0.011, 0.06],
            // 111 times longer before and after the short one.
            &[0.222, 0.222, 0.002],
        ] {
            let segs = chain_of(600, h);
            let mut held = Held::from(segs[0]);
            let mut worst = DeviationBound {
                position: 0.0,
                velocity: 0.0,
                acceleration: 0.0,
                jerk: 0.0,
            };
            for (i, next) in segs.iter().enumerate().skip(1) {
                let (c, rebuilt) =
                    Compact::continuing(&held, next, segs.get(i + 1), &DeviationBound::DEFAULT)
                        .unwrap_or_else(|| panic!("{h:?}: segment {i} sent in full"));
                assert_eq!(c.reconstruct(&held, held.segment.body_crc()), Ok(rebuilt));
                let d = DeviationBound::between(&rebuilt.segment, next);
                worst = DeviationBound {
                    position: worst.position.max(d.position),
                    velocity: worst.velocity.max(d.velocity),
                    acceleration: worst.acceleration.max(d.acceleration),
                    jerk: worst.jerk.max(d.jerk),
                };
                held = rebuilt;
            }
            std::eprintln!("{h:?}: all compact, {worst:?}");
            assert!(worst.within(&DeviationBound::DEFAULT), "{h:?}: {worst:?}");
            // Equal segments: far inside the bound, the deviation does not
            // accumulate. (After a 2 ms segment, a 50 ms one inherits its
            // end jerk to the unit, 7e-4 m/s³: up to 0.08 µm.)
            if h.len() == 1 {
                assert!(
                    worst.position < 0.1 * DeviationBound::DEFAULT.position,
                    "{worst:?}"
                );
            }
        }
    }

    #[test]
    fn mantissas_cover_the_coefficient_range_exactly() {
        // The largest coefficient a segment holds (±128 m) has an exponent.
        let top = (I48_MAX << FINE_BITS) as f64;
        let e = exponent_for(top).unwrap();
        assert!(e <= EXP_MAX);
        assert!(coefficient(MANTISSA_MAX as i32, e).is_some());
        assert_eq!(coefficient(MANTISSA_MAX as i32 + 1, 0), None);
        assert_eq!(coefficient(1, EXP_MAX + 1), None);
        assert_eq!(exponent_for(0.0), Some(0));
        assert_eq!(exponent_for(f64::NAN), None);
        assert_eq!(exponent_for(f64::INFINITY), None);
        for (v, e, want) in [
            (5i64, 1u8, 3i64),
            (-5, 1, -3),
            (4, 2, 1),
            (-6, 2, -2),
            (7, 0, 7),
        ] {
            assert_eq!(shift_round(v, e), want, "{v} {e}");
        }
        // Every field survives the wire: negative and extreme mantissas,
        // the largest exponent and duration, a pose.
        let c = Compact {
            seq: 0,
            duration_us: COMPACT_MAX_DURATION_US,
            flags: FLAG_AT_REST | FLAG_LAST as u8,
            exp: EXP_MAX,
            mantissas: [
                [MANTISSA_MAX as i32, -(MANTISSA_MAX as i32)],
                [-1, 0],
                [1, -4_000_000],
            ],
            pose: [I48_MAX, -I48_MAX, -1],
            crc: 0xDEAD_BEEF,
        };
        let (body, len) = c.encode_body();
        assert_eq!(len, COMPACT_MAX);
        assert_eq!(Compact::decode_body(&body), c);
        let c = Compact {
            flags: 0,
            pose: [0; 3],
            ..c
        };
        let (body, len) = c.encode_body();
        assert_eq!(len, COMPACT_LEN);
        assert_eq!(Compact::decode_body(&body), c);
    }

    #[test]
    fn scaling_rounds_alike_in_64_and_128_bits() {
        for (x, h, d) in [
            (7i128, 3i128, 2i128),
            (-7, 3, 2),
            (1 << 50, 60_000_000, 2_000),
            (-(1 << 51), 50_000, 49_999),
            (i64::MAX as i128 / 3, 3, 7),
        ] {
            let n = x * h;
            let want = (n + if n < 0 { -d / 2 } else { d / 2 }) / d;
            assert_eq!(scale_round(x, h, d), Some(want), "{x} {h} {d}");
        }
    }

    #[test]
    fn another_predecessor_is_refused() {
        let (a, b) = pair(0.25, 0.5);
        let (c, _) = Compact::continuing(&a.into(), &b, None, &DeviationBound::DEFAULT).unwrap();
        let mut other = a;
        other.coeffs[1][3] += 1;
        assert_eq!(
            c.reconstruct(&other.into(), other.body_crc()),
            Err(Reject::NoPredecessor)
        );
        let mut earlier = a;
        earlier.seq = 3;
        assert_eq!(
            c.reconstruct(&earlier.into(), a.body_crc()),
            Err(Reject::NoPredecessor)
        );
        // A flipped bit in the body is refused the same way.
        let mut bad = c;
        bad.mantissas[2][1] ^= 1;
        assert_eq!(
            bad.reconstruct(&a.into(), a.body_crc()),
            Err(Reject::NoPredecessor)
        );
    }

    #[test]
    fn a_segment_beyond_the_bound_is_sent_in_full() {
        // A long segment after a very short one sent in full: the short
        // one's integer coefficients fix its end jerk only to about
        // 3e-4 m/s³, which over the next 0.3 s moves the position by about
        // 1.5 µm. (After a short continuation the finer units fix it.)
        let (a, b) = pair(0.002, 0.3);
        assert!(Compact::continuing(&a.into(), &b, None, &DeviationBound::DEFAULT).is_none());
        let (a, mut b) = pair(0.25, 0.5);
        // A kink: the next segment does not start where `a` ends.
        b.coeffs[0][1] += 1_000_000;
        assert!(Compact::continuing(&a.into(), &b, None, &DeviationBound::DEFAULT).is_none());
    }

    /// A move from rest to rest on two segments: the first starts with
    /// velocity, acceleration and jerk 0, the second ends with velocity
    /// and acceleration 0.
    fn rest_to_rest() -> (WireSegment, WireSegment) {
        let (h0, h1) = (0.3f64, 0.2f64);
        // x(τ) on the first: x0 + b4 τ⁴ + b5 τ⁵ (normalised).
        let p0 = [0.31, 0.2, 0.35];
        let a45 = [[0.004, -0.0015], [-0.002, 0.0009], [0.001, 0.0]];
        let a: [[f64; 6]; 3] =
            core::array::from_fn(|j| [p0[j], 0.0, 0.0, 0.0, a45[j][0], a45[j][1]]);
        // The second continues it (its Taylor coefficients at the end, in
        // its normalisation) and ends with velocity and acceleration 0.
        let r = h1 / h0;
        let b: [[f64; 6]; 3] = core::array::from_fn(|j| {
            let mut c = [0.0; 6];
            for (m, cm) in c.iter_mut().take(4).enumerate() {
                *cm = (m..6).map(|k| choose(k, m) * a[j][k]).sum::<f64>() * r.powi(m as i32);
            }
            let v = c[1] + 2.0 * c[2] + 3.0 * c[3];
            let acc = 2.0 * c[2] + 6.0 * c[3];
            c[5] = (3.0 * v - acc) / 5.0;
            c[4] = (-v - 5.0 * c[5]) / 4.0;
            c
        });
        let quintic = |n: [[f64; 6]; 3], h: f64| Quintic {
            coeffs: n.map(|row| core::array::from_fn(|k| row[k] / h.powi(k as i32))),
            duration: h,
        };
        (
            WireSegment::from_quintic(0, &quintic(a, h0), FLAG_FIRST).unwrap(),
            WireSegment::from_quintic(1, &quintic(b, h1), FLAG_LAST).unwrap(),
        )
    }

    #[test]
    fn a_plan_s_first_segment_from_rest_is_sent_in_seven_classic_frames() {
        let (a, b) = rest_to_rest();
        for fd in [false, true] {
            let mut chain = Chain::default();
            let first = chain.next(&a, Some(&b));
            let last = chain.next(&b, None);
            let (f0, f1) = (first.frames(fd), last.frames(fd));
            assert_eq!(
                (f0.len(), f1.len()),
                if fd { (1, 1) } else { (7, 4) },
                "fd {fd}"
            );
            let mut rx = crate::protocol::SegmentRx::default();
            let mut got = std::vec::Vec::new();
            for f in f0.iter().chain(&f1) {
                let (msg, _) = crate::protocol::decode(f).unwrap();
                match rx.push(msg.kind(), f.payload()).unwrap() {
                    crate::protocol::SegmentEvent::Pending => {}
                    crate::protocol::SegmentEvent::Complete {
                        segment, pred_crc, ..
                    } => got.push((segment, pred_crc)),
                    e => panic!("{e:?}"),
                }
            }
            // The first is an anchor (no predecessor), the second continues it.
            assert_eq!(
                got,
                [
                    (*first.held(), None),
                    (*last.held(), Some(first.held().body_crc()))
                ]
            );
            for (held, plan) in [(first.held(), &a), (last.held(), &b)] {
                let d = DeviationBound::between(held, plan);
                assert!(d.within(&DeviationBound::DEFAULT), "{d:?}");
            }
            assert!(first.held().coeffs.iter().all(|r| r[1..4] == [0, 0, 0]));
        }
        // Not at rest: the first goes in full.
        let (c, d) = pair(0.25, 0.5);
        let mut c0 = c;
        c0.seq = 0;
        let mut d0 = d;
        d0.seq = 1;
        assert!(!Chain::default().next(&c0, Some(&d0)).is_compact());
        // A corrupted pose fails the CRC.
        let (mut x, _) = Compact::first(&a, Some(&b), &DeviationBound::DEFAULT).unwrap();
        x.pose[1] += 1;
        assert_eq!(x.from_rest(), Err(Reject::BadCrc));
    }

    #[test]
    fn parts_round_trip() {
        let (a, b) = pair(0.25, 0.5);
        let (c, _) = Compact::continuing(&a.into(), &b, None, &DeviationBound::DEFAULT).unwrap();
        for fd in [false, true] {
            let frames: heapless::Vec<Frame, 8> = c.frames(fd).collect();
            assert_eq!(frames.len(), if fd { 1 } else { 4 });
            assert_eq!(frames[0].payload().len(), if fd { FD_LEN } else { 8 });
            let mut r = CompactAssembler::default();
            let mut out = None;
            for (i, f) in frames.iter().enumerate() {
                match r.push(f.payload(), fd) {
                    CompactEvent::Pending => assert!(i + 1 < frames.len()),
                    CompactEvent::Complete(x) => out = Some(x),
                    e => panic!("{e:?}"),
                }
            }
            assert_eq!(out, Some(c));
        }
        // Out of order and duplicate parts.
        let frames: heapless::Vec<Frame, 8> = c.frames(false).collect();
        let mut r = CompactAssembler::default();
        assert_eq!(r.push(frames[0].payload(), false), CompactEvent::Pending);
        assert_eq!(
            r.push(frames[0].payload(), false),
            CompactEvent::Rejected {
                seq: Some(5),
                reason: Reject::Incomplete
            }
        );
        assert_eq!(r.push(frames[1].payload(), false), CompactEvent::Pending);
        assert_eq!(
            r.push(frames[1].payload(), false),
            CompactEvent::Ignored(Reject::Duplicate)
        );
        assert_eq!(
            r.push(frames[3].payload(), false),
            CompactEvent::Rejected {
                seq: Some(5),
                reason: Reject::OutOfOrder
            }
        );
        assert_eq!(
            r.push(frames[2].payload(), false),
            CompactEvent::Rejected {
                seq: None,
                reason: Reject::OutOfOrder
            }
        );
    }
}
