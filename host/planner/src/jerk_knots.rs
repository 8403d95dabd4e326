//! Free knots for min-max-jerk (`knots = "free"` with that objective): a
//! knot added inside every segment of the fixed-knot optimum, the times and
//! every knot's velocity and acceleration chosen again to lower the max
//! jerk at the job's total time.
//!
//! The start is the fixed-knot plan itself, each segment split where its
//! time is halved (whole microseconds): the same motion, so the same jerk.
//! From there the trust-region search over the intervals and knot
//! derivatives (the added knots' velocities and accelerations are the new
//! freedom, jerk continuity taking half of it) lowers the max jerk. The
//! added knots' positions are where the fixed optimum passes at the split:
//! a coordinate search over them at the new intervals, each move judged by
//! the exact inner optimum, gained under 1e-6 of the jerk on the paper's
//! cases for ten times the time, and is not done (docs/planner.md). The
//! via-points stay knots, never moved. The result is rounded to whole
//! microseconds as any min-max-jerk plan; `planning` keeps it only when
//! its jerk is below the fixed knots'.

use triquint_shared::quintic::eval_poly;

use crate::problem::{Problem, Solution};
use crate::rounding::round_within;
use crate::spline::Knots;

/// Shortest segment split (s): each half keeps the 5 ms a free knot's
/// segment has at least (`free_knots.rs`).
const SPLIT_AT_LEAST: f64 = 10e-3;
/// Trust-region iterations, and the relative tolerance that ends them.
const LOCAL_ITER: usize = 40;
const LOCAL_TOL: f64 = 1e-6;

/// The fixed-knot problem `p` with a knot inside every segment of its
/// solution `s` that lasts at least [`SPLIT_AT_LEAST`], at the segment's
/// half time: the problem, the same motion's knot derivatives and
/// intervals there, and the added knots' indices.
fn split(p: &Problem, s: &Solution) -> (Problem, [Vec<f64>; 3], Vec<f64>, Vec<usize>) {
    let n = p.knots.len();
    let mut q = vec![p.knots.q[0]];
    let mut h = Vec::new();
    // Per knot after the first: (velocity, acceleration) per joint.
    let mut va: Vec<[[f64; 2]; 3]> = Vec::new();
    let mut added = Vec::new();
    for k in 0..n - 1 {
        let hk = s.h[k];
        let coeffs = [0, 1, 2].map(|j| p.knots.coefficients(&s.x[j], j, k, hk));
        if hk >= SPLIT_AT_LEAST {
            let first = ((hk * 1e6).round() as i64 / 2) as f64 * 1e-6;
            let at = coeffs.map(|c| eval_poly(&c, first));
            added.push(q.len());
            q.push(at.map(|d| d[0]));
            va.push(at.map(|d| [d[1], d[2]]));
            h.push(first);
            h.push(hk - first);
        } else {
            h.push(hk);
        }
        let end = coeffs.map(|c| eval_poly(&c, hk));
        q.push(p.knots.q[k + 1]);
        va.push(end.map(|d| [d[1], d[2]]));
    }
    let interior = &va[..va.len() - 1];
    let x = [0, 1, 2].map(|j| {
        interior
            .iter()
            .map(|d| d[j][0])
            .chain(interior.iter().map(|d| d[j][1]))
            .collect::<Vec<f64>>()
    });
    let mut split = p.clone();
    split.knots = Knots { q };
    (split, x, h, added)
}

/// The min-max-jerk plan at free knots from the fixed-knot one `s` of
/// `p`, in whole microseconds within `total_time` and meeting every limit,
/// with the added knots' indices; None when no segment is long enough to
/// split or the rounded plan fails a limit.
pub(crate) fn jerk_knots(
    p: &Problem,
    s: &Solution,
    total_time: f64,
) -> Option<(Problem, Solution, Vec<usize>)> {
    let (q, x, h, added) = split(p, s);
    if added.is_empty() {
        return None;
    }
    let start = q.evaluate(&h, &x);
    let moved = q.local_search(&start, LOCAL_ITER, LOCAL_TOL);
    let best = if moved.merit(q.weight) < start.merit(q.weight) {
        moved
    } else {
        start
    };
    let rounded = round_within(&q, &best, total_time)?;
    Some((q, rounded, added))
}
