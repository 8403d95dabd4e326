//! The plan file (`triquint-plan/1`): what the planner writes and every other
//! tool (check, report, simulate, upload) reads.

use alloc::string::String;
use alloc::vec::Vec;

use serde::{Deserialize, Serialize};

use crate::protocol::WireSegment;
use crate::protocol::segment::{FLAG_FIRST, FLAG_LAST, SegmentError};
use crate::quintic::Quintic;
use crate::{Limits, Robot};

/// Value of the `format` field.
pub const PLAN_FORMAT: &str = "triquint-plan/1";

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

/// One segment: joint j is q_j(t0 + t) = Σ_k coeffs[j][k] t^k, t ∈ [0, duration].
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
    pub via_points_m: Vec<[f64; 3]>,
    pub knots_m: Vec<[f64; 3]>,
    pub intervals_s: Vec<f64>,
    pub total_time_s: f64,
    pub segments: Vec<Segment>,
    pub max_abs: MaxAbs,
    pub solver: SolverStats,
}

impl Plan {
    /// The segments as they go on the wire: sequence numbers from 0, first and
    /// last flagged. On error, the index of the segment that cannot be sent.
    pub fn wire_segments(&self) -> Result<Vec<WireSegment>, (usize, SegmentError)> {
        let n = self.segments.len();
        self.segments
            .iter()
            .enumerate()
            .map(|(i, s)| {
                let mut flags = 0;
                if i == 0 {
                    flags |= FLAG_FIRST;
                }
                if i + 1 == n {
                    flags |= FLAG_LAST;
                }
                WireSegment::from_quintic(i as u16, &s.quintic(), flags).map_err(|e| (i, e))
            })
            .collect()
    }
}
