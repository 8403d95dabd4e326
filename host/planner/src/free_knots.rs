//! Free knots for a point-to-point move: the planner chooses the interior
//! knots' number, times and joint positions.
//!
//! Between two rests the shortest motion under per-joint limits on velocity,
//! acceleration and jerk is the time-optimal jerk-limited ("double S")
//! profile s(t) along the straight line in joint space, scaled so that the
//! joint that moves farthest meets the limits: every other joint is a
//! smaller copy, and all end together (Ruckig's phase synchronisation;
//! its time synchronisation takes as long when every joint has the same
//! limits). Its jerk
//! jumps, which a C3 plan cannot do. Averaging s over a sliding window of
//! width τ (convolving its jerk with a box) makes the jerk continuous and
//! piecewise linear, keeps every |v|, |a| and |jerk| within the original's
//! (an average never exceeds the largest value averaged), keeps both ends
//! at rest, and lengthens the move by exactly τ. The result is piecewise
//! quartic with breaks at the profile's switch times and the same times
//! plus τ: those are the knots, and the quintic Hermite segments through
//! their positions, velocities and accelerations reproduce it exactly.
//! The phases and the window are whole microseconds (the jerk a hair
//! lower to keep the distance), so the knots fall on the drives' time grid
//! and nothing is re-solved. Torque is not part of the construction: when
//! it binds, the shape is time-scaled until it holds and rounded as any
//! min-time plan is (and `planning` keeps the fixed knots' plan when that
//! is shorter).
//!
//! A segment count set by the job: more than the shape's are its segments
//! halved, longest first, which changes nothing of the motion; fewer keep
//! the shape's knots nearest its jerk switches and leave the times and
//! derivatives to the min-time search, as at fixed knots.
//!
//! A bound on the Cartesian deviation is met by [`toward_straight`]: each
//! knot moved a fraction λ of the way to the inverse kinematics of the
//! Cartesian point at the same fraction of the move, and the min-time
//! search run at those knots.

use nalgebra::Vector3;
use triquint_shared::kinematics::Pose;

use crate::problem::{Problem, Solution, meets_every_limit};
use crate::rounding::{FINAL_TORQUE_SAMPLES, lengthen_until_feasible};
use crate::spline::Knots;
use crate::time_scaling::shortest_scaling;

/// The averaging window as a fraction of the profile's duration: the move
/// takes this much longer than the jerk-discontinuous optimum, and the
/// jerk's ramps are this long.
const WINDOW: f64 = 1.0 / 32.0;
/// How far inside the limits the whole-microsecond profile is built, so
/// that the evaluation's rounding never reads as a violation.
const MARGIN: f64 = 1e-9;
/// Shortest segment (µs): five times the planner's 1 ms, because the
/// check's C3 residual of a segment in power form grows as h⁻³ times the
/// rounding of its coefficients (docs/planner-speed.md).
const MIN_SEGMENT_US: i64 = 5_000;

/// Durations (s) of the double S's jerk pulse, constant-acceleration hold
/// and cruise.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Timing {
    jerk: f64,
    hold: f64,
    cruise: f64,
}

/// The time-optimal rest-to-rest timing over distance `d` under the
/// limits `v`, `a`, `j` (all > 0).
fn double_s(d: f64, v: f64, a: f64, j: f64) -> Timing {
    // Jerk time and acceleration time when the velocity limit is reached.
    let (mut tj, mut ta) = if v * j >= a * a {
        (a / j, a / j + v / a)
    } else {
        ((v / j).sqrt(), 2.0 * (v / j).sqrt())
    };
    let mut tv = d / v - ta;
    if tv < 0.0 {
        tv = 0.0;
        if d >= 2.0 * a.powi(3) / (j * j) {
            tj = a / j;
            ta = 0.5 * tj + (0.25 * tj * tj + d / a).sqrt();
        } else {
            tj = (d / (2.0 * j)).cbrt();
            ta = 2.0 * tj;
        }
    }
    Timing {
        jerk: tj,
        hold: (ta - 2.0 * tj).max(0.0),
        cruise: tv,
    }
}

impl Timing {
    /// Phases of constant jerk `j`, the zero-length ones left out.
    fn phases(&self, j: f64) -> Vec<Phase> {
        let Timing { jerk, hold, cruise } = *self;
        [
            (jerk, j),
            (hold, 0.0),
            (jerk, -j),
            (cruise, 0.0),
            (jerk, -j),
            (hold, 0.0),
            (jerk, j),
        ]
        .into_iter()
        .filter(|(t, _)| *t > 0.0)
        .collect()
    }

    /// Peak velocity and acceleration per unit of jerk.
    fn peaks(&self) -> (f64, f64) {
        (self.jerk * (self.jerk + self.hold), self.jerk)
    }
}

/// One phase of constant jerk: its duration and jerk (units of the path).
type Phase = (f64, f64);
/// A piecewise-constant-jerk profile from rest at 0, with its running
/// integral: state (∫s, s, v, a) at any time, constant (at rest at the
/// end's position) after the last phase and zero before the first.
struct Profile {
    /// Start time, jerk and state (∫s, s, v, a) of each phase.
    phases: Vec<(f64, f64, [f64; 4])>,
    end: f64,
    end_state: [f64; 4],
}

/// State (∫s, s, v, a) after `t` of constant jerk `j` from `x`.
fn advance(x: [f64; 4], j: f64, t: f64) -> [f64; 4] {
    let [i, s, v, a] = x;
    [
        i + s * t + v * t * t / 2.0 + a * t.powi(3) / 6.0 + j * t.powi(4) / 24.0,
        s + v * t + a * t * t / 2.0 + j * t.powi(3) / 6.0,
        v + a * t + j * t * t / 2.0,
        a + j * t,
    ]
}

impl Profile {
    fn new(phases: &[Phase]) -> Profile {
        let mut out = Vec::with_capacity(phases.len());
        let (mut t, mut x) = (0.0, [0.0; 4]);
        for &(h, j) in phases {
            out.push((t, j, x));
            x = advance(x, j, h);
            t += h;
        }
        Profile {
            phases: out,
            end: t,
            end_state: x,
        }
    }

    fn at(&self, t: f64) -> [f64; 4] {
        if t <= 0.0 {
            return [0.0; 4];
        }
        if t >= self.end {
            let [i, s, _, _] = self.end_state;
            return [i + s * (t - self.end), s, 0.0, 0.0];
        }
        let k = self.phases.partition_point(|p| p.0 <= t) - 1;
        let (t0, j, x) = self.phases[k];
        advance(x, j, t - t0)
    }

    /// Position, velocity and acceleration at `t` of the profile averaged
    /// over the window (t − τ, t].
    fn averaged(&self, t: f64, tau: f64) -> [f64; 3] {
        let (now, before) = (self.at(t), self.at(t - tau));
        [0, 1, 2].map(|r| (now[r] - before[r]) / tau)
    }
}

/// The whole-microsecond timing nearest above `t` whose profile over `d`
/// keeps every limit (`v`, `a`, `j` already inside by [`MARGIN`]), and its
/// jerk: each phase rounded up to whole µs (and to 1 ms when it is
/// shorter), the jerk lowered so that the distance stays `d`, then a phase
/// lengthened by a microsecond while its peak is over.
fn whole_microseconds(t: Timing, d: f64, v: f64, a: f64, j: f64) -> Option<([i64; 3], f64)> {
    let up = |x: f64| {
        if x > 0.0 {
            ((x * 1e6).ceil() as i64).max(MIN_SEGMENT_US)
        } else {
            0
        }
    };
    let mut us = [up(t.jerk).max(MIN_SEGMENT_US), up(t.hold), up(t.cruise)];
    for _ in 0..10_000 {
        let t = Timing {
            jerk: us[0] as f64 * 1e-6,
            hold: us[1] as f64 * 1e-6,
            cruise: us[2] as f64 * 1e-6,
        };
        let unit = Profile::new(&t.phases(1.0)).end_state[1];
        let jerk = d / unit;
        let (pv, pa) = t.peaks();
        if jerk > j {
            us[0] += 1;
        } else if jerk * pa > a {
            us[1] = (us[1] + 1).max(MIN_SEGMENT_US);
        } else if jerk * pv > v {
            us[2] = (us[2] + 1).max(MIN_SEGMENT_US);
        } else {
            return Some((us, jerk));
        }
    }
    None
}

/// Knot times (µs) of the profile of `us` averaged over `window` µs: the
/// switch times and the same plus the window; None when two are closer
/// than the shortest segment.
fn knot_times(us: [i64; 3], window: i64) -> Option<Vec<i64>> {
    let [j, h, c] = us;
    // Phase ends where the jerk changes: two decelerating pulses with no
    // cruise between them are one phase.
    let mut switches = vec![0];
    let mut jerk_before = None;
    for (d, sign) in [(j, 1), (h, 0), (j, -1), (c, 0), (j, -1), (h, 0), (j, 1)] {
        if d == 0 {
            continue;
        }
        let end = switches[switches.len() - 1] + d;
        if jerk_before == Some(sign) {
            *switches.last_mut().expect("starts with 0") = end;
        } else {
            switches.push(end);
        }
        jerk_before = Some(sign);
    }
    let mut all: Vec<i64> = switches.iter().flat_map(|&t| [t, t + window]).collect();
    all.sort_unstable();
    all.dedup();
    all.windows(2)
        .all(|w| w[1] - w[0] >= MIN_SEGMENT_US)
        .then_some(all)
}

/// What the free knots of a point-to-point move come to.
pub(crate) enum FreeShape {
    /// The plan at the knots, in whole microseconds and meeting every
    /// limit, and whether torque made it slower than the construction.
    Solved(Problem, Solution, bool),
    /// Fewer segments than the shape has: the knots, for the min-time search.
    Knots(Problem),
}

/// Why a job's segment count cannot be had.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct TooManySegments {
    /// The most this move takes: its segments halved down to the shortest.
    pub(crate) most: usize,
}

/// `times` (µs) with segments halved, longest first, until there are
/// `segments`; Err with the most there can be when a half would be
/// shorter than the shortest segment.
fn split(mut times: Vec<i64>, segments: usize) -> Result<Vec<i64>, TooManySegments> {
    while times.len() - 1 < segments {
        let k = (0..times.len() - 1)
            .max_by_key(|&k| (times[k + 1] - times[k], std::cmp::Reverse(k)))
            .expect("two knots at least");
        let mid = (times[k] + times[k + 1]) / 2;
        if mid - times[k] < MIN_SEGMENT_US || times[k + 1] - mid < MIN_SEGMENT_US {
            return Err(TooManySegments {
                most: times.len() - 1,
            });
        }
        times.insert(k + 1, mid);
    }
    Ok(times)
}

/// `times` (µs) down to `segments`: the interior knot whose removal makes
/// the shortest merged segment goes first, so the knots kept are those
/// the shape's long phases begin and end at.
fn merge(mut times: Vec<i64>, segments: usize) -> Vec<i64> {
    while times.len() - 1 > segments {
        let k = (1..times.len() - 1)
            .min_by_key(|&k| times[k + 1] - times[k - 1])
            .expect("an interior knot");
        times.remove(k);
    }
    times
}

/// The free knots of a point-to-point move ([`FreeShape`]), with
/// `segments` segments when given; Ok(None) when no time-scaling of the
/// shape meets the limits. `template` is the job's problem: its first and
/// last knots are the move's ends.
pub(crate) fn free_knots(
    template: &Problem,
    segments: Option<usize>,
) -> Result<Option<FreeShape>, TooManySegments> {
    let q = &template.knots.q;
    let (start, end) = (q[0], q[q.len() - 1]);
    let dq: [f64; 3] = [0, 1, 2].map(|j| end[j] - start[j]);
    // The joint that moves farthest meets the limits; the others follow.
    let d = dq.iter().fold(0.0, |m: f64, x| m.max(x.abs()));
    let l = &template.limits;
    let [v, a, j] = [l.velocity, l.acceleration, l.jerk].map(|x| x * (1.0 - MARGIN));
    let Some((us, jerk)) = whole_microseconds(double_s(d, v, a, j), d, v, a, j) else {
        return Ok(None);
    };
    let total_us = 4 * us[0] + 2 * us[1] + us[2];
    // The window nearest the wanted fraction that keeps every segment at
    // least the shortest: tried at millisecond steps either side.
    let aim = ((total_us as f64 * WINDOW).round() as i64).max(MIN_SEGMENT_US);
    let Some((window, times)) = (0..64)
        .map(|i| aim + if i % 2 == 0 { 1 } else { -1 } * (i + 1) / 2 * 1_000)
        .filter(|&w| w >= MIN_SEGMENT_US)
        .find_map(|w| knot_times(us, w).map(|t| (w, t)))
    else {
        return Ok(None);
    };
    let fewer = segments.is_some_and(|n| n < times.len() - 1);
    let times = match segments {
        Some(n) if n < times.len() - 1 => merge(times, n),
        Some(n) => split(times, n)?,
        None => times,
    };
    let timing = Timing {
        jerk: us[0] as f64 * 1e-6,
        hold: us[1] as f64 * 1e-6,
        cruise: us[2] as f64 * 1e-6,
    };
    let profile = Profile::new(&timing.phases(jerk));
    let tau = window as f64 * 1e-6;
    let n = times.len();
    let states: Vec<[f64; 3]> = times
        .iter()
        .map(|&t| profile.averaged(t as f64 * 1e-6, tau))
        .collect();
    let mut knots = Vec::with_capacity(n);
    knots.push(start);
    for s in &states[1..n - 1] {
        knots.push([0, 1, 2].map(|j| start[j] + dq[j] / d * s[0]));
    }
    knots.push(end);
    let h: Vec<f64> = times
        .windows(2)
        .map(|w| (w[1] - w[0]) as f64 * 1e-6)
        .collect();
    // Per joint: the interior knots' velocities, then their accelerations.
    let mut x = [0, 1, 2].map(|j| {
        let inner = &states[1..n - 1];
        let u = dq[j] / d;
        inner
            .iter()
            .map(|s| u * s[1])
            .chain(inner.iter().map(|s| u * s[2]))
            .collect::<Vec<f64>>()
    });
    let mut p = template.clone();
    p.knots = Knots { q: knots };
    if fewer {
        return Ok(Some(FreeShape::Knots(p)));
    }
    p.torque_samples = FINAL_TORQUE_SAMPLES;
    p.total_time = h.iter().sum();
    // C3 holds in exact arithmetic; the projection takes out the rounding.
    p.project(&h, &mut x);
    let exact = p.evaluate(&h, &x);
    if meets_every_limit(&p, &exact) {
        return Ok(Some(FreeShape::Solved(p, exact, false)));
    }
    // Torque binds: slowed down until it holds, then rounded and re-solved.
    Ok(slowed_until_feasible(&p, &exact).map(|s| FreeShape::Solved(p, s, true)))
}

/// `s` time-scaled until every limit holds, then rounded to whole µs and
/// re-solved there.
fn slowed_until_feasible(p: &Problem, s: &Solution) -> Option<Solution> {
    let slower = shortest_scaling(p, s)?;
    lengthen_until_feasible(p, &slower)
}

/// The free-knot problem `p` of the move from `a` to `b` (Cartesian, m)
/// with its interior knots moved the fraction `lambda` of the way to the
/// straight Cartesian segment: the knot at the fraction f of the joints'
/// travel goes toward the inverse kinematics of a + f (b − a). None when
/// that leaves the workspace. The min-time search plans it.
pub(crate) fn toward_straight(
    p: &Problem,
    a: [f64; 3],
    b: [f64; 3],
    lambda: f64,
) -> Option<Problem> {
    let q = &p.knots.q;
    let (start, end) = (q[0], q[q.len() - 1]);
    let dq = Vector3::from(end) - Vector3::from(start);
    let (a, b) = (Vector3::from(a), Vector3::from(b));
    let mut moved = q.clone();
    for k in moved.iter_mut().take(q.len() - 1).skip(1) {
        let f = (Vector3::from(*k) - Vector3::from(start)).dot(&dq) / dq.norm_squared();
        let on = Pose::from_cartesian(&p.model, a + (b - a) * f).ok()?.q;
        *k = [0, 1, 2].map(|j| k[j] + lambda * (on[j] - k[j]));
    }
    let mut blended = p.clone();
    blended.knots = Knots { q: moved };
    Some(blended)
}
