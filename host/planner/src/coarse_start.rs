//! Starts for a long path from a coarser one: every `STRIDE`-th knot is
//! planned first (itself from a coarser one while it is long), and the
//! coarse optimum's time law is carried to the fine knots along the fine
//! path's chord length. The fine search then only refines: on a long path
//! a start far from the optimum (the rest ends want intervals several
//! times the others') costs dozens of trust-region steps at the full size,
//! while the coarse path's steps cost a quarter as much.
//!
//! A long path its coarser path does not trace (a random walk, which turns
//! between every few via-points) is started from overlapping windows of
//! itself instead ([`window_start`]): each window's near-optimum, its
//! middle kept, every window time-scaled to one max jerk.

use crate::extrema::max_abs_on_interval;
use crate::problem::{Problem, Solution};
use crate::spline::Knots;
use crate::time_scaling::within_bounds;

/// Paths of more knots than this are started from a coarser one.
pub(crate) const COARSE_ABOVE_KNOTS: usize = 64;
/// Every this many knots are kept in the coarser path.
const STRIDE: usize = 4;
/// Samples of a coarse segment's arc length.
const SAMPLES: usize = 256;
/// The coarse path stands for the fine one when the fine path is at most
/// this much longer (in joint space): its corners are resolved. A path
/// that turns between every few via-points (a random walk) is started
/// from its windows ([`window_start`]).
const RESOLVED_LENGTH: f64 = 1.05;
/// Starts closer than this (relative, in every interval) are one.
const SAME_START: f64 = 1e-6;

/// The fine knots the coarse path keeps: every `STRIDE`-th and the last
/// (a remainder under half a stride joins the segment before it).
fn kept(n: usize) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..n).step_by(STRIDE).collect();
    let last = n - 1;
    if let Some(&l) = idx.last()
        && l != last
    {
        if last - l < STRIDE / 2 && idx.len() > 1 {
            idx.pop();
        }
        idx.push(last);
    }
    idx
}

/// Interval starts for the jerk-only problem `p` (at its total time) from
/// the optimum shapes of its coarser path, brought within its interval
/// bounds, best first and distinct, and the LP solves they took. `search`
/// gives a path's optimum shapes, best first, and its LP solves (the
/// relaxation's global search). None for a path of at most
/// [`COARSE_ABOVE_KNOTS`] knots, one its coarse path does not resolve, or
/// when the coarse search fails.
pub(crate) fn coarse_starts(
    p: &Problem,
    search: impl Fn(&Problem) -> Option<(Vec<Solution>, u64)>,
) -> Option<(Vec<Vec<f64>>, u64)> {
    if p.knots.len() <= COARSE_ABOVE_KNOTS {
        return None;
    }
    let idx = kept(p.knots.len());
    let coarse_q: Vec<[f64; 3]> = idx.iter().map(|&i| p.knots.q[i]).collect();
    if length(&p.knots.q) > RESOLVED_LENGTH * length(&coarse_q) {
        return None;
    }
    let coarse = Problem {
        knots: Knots { q: coarse_q },
        // A coarse segment spans several fine ones.
        h_max: f64::INFINITY,
        shown_jerk: None,
        ..p.relaxed()
    };
    let (shapes, solves) = search(&coarse)?;
    let mut starts: Vec<Vec<f64>> = Vec::new();
    for s in &shapes {
        let mut h = fine_intervals(&p.knots, &coarse.knots, &idx, &s.h, &s.x, p.h_min);
        // The coarse problem's intervals are not bounded above.
        within_bounds(&mut h, p.h_min, p.h_max);
        let same = |t: &Vec<f64>| {
            t.iter()
                .zip(&h)
                .all(|(a, b)| (a - b).abs() <= SAME_START * a.abs())
        };
        if !starts.iter().any(same) {
            starts.push(h);
        }
    }
    (!starts.is_empty()).then_some((starts, solves))
}

/// The fine intervals of the coarse plan (`h`, `x` on `coarse`, whose knot
/// i is fine knot `idx[i]`): each fine knot is placed at the time the
/// coarse trajectory has covered the same share of its segment's joint
/// space arc length as the fine path's chords have of theirs.
fn fine_intervals(
    fine: &Knots,
    coarse: &Knots,
    idx: &[usize],
    h: &[f64],
    x: &[Vec<f64>; 3],
    h_min: f64,
) -> Vec<f64> {
    let mut out = Vec::with_capacity(fine.segments());
    for (i, w) in idx.windows(2).enumerate() {
        let (a, b) = (w[0], w[1]);
        let big = h[i];
        let c: [[f64; 6]; 3] = std::array::from_fn(|j| coarse.coefficients(&x[j], j, i, big));
        let at = |t: f64| -> [f64; 3] {
            std::array::from_fn(|j| c[j].iter().rev().fold(0.0, |acc, &ck| acc * t + ck))
        };
        // Arc length of the coarse segment at SAMPLES + 1 instants.
        let mut arc = vec![0.0; SAMPLES + 1];
        let mut prev = at(0.0);
        for l in 1..=SAMPLES {
            let q = at(big * l as f64 / SAMPLES as f64);
            arc[l] = arc[l - 1] + dist(&prev, &q);
            prev = q;
        }
        let chords: Vec<f64> = (a..b).map(|k| dist(&fine.q[k], &fine.q[k + 1])).collect();
        let total: f64 = chords.iter().sum();
        let mut times = Vec::with_capacity(b - a + 1);
        times.push(0.0);
        let mut covered = 0.0;
        for d in &chords[..chords.len() - 1] {
            covered += d;
            let t = if total > 0.0 && arc[SAMPLES] > 0.0 {
                time_at(&arc, covered / total * arc[SAMPLES]) * big
            } else {
                big * (times.len() as f64) / (b - a) as f64
            };
            times.push(t);
        }
        times.push(big);
        // No interval collapses: at least a thousandth of an even share
        // and the shortest interval.
        let floor = (1e-3 * big / (b - a) as f64).max(h_min);
        let seg: Vec<f64> = times.windows(2).map(|t| (t[1] - t[0]).max(floor)).collect();
        let sum: f64 = seg.iter().sum();
        out.extend(seg.iter().map(|s| s * big / sum));
    }
    out
}

/// The length of the polyline through `q`.
fn length(q: &[[f64; 3]]) -> f64 {
    q.windows(2).map(|w| dist(&w[0], &w[1])).sum()
}

fn dist(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(p, q)| (p - q) * (p - q))
        .sum::<f64>()
        .sqrt()
}

/// The normalised time (0..1) at which the sampled arc length `arc`
/// (nondecreasing) reaches `s`, interpolated linearly.
fn time_at(arc: &[f64], s: f64) -> f64 {
    let n = arc.len() - 1;
    let l = arc.partition_point(|&a| a < s).clamp(1, n);
    let (a0, a1) = (arc[l - 1], arc[l]);
    let frac = if a1 > a0 { (s - a0) / (a1 - a0) } else { 0.0 };
    ((l - 1) as f64 + frac.clamp(0.0, 1.0)) / n as f64
}

/// Segments of a window of a long path its coarser path does not resolve.
const WINDOW_SEGMENTS: usize = 48;
/// Segments at each end of a window that only shield its middle from its
/// artificial rest ends.
const WINDOW_MARGIN: usize = 8;

/// A start for the jerk-only problem `p` (a long path that its coarser
/// path does not resolve) from overlapping windows of it: each window's
/// near-optimum (`search_all` gives them, in the windows' order), the
/// middle of each kept, every window time-scaled so that all reach one
/// max jerk and together the total time. None for a path of at most
/// [`COARSE_ABOVE_KNOTS`] knots or when a window's search fails.
pub(crate) fn window_start(
    p: &Problem,
    search_all: impl FnOnce(&[Problem]) -> Vec<Option<Solution>>,
) -> Option<(Vec<Vec<f64>>, u64)> {
    let nseg = p.knots.segments();
    if p.knots.len() <= COARSE_ABOVE_KNOTS || nseg < WINDOW_SEGMENTS {
        return None;
    }
    let stride = WINDOW_SEGMENTS - 2 * WINDOW_MARGIN;
    let mut firsts: Vec<usize> = (0..)
        .map(|i| i * stride)
        .take_while(|&a| a + WINDOW_SEGMENTS < nseg)
        .collect();
    firsts.push(nseg - WINDOW_SEGMENTS);
    firsts.dedup();
    let windows: Vec<Problem> = firsts
        .iter()
        .map(|&a| Problem {
            knots: Knots {
                q: p.knots.q[a..=a + WINDOW_SEGMENTS].to_vec(),
            },
            total_time: p.total_time * WINDOW_SEGMENTS as f64 / nseg as f64,
            h_max: f64::INFINITY,
            shown_jerk: None,
            ..p.relaxed()
        })
        .collect();
    let solved = search_all(&windows);
    if solved.len() != windows.len() {
        return None;
    }
    let solved: Vec<Solution> = solved.into_iter().collect::<Option<_>>()?;
    let solves = solved.iter().map(|s| s.lp_solves).sum();
    // Each window keeps its segments up to the middle of its overlap with the next.
    let mut parts: Vec<(Vec<f64>, f64)> = Vec::with_capacity(windows.len());
    for (i, (&a, s)) in firsts.iter().zip(&solved).enumerate() {
        let lo = if i == 0 {
            0
        } else {
            (firsts[i - 1] + WINDOW_SEGMENTS + a) / 2
        };
        let hi = firsts
            .get(i + 1)
            .map_or(nseg, |&b| (a + WINDOW_SEGMENTS + b) / 2);
        let w = &windows[i];
        let jerk = (lo..hi)
            .map(|k| {
                let l = k - a;
                (0..3)
                    .map(|j| segment_jerk(&w.knots.coefficients(&s.x[j], j, l, s.h[l]), s.h[l]))
                    .fold(0.0, f64::max)
            })
            .fold(0.0, f64::max);
        parts.push((s.h[lo - a..hi - a].to_vec(), jerk));
    }
    // One max jerk J for all: a window's time law scaled by c stays its
    // shape, its jerk divided by c³.
    let cbrt_j: f64 = parts
        .iter()
        .map(|(h, j)| h.iter().sum::<f64>() * j.cbrt())
        .sum::<f64>()
        / p.total_time;
    if !(cbrt_j > 0.0 && cbrt_j.is_finite()) {
        return None;
    }
    let mut h: Vec<f64> = parts
        .iter()
        .flat_map(|(h, j)| {
            let c = (j.cbrt() / cbrt_j).max(1e-3);
            h.iter().map(move |x| x * c)
        })
        .collect();
    let sum: f64 = h.iter().sum();
    h.iter_mut().for_each(|x| *x *= p.total_time / sum);
    within_bounds(&mut h, p.h_min, p.h_max);
    (h.len() == nseg).then_some((vec![h], solves))
}

/// Max |jerk| over [0, h] of the quintic with power coefficients `c`.
fn segment_jerk(c: &[f64; 6], h: f64) -> f64 {
    max_abs_on_interval(&[6.0 * c[3], 24.0 * c[4], 60.0 * c[5]], 0.0, h)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_coarse_path_keeps_both_ends_and_every_stride() {
        assert_eq!(kept(9), vec![0, 4, 8]);
        assert_eq!(kept(10), vec![0, 4, 9]);
        assert_eq!(kept(11), vec![0, 4, 8, 10]);
        assert_eq!(kept(100).len(), 26);
        for n in 3..200 {
            let k = kept(n);
            assert_eq!((k[0], *k.last().unwrap()), (0, n - 1));
            assert!(
                k.windows(2)
                    .all(|w| w[1] > w[0] && w[1] - w[0] < 2 * STRIDE)
            );
        }
    }

    #[test]
    fn time_at_inverts_the_arc_length() {
        let arc: Vec<f64> = (0..=100).map(|l| (l as f64 / 100.0).powi(3)).collect();
        for s in [0.0, 0.001, 0.125, 0.5, 0.9, 1.0] {
            let t = time_at(&arc, s);
            assert!((t.powi(3) - s).abs() < 2e-3, "{s}: {t}");
        }
    }
}
