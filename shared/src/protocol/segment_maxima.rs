//! The exact largest |q′|, |q″|, |q‴| of a segment as the drives hold it
//! (f32, normalised time), and the stop ramps they need: one
//! implementation the drives run on every segment they accept and the host
//! runs over a plan (docs/protocol.md, "Stop ramp"), so the host's ramp is
//! never shorter than a drive's.

use super::WireSegment;
use super::stop_ramp::{budgets, pieces_ramp_and_units};

/// Bisection steps on u ∈ [0, 1]: f32's 24-bit mantissa.
const BISECT_STEPS: usize = 24;

/// 1/h (s⁻¹) of a segment of `duration_us` (0 for none).
pub fn inv_h(duration_us: u32) -> f32 {
    let h = duration_us as f32 * 1e-6;
    if h > 0.0 { 1.0 / h } else { 0.0 }
}

/// Σ c_k u^k by Horner's rule (`c` lowest power first).
fn poly(c: &[f32], u: f32) -> f32 {
    c.iter().rev().fold(0.0, |acc, x| acc * u + x)
}

/// The root of `c` in (lo, hi) where it changes sign there (monotone on
/// it: at most one), by bisection.
fn root_in(c: &[f32], lo: f32, hi: f32) -> Option<f32> {
    let (mut lo, mut hi) = (lo, hi);
    let (flo, fhi) = (poly(c, lo), poly(c, hi));
    if flo == 0.0 || fhi == 0.0 || (flo < 0.0) == (fhi < 0.0) {
        return None;
    }
    for _ in 0..BISECT_STEPS {
        let mid = 0.5 * (lo + hi);
        if (poly(c, mid) < 0.0) == (flo < 0.0) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    Some(0.5 * (lo + hi))
}

/// The roots in (0, 1) of `c`, given the points (sorted, 0 and 1
/// included) between which it is monotone, sorted and with 0 and 1: the
/// points between which its antiderivative is monotone. Returns how many.
// Out of line, as the stop ramp's helpers: one copy in the drives' flash,
// which has little room left.
#[inline(never)]
fn roots(c: &[f32], pieces: &[f32], out: &mut [f32; 6]) -> usize {
    let inner = pieces.windows(2).filter_map(|w| match *w {
        [lo, hi] => root_in(c, lo, hi),
        _ => None,
    });
    let mut n = 0;
    for x in core::iter::once(0.0)
        .chain(inner)
        .chain(core::iter::once(1.0))
    {
        if let Some(slot) = out.get_mut(n) {
            *slot = x;
            n += 1;
        }
    }
    n
}

/// Pieces of equal length each segment is split into for its stop ramps:
/// each joint's maxima on each piece bound the joint there.
pub const PIECES: usize = 4;

/// Each joint's largest |q′|, |q″|, |q‴| on each piece (joint-major).
pub type PieceMaxima = [[f32; 3]; 3 * PIECES];

/// Raises `out[p]` to the largest |c(u)| on each piece p: over the points
/// (0, 1 and the points between which c is monotone, sorted) and the
/// pieces' bounds, each bound counted on both sides.
fn largest_by_piece(c: &[f32], points: &[f32], out: &mut [f32; PIECES]) {
    let n = PIECES as f32;
    for u in points {
        let p = ((*u * n) as usize).min(PIECES - 1);
        if let Some(o) = out.get_mut(p) {
            raise(o, poly(c, *u).abs());
        }
    }
    for k in 1..PIECES {
        let x = poly(c, k as f32 / n).abs();
        for o in out.iter_mut().skip(k - 1).take(2) {
            raise(o, x);
        }
    }
}

/// `m` raised to `x` (a NaN `x` leaves it), inline where `f32::max` is
/// a library call on the drives.
fn raise(m: &mut f32, x: f32) {
    if x > *m {
        *m = x;
    }
}

/// Each joint's largest |q′|, |q″|, |q‴| (m/s, m/s², m/s³) on each of
/// [`PIECES`] equal pieces of a segment of normalised coefficients `b`
/// (u = t/h) and 1/h `inv_h`, exact up to f32 rounding: q‴ is a
/// quadratic, so q″ is monotone between q⁗'s root and the ends, q′
/// between q‴'s roots; on a piece each derivative peaks at one of its
/// ends or at a root of the next inside it.
pub fn piece_maxima(b: &[[f32; 6]; 3], inv_h: f32) -> PieceMaxima {
    let ih = inv_h;
    let mut out = [[0.0f32; 3]; 3 * PIECES];
    for (b, rows) in b.iter().zip(out.chunks_exact_mut(PIECES)) {
        let d1 = [b[1], 2.0 * b[2], 3.0 * b[3], 4.0 * b[4], 5.0 * b[5]];
        let d2 = [2.0 * b[2], 6.0 * b[3], 12.0 * b[4], 20.0 * b[5]];
        let d3 = [6.0 * b[3], 24.0 * b[4], 60.0 * b[5]];
        let d4 = [24.0 * b[4], 120.0 * b[5]];
        let (mut p4, mut p3, mut p2) = ([0.0; 6], [0.0; 6], [0.0; 6]);
        // `get` rather than slicing: no panic path on the receive side.
        let n4 = roots(&d4, &[0.0, 1.0], &mut p4);
        let p4 = p4.get(..n4).unwrap_or(&[]);
        let n3 = roots(&d3, p4, &mut p3);
        let p3 = p3.get(..n3).unwrap_or(&[]);
        let n2 = roots(&d2, p3, &mut p2);
        let p2 = p2.get(..n2).unwrap_or(&[]);
        let mut m = [[0.0f32; PIECES]; 3];
        let [m1, m2, m3] = &mut m;
        largest_by_piece(&d1, p2, m1);
        largest_by_piece(&d2, p3, m2);
        largest_by_piece(&d3, p4, m3);
        for (p, row) in rows.iter_mut().enumerate() {
            *row = [
                m1.get(p).map_or(0.0, |x| x * ih),
                m2.get(p).map_or(0.0, |x| x * ih * ih),
                m3.get(p).map_or(0.0, |x| x * ih * ih * ih),
            ];
        }
    }
    out
}

/// The largest of each column over the pieces: the segment's maxima.
#[inline(never)]
pub fn overall(pieces: &[[f32; 3]]) -> [f32; 3] {
    let mut m = [0.0f32; 3];
    for p in pieces {
        for (m, x) in m.iter_mut().zip(p) {
            raise(m, *x);
        }
    }
    m
}

/// Largest |q′|, |q″|, |q‴| (m/s, m/s², m/s³) over the three joints of a
/// segment ([`piece_maxima`] over all its pieces).
pub fn maxima(b: &[[f32; 6]; 3], inv_h: f32) -> [f32; 3] {
    overall(&piece_maxima(b, inv_h))
}

/// The controlled and quick stop ramps (s) of a segment with piece maxima
/// `pieces` on a drive with jerk limit `jerk_limit`, ceiling `ceiling`
/// and override cap `cap`: the budgets from the segment's own largest
/// |q‴|, the ramps over every joint's every piece
/// ([`pieces_ramp`](super::stop_ramp::pieces_ramp)).
pub fn piece_ramps(
    pieces: &PieceMaxima,
    jerk_limit: f32,
    ceiling: f32,
    cap: f32,
) -> Option<(f32, f32)> {
    piece_ramps_and_at_unit(pieces, jerk_limit, ceiling, cap, f32::INFINITY).map(|[full, _]| full)
}

/// Each piece's own ramps (controlled, quick; s) for a stop along the
/// path from σ ≤ 1, in plan order.
pub type PieceUnitRamps = [(f32, f32); PIECES];

/// [`piece_ramps`] and, from the same pass, each piece's own ramps for a
/// stop along the path from σ ≤ 1 (over its three joints' maxima there,
/// `stop_ramp::unit_ramp`, the joint acceleration within
/// `accel_ceiling`): what a stop carrying a ramp for the path ahead is held
/// to where it passes that piece. `(full, by piece)`, each (controlled,
/// quick).
pub fn piece_ramps_and_units(
    pieces: &PieceMaxima,
    jerk_limit: f32,
    ceiling: f32,
    cap: f32,
    accel_ceiling: f32,
) -> Option<((f32, f32), PieceUnitRamps)> {
    let j = overall(pieces)[2];
    let b = budgets(j, jerk_limit, ceiling, cap);
    let at = |p: usize| pieces.get(p).copied().unwrap_or_default();
    let group = |p: usize| [at(p), at(PIECES + p), at(2 * PIECES + p)];
    let ([s, q], units) = pieces_ramp_and_units::<PIECES>(pieces, group, b, cap, accel_ceiling)?;
    Some(((s, q), units.map(|[s, q]| (s, q))))
}

/// [`piece_ramps_and_units`] with the segment's own ramps for a stop
/// along the path from σ ≤ 1: the largest over its pieces. `[full,
/// at_unit]`.
pub fn piece_ramps_and_at_unit(
    pieces: &PieceMaxima,
    jerk_limit: f32,
    ceiling: f32,
    cap: f32,
    accel_ceiling: f32,
) -> Option<[(f32, f32); 2]> {
    let (full, units) = piece_ramps_and_units(pieces, jerk_limit, ceiling, cap, accel_ceiling)?;
    Some([full, largest_unit(&units)])
}

/// The largest of `units` (controlled, quick).
pub fn largest_unit(units: &[(f32, f32)]) -> (f32, f32) {
    let mut m = (0.0f32, 0.0f32);
    for &(s, q) in units {
        raise(&mut m.0, s);
        raise(&mut m.1, q);
    }
    m
}

/// The controlled and quick stop ramps (s) a drive sizes for the wire
/// segment `w` on receipt ([`piece_ramps`] over its own piece maxima), with
/// jerk limit `jerk_limit`, ceiling `ceiling` and override cap `cap`;
/// `None` if a drive would refuse it for its stop.
pub fn wire_ramps(w: &WireSegment, jerk_limit: f32, ceiling: f32, cap: f32) -> Option<(f32, f32)> {
    wire_ramps_and_at_unit(w, jerk_limit, ceiling, cap, f32::INFINITY).map(|[full, _]| full)
}

/// [`wire_ramps`] and, from the same pass, the segment's own ramps for a
/// stop along the path from σ ≤ 1 (its joint acceleration within
/// `accel_ceiling`), as a drive computes them for it
/// ([`piece_ramps_and_at_unit`]). `[full, at_unit]`.
pub fn wire_ramps_and_at_unit(
    w: &WireSegment,
    jerk_limit: f32,
    ceiling: f32,
    cap: f32,
    accel_ceiling: f32,
) -> Option<[(f32, f32); 2]> {
    let pieces = piece_maxima(&w.normalised_f32(), inv_h(w.duration_us));
    piece_ramps_and_at_unit(&pieces, jerk_limit, ceiling, cap, accel_ceiling)
}

/// [`piece_ramps_and_units`] of the wire segment `w`, as a drive computes
/// them for it.
pub fn wire_ramps_and_units(
    w: &WireSegment,
    jerk_limit: f32,
    ceiling: f32,
    cap: f32,
    accel_ceiling: f32,
) -> Option<((f32, f32), PieceUnitRamps)> {
    let pieces = piece_maxima(&w.normalised_f32(), inv_h(w.duration_us));
    piece_ramps_and_units(&pieces, jerk_limit, ceiling, cap, accel_ceiling)
}

/// The controlled and quick stop ramps (s) the drives need for the whole
/// of `segments` (the largest of each segment's own,
/// [`wire_ramps`]) with jerk limit `jerk_limit`, ceiling `ceiling` and
/// override cap `cap`; `None` if a drive would refuse a segment for it.
pub fn plan_ramps<'a>(
    segments: impl IntoIterator<Item = &'a WireSegment>,
    jerk_limit: f32,
    ceiling: f32,
    cap: f32,
) -> Option<(f32, f32)> {
    let mut out = (0.0f32, 0.0f32);
    for w in segments {
        let (s, q) = wire_ramps(w, jerk_limit, ceiling, cap)?;
        out = (out.0.max(s), out.1.max(q));
    }
    Some(out)
}

/// What the host configures for `plan` on drives with `settings`: the
/// override cap (`cap`, the plan's own, lowered where the drives' jerk
/// ceiling C leaves a stop from it less than J/2 of room: j·cap³ ≤ C − J/2,
/// never below 1) and the controlled and quick stop ramps (s) for it,
/// [`plan_ramps`] over its wire segments with the jerk limit and ceiling
/// each drive holds (the same f32 values `DriveConfig::new` writes).
/// When a segment cannot be sent or a drive would refuse one for its stop,
/// `plan_wide` (the cap and ramps from the plan's own limits): the drives
/// then refuse the segment themselves, whatever the host configured.
#[cfg(feature = "alloc")]
pub fn for_plan(
    plan: &crate::plan::Plan,
    settings: &super::DriveSettings,
    plan_wide: &crate::plan::override_cap::Scaling,
) -> PlanRamps {
    sized(plan, settings, plan_wide.cap).unwrap_or(PlanRamps {
        cap: plan_wide.cap,
        stop_time_s: plan_wide.stop_time_s,
        quick_stop_time_s: plan_wide.quick_stop_time_s,
    })
}

#[cfg(feature = "alloc")]
fn sized(plan: &crate::plan::Plan, settings: &super::DriveSettings, cap: f64) -> Option<PlanRamps> {
    let w = plan.wire_segments().ok()?;
    let c = settings.ceilings.jerk;
    let jl = plan.limits.jerk.min(c);
    let j = w
        .iter()
        .map(|w| maxima(&w.normalised_f32(), inv_h(w.duration_us))[2] as f64)
        .fold(0.0, f64::max);
    let room_cap = if j > 0.0 {
        libm::floor(libm::cbrt((c - 0.5 * jl).max(0.0) / j) * 1000.0) / 1000.0
    } else {
        cap
    };
    let cap = cap.min(room_cap).max(1.0);
    let (s, q) = plan_ramps(&w, jl as f32, c as f32, cap as f32)?;
    Some(PlanRamps {
        cap,
        stop_time_s: s as f64,
        quick_stop_time_s: q as f64,
    })
}

/// The override cap and stop ramps the host configures ([`for_plan`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlanRamps {
    pub cap: f64,
    pub stop_time_s: f64,
    pub quick_stop_time_s: f64,
}
