//! The exact largest |q′|, |q″|, |q‴| of a segment as the drives hold it
//! (f32, normalised time), and the stop ramps they need: one
//! implementation the drives run on every segment they accept and the host
//! runs over a plan (docs/protocol.md, "Stop ramp"), so the host's ramp is
//! never shorter than a drive's.

use super::WireSegment;
use super::stop_ramp::{segment_ramps, segment_ramps_and_at_unit};

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

/// Largest |c(u)| over the points.
fn largest(c: &[f32], points: &[f32]) -> f32 {
    points.iter().fold(0.0f32, |m, u| m.max(poly(c, *u).abs()))
}

/// Largest |q′|, |q″|, |q‴| (m/s, m/s², m/s³) over the three joints of a
/// segment of normalised coefficients `b` (u = t/h) and 1/h `inv_h`, exact
/// up to f32 rounding: q‴ is a quadratic, so q″ is monotone between q⁗'s
/// root and the ends, q′ between q‴'s roots; each derivative peaks at an
/// end or at a root of the next.
pub fn maxima(b: &[[f32; 6]; 3], inv_h: f32) -> [f32; 3] {
    let ih = inv_h;
    let mut m = [0.0f32; 3];
    for b in b {
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
        m[0] = m[0].max(largest(&d1, p2));
        m[1] = m[1].max(largest(&d2, p3));
        m[2] = m[2].max(largest(&d3, p4));
    }
    [m[0] * ih, m[1] * ih * ih, m[2] * ih * ih * ih]
}

/// The controlled and quick stop ramps (s) a drive sizes for the wire
/// segment `w` on receipt ([`segment_ramps`] over its own maxima), with
/// jerk limit `jerk_limit`, ceiling `ceiling` and override cap `cap`;
/// `None` if a drive would refuse it for its stop.
pub fn wire_ramps(w: &WireSegment, jerk_limit: f32, ceiling: f32, cap: f32) -> Option<(f32, f32)> {
    let [v, a, j] = maxima(&w.normalised_f32(), inv_h(w.duration_us));
    segment_ramps(v, a, j, jerk_limit, ceiling, cap)
}

/// A wire segment's own ramps for a stop from σ ≤ 1 (controlled, quick;
/// s), as a drive computes them for it (`segment_ramps_and_at_unit`).
pub fn wire_stop_ramps_at_unit(
    w: &WireSegment,
    jerk_limit: f32,
    ceiling: f32,
    cap: f32,
) -> Option<(f32, f32)> {
    let [v, a, j] = maxima(&w.normalised_f32(), inv_h(w.duration_us));
    segment_ramps_and_at_unit(v, a, j, jerk_limit, ceiling, cap).map(|(_, at_unit)| at_unit)
}

/// The controlled and quick stop ramps (s) the drives need for the whole
/// of `segments` (the largest of each segment's own,
/// [`segment_ramps`]) with jerk limit `jerk_limit`, ceiling `ceiling` and
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
