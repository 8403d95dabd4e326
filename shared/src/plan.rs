//! The plan file (`triquint-plan/3`, 4 with free knots, 5 shaped, 6 with a
//! deviation bound; docs/plan-format.md): what the planner
//! writes and every other tool (check, report, simulate, upload) reads, and
//! its evaluation at a plan time ([`Plan::at`], [`Plan::sample`]; the
//! conventions are in [`eval`]). Format 1 and 2 plans still load,
//! read-only, with the default machine's values for what they lack.

use alloc::string::String;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use crate::machine::Ceilings;
use crate::protocol::WireSegment;
use crate::protocol::segment::{FLAG_FIRST, FLAG_LAST, SegmentError};
use crate::quintic::Quintic;
use crate::{Limits, Robot, Travel};

pub mod eval;
pub mod extrema;
pub mod figures;
pub mod override_cap;
pub mod shaping;

pub use eval::{JointState, MAX_SAMPLES, SampleError, Samples};

/// Value of the `format` field of the plans this version writes.
pub const PLAN_FORMAT: &str = "triquint-plan/3";
/// Earlier formats: read (with the default machine's values for what they
/// lack: travel before 2, ceilings before 3), never written.
pub const PLAN_FORMAT_1: &str = "triquint-plan/1";
pub const PLAN_FORMAT_2: &str = "triquint-plan/2";
/// Format 3 with `free_knots`: written for a plan whose planner chose some
/// knots (docs/plan-format.md); a plan without free knots is format 3.
pub const PLAN_FORMAT_FREE_KNOTS: &str = "triquint-plan/4";
/// A shaped plan, with `shaping` (its shaper and the unshaped plan, whose
/// free knots it keeps): written for every plan a job shapes.
pub const PLAN_FORMAT_SHAPED: &str = "triquint-plan/5";
/// A plan whose job bounded the platform's distance from the straight
/// segments between the via-points, with `max_deviation_m` (and
/// `free_knots` when the planner chose some): written for every unshaped
/// plan of such a job.
pub const PLAN_FORMAT_BOUNDED: &str = "triquint-plan/6";

/// The most segments a plan may have: the wire numbers them from 0 in 16
/// bits, and a number that wrapped would break the host's credit and
/// acknowledgement bookkeeping.
pub const MAX_SEGMENTS: usize = u16::MAX as usize;

/// The first of a plan's segments that cannot go on the wire.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("segment {index}: {source}")]
pub struct WireError {
    /// Its index in the plan (the first beyond [`MAX_SEGMENTS`] if there are more).
    pub index: usize,
    #[source]
    pub source: SegmentError,
}

/// What the planner optimises.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Objective {
    /// Minimise the maximum absolute joint jerk with Σh ≤ total_time.
    #[default]
    MinMaxJerk,
    /// Shortest total time meeting every limit, then min-max jerk at that time.
    MinTime,
}

/// One segment: joint j is `q_j(t0 + t) = Σ_k coeffs[j][k] t^k`, t ∈ [0, duration].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Segment {
    pub t0_s: f64,
    pub duration_s: f64,
    pub coeffs: [[f64; 6]; 3],
}

impl Segment {
    pub fn quintic(&self) -> Quintic<f64> {
        Quintic {
            coeffs: self.coeffs,
            duration: self.duration_s,
        }
    }
}

/// Exact continuous-time maxima of |v|, |a|, |jerk| and |τ| per joint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct MaxAbs {
    pub velocity: [f64; 3],
    pub acceleration: [f64; 3],
    pub jerk: [f64; 3],
    pub torque: [f64; 3],
}

/// How the solver got there. `seconds` is the only field that varies run to run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct SolverStats {
    pub seconds: f64,
    pub starts: u64,
    pub lp_solves: u64,
}

/// A complete plan.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Plan {
    pub format: String,
    pub objective: Objective,
    pub robot: Robot,
    pub limits: Limits,
    /// The sliders' travel the plan was made for, which `check` proves it
    /// against (format 2; a format 1 plan has none and gets the default).
    #[serde(default)]
    pub travel: Travel,
    /// The machine's ceilings the plan's limits were held to, which `check`
    /// proves them against (format 3; earlier ones get the default machine's).
    #[serde(default)]
    pub ceilings: Ceilings,
    pub via_points_m: Vec<[f64; 3]>,
    pub knots_m: Vec<[f64; 3]>,
    /// Indices in `knots_m` of the knots whose time and position the
    /// planner chose (format 4; empty, and absent from the file, otherwise).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub free_knots: Vec<usize>,
    /// The job's bound on the platform's distance from the straight
    /// segments between the via-points (m), which `check` proves (format 6;
    /// absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub max_deviation_m: Option<f64>,
    pub intervals_s: Vec<f64>,
    pub total_time_s: f64,
    pub segments: Vec<Segment>,
    pub max_abs: MaxAbs,
    pub solver: SolverStats,
    /// The shaper and the unshaped plan (format 5; absent otherwise).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub shaping: Option<shaping::Shaping>,
}

impl Plan {
    /// Total duration (s): the sum of the segments' durations (what the
    /// planner writes as `total_time_s`); 0 for a plan with no segments.
    ///
    /// ```
    /// # use triquint_shared::plan::*;
    /// # fn plan(segments: Vec<Segment>) -> Plan { Plan { format: PLAN_FORMAT.into(),
    /// #     objective: Objective::MinMaxJerk, robot: Default::default(), limits: Default::default(), travel: Default::default(), ceilings: Default::default(),
    /// #     via_points_m: vec![], knots_m: vec![], free_knots: vec![], max_deviation_m: None, intervals_s: vec![], total_time_s: 0.0,
    /// #     segments, max_abs: Default::default(), solver: Default::default(), shaping: None } }
    /// let seg = |t0_s, duration_s| Segment { t0_s, duration_s, coeffs: [[0.3, 0.0, 0.0, 0.0, 0.0, 0.0]; 3] };
    /// assert_eq!(plan(vec![seg(0.0, 1.5), seg(1.5, 0.5)]).duration(), 2.0);
    /// assert_eq!(plan(vec![]).duration(), 0.0);
    /// ```
    pub fn duration(&self) -> f64 {
        eval::duration(&self.segments)
    }

    /// The segment running at plan time `t` (s) and its index, by binary
    /// search on the segments' start times: at a knot the later segment, at
    /// `t == duration()` the last. `None` outside [0, [`duration`](Self::duration)],
    /// for a NaN `t` and for a plan with no segments ([`Plan::at`] clamps instead).
    ///
    /// ```
    /// # use triquint_shared::plan::*;
    /// # fn plan(segments: Vec<Segment>) -> Plan { Plan { format: PLAN_FORMAT.into(),
    /// #     objective: Objective::MinMaxJerk, robot: Default::default(), limits: Default::default(), travel: Default::default(), ceilings: Default::default(),
    /// #     via_points_m: vec![], knots_m: vec![], free_knots: vec![], max_deviation_m: None, intervals_s: vec![], total_time_s: 0.0,
    /// #     segments, max_abs: Default::default(), solver: Default::default(), shaping: None } }
    /// let seg = |t0_s, duration_s| Segment { t0_s, duration_s, coeffs: [[0.3, 0.0, 0.0, 0.0, 0.0, 0.0]; 3] };
    /// let p = plan(vec![seg(0.0, 1.5), seg(1.5, 0.5)]);
    /// assert_eq!(p.segment_at(0.0).map(|(i, _)| i), Some(0));
    /// assert_eq!(p.segment_at(1.5).map(|(i, _)| i), Some(1));
    /// assert_eq!(p.segment_at(2.0).map(|(i, s)| (i, s.t0_s)), Some((1, 1.5)));
    /// assert!(p.segment_at(-0.1).is_none() && p.segment_at(2.1).is_none());
    /// assert!(p.segment_at(f64::NAN).is_none());
    /// ```
    pub fn segment_at(&self, t: f64) -> Option<(usize, &Segment)> {
        eval::segment_at(&self.segments, t)
    }

    /// Position, velocity, acceleration and jerk of every joint at plan time
    /// `t` (s), from the quintic of the segment running at `t`. Time is
    /// clamped to the plan: before 0 the joints rest at the start position,
    /// after the end at the end position (velocity, acceleration and jerk 0).
    /// `None` for a NaN `t` or a plan with no segments (it has no position).
    ///
    /// ```
    /// # use triquint_shared::plan::*;
    /// # fn plan(segments: Vec<Segment>) -> Plan { Plan { format: PLAN_FORMAT.into(),
    /// #     objective: Objective::MinMaxJerk, robot: Default::default(), limits: Default::default(), travel: Default::default(), ceilings: Default::default(),
    /// #     via_points_m: vec![], knots_m: vec![], free_knots: vec![], max_deviation_m: None, intervals_s: vec![], total_time_s: 0.0,
    /// #     segments, max_abs: Default::default(), solver: Default::default(), shaping: None } }
    /// // Every joint: q = 0.3 + 0.1 t² for 1 s, then on at 0.2 m/s.
    /// let p = plan(vec![
    ///     Segment { t0_s: 0.0, duration_s: 1.0, coeffs: [[0.3, 0.0, 0.1, 0.0, 0.0, 0.0]; 3] },
    ///     Segment { t0_s: 1.0, duration_s: 1.0, coeffs: [[0.4, 0.2, 0.0, 0.0, 0.0, 0.0]; 3] },
    /// ]);
    /// let s = p.at(0.5).unwrap();
    /// assert!((s.q[0] - 0.325).abs() < 1e-12);
    /// assert!((s.v[1] - 0.1).abs() < 1e-12 && s.a[2] == 0.2 && s.jerk == [0.0; 3]);
    /// assert!((p.at(1.0).unwrap().q[0] - 0.4).abs() < 1e-12);
    /// let end = p.at(5.0).unwrap();
    /// assert!((end.q[0] - 0.6).abs() < 1e-12 && end.v == [0.0; 3]);
    /// assert_eq!(p.at(-1.0), Some(JointState::at_rest([0.3; 3])));
    /// assert!(p.at(f64::NAN).is_none());
    /// assert!(plan(vec![]).at(0.0).is_none());
    /// ```
    pub fn at(&self, t: f64) -> Option<JointState> {
        eval::at(&self.segments, t)
    }

    /// `(t, self.at(t))` at t = 0, dt, 2dt, … and at the end time exactly
    /// (last), lazily; a plan with no segments gives none. A grid time within
    /// dt·10⁻⁹ of the end is dropped for the end itself. Errors for `dt` not
    /// finite and positive, a duration not finite and non-negative, or more
    /// than [`MAX_SAMPLES`] samples (a step too small is refused, not enlarged).
    ///
    /// ```
    /// # use triquint_shared::plan::*;
    /// # fn plan(segments: Vec<Segment>) -> Plan { Plan { format: PLAN_FORMAT.into(),
    /// #     objective: Objective::MinMaxJerk, robot: Default::default(), limits: Default::default(), travel: Default::default(), ceilings: Default::default(),
    /// #     via_points_m: vec![], knots_m: vec![], free_knots: vec![], max_deviation_m: None, intervals_s: vec![], total_time_s: 0.0,
    /// #     segments, max_abs: Default::default(), solver: Default::default(), shaping: None } }
    /// let p = plan(vec![Segment { t0_s: 0.0, duration_s: 1.0, coeffs: [[0.3, 0.1, 0.0, 0.0, 0.0, 0.0]; 3] }]);
    /// let samples: Vec<(f64, JointState)> = p.sample(0.4)?.collect();
    /// let times: Vec<f64> = samples.iter().map(|(t, _)| *t).collect();
    /// assert_eq!(times, [0.0, 0.4, 0.8, 1.0]);
    /// assert!((samples[3].1.q[0] - 0.4).abs() < 1e-12);
    /// assert_eq!(p.sample(0.001)?.len(), 1001);
    /// assert_eq!(p.sample(-1.0).unwrap_err(), SampleError::InvalidStep);
    /// assert_eq!(p.sample(f64::NAN).unwrap_err(), SampleError::InvalidStep);
    /// # Ok::<(), SampleError>(())
    /// ```
    pub fn sample(&self, dt: f64) -> Result<Samples<'_>, SampleError> {
        eval::sample(&self.segments, dt)
    }

    /// The segments as they go on the wire: sequence numbers from 0, first and
    /// last flagged. On error, the first segment that cannot be sent (the
    /// first beyond [`MAX_SEGMENTS`] if there are more).
    pub fn wire_segments(&self) -> Result<Vec<WireSegment>, WireError> {
        let n = self.segments.len();
        self.segments
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let seq = match u16::try_from(i) {
                    Ok(seq) if i < MAX_SEGMENTS => seq,
                    _ => {
                        return Err(WireError {
                            index: i,
                            source: SegmentError::TooMany(n),
                        });
                    }
                };
                let mut flags = 0;
                if i == 0 {
                    flags |= FLAG_FIRST;
                }
                if i + 1 == n {
                    flags |= FLAG_LAST;
                }
                WireSegment::from_quintic(seq, &s.quintic(), flags)
                    .map_err(|source| WireError { index: i, source })
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn resting(n: usize) -> Plan {
        let seg = |i: usize| Segment {
            t0_s: i as f64 * 1e-3,
            duration_s: 1e-3,
            coeffs: [[0.3, 0.0, 0.0, 0.0, 0.0, 0.0]; 3],
        };
        Plan {
            format: PLAN_FORMAT.into(),
            objective: Objective::MinMaxJerk,
            robot: Robot::default(),
            limits: Limits::default(),
            travel: Travel::default(),
            ceilings: Ceilings::default(),
            via_points_m: Vec::new(),
            knots_m: Vec::new(),
            free_knots: Vec::new(),
            max_deviation_m: None,
            intervals_s: Vec::new(),
            total_time_s: 0.0,
            segments: (0..n).map(seg).collect(),
            max_abs: MaxAbs::default(),
            solver: SolverStats::default(),
            shaping: None,
        }
    }

    #[test]
    fn segment_numbers_never_wrap() {
        let w = resting(MAX_SEGMENTS).wire_segments().unwrap();
        assert_eq!(w.last().map(|s| s.seq), Some(u16::MAX - 1));
        assert_eq!(
            resting(MAX_SEGMENTS + 1).wire_segments().unwrap_err(),
            WireError {
                index: MAX_SEGMENTS,
                source: SegmentError::TooMany(MAX_SEGMENTS + 1)
            }
        );
    }
}
