//! Evaluating a plan at a plan time: which segment is running, the joints'
//! motion, and an evenly spaced sampling that always ends on the end time.
//!
//! [`Plan::duration`](super::Plan::duration), [`Plan::segment_at`](super::Plan::segment_at),
//! [`Plan::at`](super::Plan::at) and [`Plan::sample`](super::Plan::sample) are
//! the usual entry points; the functions here do the same on bare consecutive
//! segments (for example segments as a drive received them off the wire, with
//! no plan file around them).
//!
//! Conventions, the same everywhere:
//! - Plan time runs from 0 to the duration, the sum of the segments' durations.
//! - A segment covers [t0, t0 + h); at a knot the later segment runs, and the
//!   end time belongs to the last segment.
//! - Outside [0, duration] the joints are held at rest (zero velocity,
//!   acceleration and jerk) at the start or end position.
//! - No segments, or a NaN time, give `None`: there is no motion to report,
//!   and nothing here panics.

use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

use super::Segment;
use crate::quintic::JointMotion;

/// Position (m), velocity (m/s), acceleration (m/s²) and jerk (m/s³) of the
/// three joints at one instant.
///
/// The motor torques and the platform position at that instant come from
/// [`dynamics::state_torque`](crate::dynamics::state_torque) and
/// [`kinematics::platform_position`](crate::kinematics::platform_position):
///
/// ```
/// use triquint_shared::plan::{JointState, Segment, eval};
/// use triquint_shared::{KinematicsError, Robot, dynamics, kinematics};
///
/// let m = Robot::default().model::<f64>();
/// // All sliders from 0.3 m up at 0.1 m/s for 1 s: the platform rises with them.
/// let segs = [Segment { t0_s: 0.0, duration_s: 1.0, coeffs: [[0.3, 0.1, 0.0, 0.0, 0.0, 0.0]; 3] }];
/// let (s0, s1) = (eval::at(&segs, 0.0).unwrap(), eval::at(&segs, 1.0).unwrap());
/// let (r0, r1) = (kinematics::platform_position(&m, s0.q)?, kinematics::platform_position(&m, s1.q)?);
/// assert!((r1 - r0 - nalgebra::Vector3::new(0.0, 0.0, 0.1)).norm() < 1e-12);
/// let tau = dynamics::state_torque(&m, s0)?;
/// assert!(tau.iter().all(|t| *t > 0.0));
/// # Ok::<(), KinematicsError>(())
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointState {
    pub q: [f64; 3],
    pub v: [f64; 3],
    pub a: [f64; 3],
    pub jerk: [f64; 3],
}

impl JointState {
    /// Standing still at `q`: velocity, acceleration and jerk zero.
    ///
    /// ```
    /// use triquint_shared::plan::JointState;
    /// let s = JointState::at_rest([0.1, 0.2, 0.3]);
    /// assert_eq!(s.q, [0.1, 0.2, 0.3]);
    /// assert_eq!((s.v, s.a, s.jerk), ([0.0; 3], [0.0; 3], [0.0; 3]));
    /// ```
    pub fn at_rest(q: [f64; 3]) -> Self {
        Self {
            q,
            ..Self::default()
        }
    }

    /// The same state as the vectors the kinematics and dynamics take.
    pub fn motion(&self) -> JointMotion<f64> {
        JointMotion {
            q: Vector3::from(self.q),
            qd: Vector3::from(self.v),
            qdd: Vector3::from(self.a),
            qddd: Vector3::from(self.jerk),
        }
    }
}

impl From<JointMotion<f64>> for JointState {
    fn from(m: JointMotion<f64>) -> Self {
        Self {
            q: m.q.into(),
            v: m.qd.into(),
            a: m.qdd.into(),
            jerk: m.qddd.into(),
        }
    }
}

impl From<JointState> for JointMotion<f64> {
    fn from(s: JointState) -> Self {
        s.motion()
    }
}

/// Most samples [`sample`] hands out: 2²⁴ (16 777 216), 4.6 h at a 1 ms step
/// or 168 s at 10 µs. A step that would need more is refused rather than
/// enlarged, so a sample's time is always a whole multiple of the step asked for.
pub const MAX_SAMPLES: u64 = 1 << 24;

/// Why [`sample`] cannot sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SampleError {
    /// The step is zero, negative, NaN or infinite.
    #[error("sample step must be a finite positive number of seconds")]
    InvalidStep,
    /// The segments' total duration is negative, NaN or infinite.
    #[error("plan duration is not a finite non-negative number of seconds")]
    InvalidDuration,
    /// The step is so small the plan would take more than [`MAX_SAMPLES`] samples.
    #[error("sample step too small: more than {MAX_SAMPLES} samples")]
    TooManySamples,
}

/// Total duration (s) of consecutive segments: the sum of their durations
/// (0 for none).
///
/// ```
/// use triquint_shared::plan::{Segment, eval};
/// let seg = |t0_s, duration_s| Segment { t0_s, duration_s, coeffs: [[0.0; 6]; 3] };
/// assert_eq!(eval::duration(&[seg(0.0, 0.5), seg(0.5, 0.25)]), 0.75);
/// assert_eq!(eval::duration(&[]), 0.0);
/// ```
pub fn duration(segments: &[Segment]) -> f64 {
    segments.iter().map(|s| s.duration_s).sum()
}

/// The segment running at time `t` (s) and its index: the last segment with
/// t0 ≤ t, found by binary search on t0 (so at a knot, the later segment;
/// at `t == duration`, the last one). `None` for no segments, a NaN `t`, or
/// `t` outside [0, [`duration`]].
///
/// ```
/// use triquint_shared::plan::{Segment, eval};
/// let seg = |t0_s, duration_s| Segment { t0_s, duration_s, coeffs: [[0.0; 6]; 3] };
/// let segs = [seg(0.0, 0.5), seg(0.5, 0.5)];
/// assert_eq!(eval::segment_at(&segs, 0.2).map(|(i, _)| i), Some(0));
/// assert_eq!(eval::segment_at(&segs, 0.5).map(|(i, _)| i), Some(1));
/// assert_eq!(eval::segment_at(&segs, 1.0).map(|(i, _)| i), Some(1));
/// assert!(eval::segment_at(&segs, 1.5).is_none());
/// assert!(eval::segment_at(&segs, f64::NAN).is_none());
/// ```
pub fn segment_at(segments: &[Segment], t: f64) -> Option<(usize, &Segment)> {
    segment_at_within(segments, duration(segments), t)
}

/// [`segment_at`] with the segments' [`duration`] already known: a caller
/// that evaluates many times pays its sum once, not at every call.
pub fn segment_at_within(segments: &[Segment], duration: f64, t: f64) -> Option<(usize, &Segment)> {
    // `!(a <= b)` also rejects NaN, in `t` or in the duration.
    if !(0.0 <= t && t <= duration) {
        return None;
    }
    let i = segments.partition_point(|s| s.t0_s <= t).saturating_sub(1);
    segments.get(i).map(|s| (i, s))
}

/// The joints' motion at time `t` (s) along consecutive segments, by the
/// quintic of the segment running at `t` ([`segment_at`]). Before 0 the
/// joints rest at the start position, after the end at the end position
/// (±∞ included). `None` for no segments or a NaN `t`.
///
/// ```
/// use triquint_shared::plan::{Segment, eval};
/// // q = 0.1 + 0.2 t on every joint for 1 s.
/// let segs = [Segment { t0_s: 0.0, duration_s: 1.0, coeffs: [[0.1, 0.2, 0.0, 0.0, 0.0, 0.0]; 3] }];
/// let s = eval::at(&segs, 0.5).unwrap();
/// assert!((s.q[0] - 0.2).abs() < 1e-12 && s.v[0] == 0.2);
/// let after = eval::at(&segs, 7.0).unwrap();
/// assert!((after.q[2] - 0.3).abs() < 1e-12 && after.v == [0.0; 3]);
/// assert!(eval::at(&segs, f64::NAN).is_none());
/// assert!(eval::at(&[], 0.0).is_none());
/// ```
pub fn at(segments: &[Segment], t: f64) -> Option<JointState> {
    at_within(segments, duration(segments), t)
}

/// [`at`] with the segments' [`duration`] already known (as
/// [`segment_at_within`]).
pub fn at_within(segments: &[Segment], duration: f64, t: f64) -> Option<JointState> {
    if t.is_nan() {
        return None;
    }
    let (first, last) = (segments.first()?, segments.last()?);
    if t < 0.0 {
        return Some(JointState::at_rest(first.quintic().eval(0.0).q.into()));
    }
    match segment_at_within(segments, duration, t) {
        Some((_, s)) => Some(s.quintic().eval(t - s.t0_s).into()),
        None => Some(JointState::at_rest(last.quintic().end().q.into())),
    }
}

/// Samples at times 0, dt, 2dt, … before the end and then at the end time
/// exactly (so even a plan shorter than `dt` gives its start and its end).
/// A grid time within dt·10⁻⁹ of the end is left out in favour of the end
/// itself, so no two samples nearly coincide. Times are k·dt, not a running
/// sum, so they do not drift. No segments give no samples.
///
/// Errors for a step that is not finite and positive, a duration that is not
/// finite and non-negative, or more than [`MAX_SAMPLES`] samples.
///
/// ```
/// use triquint_shared::plan::{Segment, SampleError, eval};
/// let segs = [Segment { t0_s: 0.0, duration_s: 0.25, coeffs: [[0.0; 6]; 3] }];
/// let times: Vec<f64> = eval::sample(&segs, 0.1).unwrap().map(|(t, _)| t).collect();
/// assert_eq!(times, [0.0, 0.1, 0.2, 0.25]);
/// assert_eq!(eval::sample(&segs, 0.0).unwrap_err(), SampleError::InvalidStep);
/// assert_eq!(eval::sample(&segs, 1e-12).unwrap_err(), SampleError::TooManySamples);
/// assert_eq!(eval::sample(&[], 0.1).unwrap().count(), 0);
/// ```
pub fn sample(segments: &[Segment], dt: f64) -> Result<Samples<'_>, SampleError> {
    if !(dt.is_finite() && dt > 0.0) {
        return Err(SampleError::InvalidStep);
    }
    let end = duration(segments);
    if !(end.is_finite() && end >= 0.0) {
        return Err(SampleError::InvalidDuration);
    }
    // Grid points k·dt < end − dt·1e-9, k = 0 … grid − 1.
    let span = (end - dt * 1e-9) / dt;
    // `span` is not NaN here; +∞ (a huge duration over a tiny step) is refused.
    if span >= MAX_SAMPLES as f64 {
        return Err(SampleError::TooManySamples);
    }
    let grid = if span > 0.0 {
        libm::ceil(span) as u64
    } else {
        0
    };
    Ok(Samples {
        segments,
        dt,
        end,
        next: 0,
        grid,
        done: segments.is_empty(),
    })
}

/// Iterator of [`sample`]: `(plan time (s), joint state)`.
#[derive(Clone, Debug)]
pub struct Samples<'a> {
    segments: &'a [Segment],
    dt: f64,
    end: f64,
    next: u64,
    grid: u64,
    done: bool,
}

impl Iterator for Samples<'_> {
    type Item = (f64, JointState);

    fn next(&mut self) -> Option<Self::Item> {
        if self.done {
            return None;
        }
        let t = if self.next < self.grid {
            self.next as f64 * self.dt
        } else {
            self.done = true;
            self.end
        };
        self.next += 1;
        at_within(self.segments, self.end, t).map(|s| (t, s))
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let n = if self.done {
            0
        } else {
            (self.grid - self.next.min(self.grid) + 1) as usize
        };
        (n, Some(n))
    }
}

impl ExactSizeIterator for Samples<'_> {}

impl core::iter::FusedIterator for Samples<'_> {}

#[cfg(test)]
mod tests {
    use super::*;
    use alloc::vec::Vec;

    /// Minimum-jerk rest-to-rest move q(τ) = q0 + Δ(10τ³ − 15τ⁴ + 6τ⁵),
    /// τ = t/T, on joint j with its own q0 and Δ: the global polynomial in t.
    fn global(j: usize, total: f64) -> [f64; 6] {
        let (q0, d) = ([0.2, 0.3, 0.25][j], [0.1, -0.05, 0.02][j]);
        let t = total;
        [
            q0,
            0.0,
            0.0,
            10.0 * d / t.powi(3),
            -15.0 * d / t.powi(4),
            6.0 * d / t.powi(5),
        ]
    }

    /// The coefficients of p(t0 + s) in s (Taylor shift).
    fn shift(p: &[f64; 6], t0: f64) -> [f64; 6] {
        let binom = |n: usize, k: usize| -> f64 {
            (0..k).fold(1.0, |acc, i| acc * (n - i) as f64 / (i + 1) as f64)
        };
        let mut out = [0.0; 6];
        for (k, o) in out.iter_mut().enumerate() {
            *o = (k..6)
                .map(|n| p[n] * binom(n, k) * t0.powi((n - k) as i32))
                .sum();
        }
        out
    }

    /// The move cut at the given knots into consecutive segments.
    fn split(total: f64, knots: &[f64]) -> Vec<Segment> {
        let mut edges = Vec::from([0.0]);
        edges.extend_from_slice(knots);
        edges.push(total);
        edges
            .windows(2)
            .map(|w| Segment {
                t0_s: w[0],
                duration_s: w[1] - w[0],
                coeffs: [0, 1, 2].map(|j| shift(&global(j, total), w[0])),
            })
            .collect()
    }

    fn exact(t: f64, total: f64) -> JointState {
        let mut out = JointState::default();
        for j in 0..3 {
            let [p, v, a, jk] = crate::quintic::eval_poly(&global(j, total), t);
            (out.q[j], out.v[j], out.a[j], out.jerk[j]) = (p, v, a, jk);
        }
        out
    }

    fn close(a: &JointState, b: &JointState, tol: f64) -> bool {
        let pairs = [(a.q, b.q), (a.v, b.v), (a.a, b.a), (a.jerk, b.jerk)];
        pairs
            .iter()
            .all(|(x, y)| (0..3).all(|j| (x[j] - y[j]).abs() <= tol))
    }

    const T: f64 = 2.0;
    const KNOTS: [f64; 3] = [0.3, 1.1, 1.6];

    #[test]
    fn at_matches_the_segments_inside_and_at_their_ends() {
        let segs = split(T, &KNOTS);
        for (i, s) in segs.iter().enumerate() {
            let q = s.quintic();
            for k in 0..=10 {
                let local = s.duration_s * k as f64 / 10.0;
                let t = s.t0_s + local;
                let got = at(&segs, t).unwrap();
                // Against the segment that runs there (the later one at a knot).
                let (idx, running) = segment_at(&segs, t).unwrap();
                let want_idx = if k == 10 && i + 1 < segs.len() {
                    i + 1
                } else {
                    i
                };
                assert_eq!(idx, want_idx, "t {t}");
                let direct: JointState = running.quintic().eval(t - running.t0_s).into();
                assert_eq!(got, direct);
                // And against this segment and the unsplit move.
                assert!(close(&got, &q.eval(local).into(), 1e-9), "t {t}");
                assert!(close(&got, &exact(t, T), 1e-9), "t {t}");
            }
        }
    }

    #[test]
    fn continuous_at_knots() {
        let segs = split(T, &KNOTS);
        for w in segs.windows(2) {
            let before: JointState = w[0].quintic().end().into();
            let after = at(&segs, w[1].t0_s).unwrap();
            assert!(close(&before, &after, 1e-9), "knot {}", w[1].t0_s);
            let (l, r) = (at(&segs, w[1].t0_s - 1e-9), at(&segs, w[1].t0_s + 1e-9));
            assert!(close(&l.unwrap(), &r.unwrap(), 1e-7));
        }
    }

    #[test]
    fn segment_lookup_at_edges() {
        let segs = split(T, &KNOTS);
        assert_eq!(segment_at(&segs, 0.0).unwrap().0, 0);
        assert_eq!(segment_at(&segs, 0.3).unwrap().0, 1);
        assert_eq!(segment_at(&segs, 0.3 - 1e-12).unwrap().0, 0);
        assert_eq!(segment_at(&segs, duration(&segs)).unwrap().0, 3);
        assert!(segment_at(&segs, -1e-12).is_none());
        assert!(segment_at(&segs, duration(&segs) + 1e-9).is_none());
        for t in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert!(segment_at(&segs, t).is_none());
        }
        assert!(segment_at(&[], 0.0).is_none());
        // A zero-length segment at a knot: the later one runs there.
        let mut segs = split(1.0, &[0.5, 0.5]);
        assert_eq!(segs[1].duration_s, 0.0);
        assert_eq!(segment_at(&segs, 0.5).unwrap().0, 2);
        // Garbage durations: no panic.
        segs[1].duration_s = f64::NAN;
        assert!(segment_at(&segs, 0.2).is_none());
        assert!(at(&segs, 0.2).is_some());
    }

    #[test]
    fn at_clamps_to_rest_outside_the_plan() {
        let segs = split(T, &KNOTS);
        let start = exact(0.0, T);
        let end = exact(T, T);
        for t in [-1.0, -1e-12, f64::NEG_INFINITY] {
            assert_eq!(at(&segs, t).unwrap(), JointState::at_rest(start.q));
        }
        for t in [T + 1e-12, 10.0, f64::INFINITY] {
            let s = at(&segs, t).unwrap();
            assert!(close(&s, &JointState::at_rest(end.q), 1e-12), "t {t}");
            assert_eq!((s.v, s.a, s.jerk), ([0.0; 3], [0.0; 3], [0.0; 3]));
        }
        // At the ends themselves: the segments' own values (the jerk of a
        // minimum-jerk move is not zero there).
        let s0 = at(&segs, 0.0).unwrap();
        assert!(close(&s0, &start, 1e-12));
        assert!(s0.jerk[0] != 0.0);
    }

    #[test]
    fn nan_and_empty_give_none() {
        let segs = split(T, &KNOTS);
        assert!(at(&segs, f64::NAN).is_none());
        assert!(at(&[], 0.0).is_none());
        assert!(at(&[], f64::NAN).is_none());
        assert_eq!(duration(&[]), 0.0);
    }

    #[test]
    fn sample_includes_the_end_exactly() {
        let segs = split(T, &KNOTS);
        for dt in [0.1, 0.3, 0.7, 1e-3, 2.0, 5.0, T / 3.0] {
            let s: Vec<_> = sample(&segs, dt).unwrap().collect();
            let (t_last, last) = s[s.len() - 1];
            assert_eq!(t_last, T, "dt {dt}");
            assert!(close(&last, &exact(T, T), 1e-9));
            assert_eq!(s[0].0, 0.0);
            for (k, (t, st)) in s[..s.len() - 1].iter().enumerate() {
                assert_eq!(*t, k as f64 * dt);
                assert!(close(st, &exact(*t, T), 1e-9));
            }
            // Increasing, nothing nearly doubled at the end.
            for w in s.windows(2) {
                assert!(
                    w[1].0 - w[0].0 > dt * 1e-6,
                    "dt {dt}: {} {}",
                    w[0].0,
                    w[1].0
                );
            }
            let n = (T / dt - 1e-9).ceil() as usize + 1;
            assert_eq!(s.len(), n, "dt {dt}");
            assert_eq!(sample(&segs, dt).unwrap().len(), n);
        }
    }

    #[test]
    fn sample_refuses_bad_steps_and_durations() {
        let segs = split(T, &KNOTS);
        for dt in [0.0, -0.1, f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(sample(&segs, dt).unwrap_err(), SampleError::InvalidStep);
        }
        assert_eq!(
            sample(&segs, f64::MIN_POSITIVE).unwrap_err(),
            SampleError::TooManySamples
        );
        assert_eq!(
            sample(&segs, T / MAX_SAMPLES as f64 / 2.0).unwrap_err(),
            SampleError::TooManySamples
        );
        let mut bad = segs.clone();
        bad[2].duration_s = f64::INFINITY;
        assert_eq!(sample(&bad, 0.1).unwrap_err(), SampleError::InvalidDuration);
        bad[2].duration_s = f64::NAN;
        assert_eq!(sample(&bad, 0.1).unwrap_err(), SampleError::InvalidDuration);
        bad[2].duration_s = -10.0;
        assert_eq!(sample(&bad, 0.1).unwrap_err(), SampleError::InvalidDuration);
        assert_eq!(sample(&[], 0.1).unwrap().count(), 0);
        // A zero-length plan: one sample, at 0.
        let point = [Segment {
            t0_s: 0.0,
            duration_s: 0.0,
            coeffs: [[0.1, 1.0, 0.0, 0.0, 0.0, 0.0]; 3],
        }];
        let s: Vec<_> = sample(&point, 0.1).unwrap().collect();
        assert_eq!(s.len(), 1);
        assert_eq!(s[0].0, 0.0);
    }

    #[test]
    fn torque_and_platform_position_along_the_plan() {
        use crate::{Robot, dynamics, kinematics};
        let m = Robot::default().model::<f64>();
        let segs = split(T, &KNOTS);
        for (t, s) in sample(&segs, 0.05).unwrap() {
            let mo = s.motion();
            let want = dynamics::torque(&m, &mo.q, &mo.qd, &mo.qdd).unwrap();
            assert_eq!(dynamics::state_torque(&m, s).unwrap(), want, "t {t}");
            let r = kinematics::platform_position(&m, s.q).unwrap();
            let back = crate::kinematics::Pose::from_cartesian(&m, r).unwrap().q;
            assert!((back - mo.q).norm() < 1e-9, "t {t}");
        }
    }

    #[test]
    fn joint_state_round_trips_through_motion() {
        let s = JointState {
            q: [1.0, 2.0, 3.0],
            v: [4.0, 5.0, 6.0],
            a: [7.0, 8.0, 9.0],
            jerk: [10.0, 11.0, 12.0],
        };
        assert_eq!(JointState::from(s.motion()), s);
        assert_eq!(JointMotion::from(s).qddd[2], 12.0);
    }
}
