//! The triquint planner: Cartesian via-points of a 3-PUU translational
//! parallel robot → a globally min-max-jerk (or minimum-time) C3 piecewise
//! quintic joint trajectory under velocity, acceleration, jerk, torque and
//! total-time limits, every limit verified in continuous time.
//!
//! Three nouns: a [`Job`] (built in code or read from TOML) → [`plan`] →
//! a [`Plan`] you can evaluate at any time ([`Plan::at`]), write as JSON,
//! [`check`] independently, or send to the drives. Every failure is one
//! [`PlanError`] with data.
//!
//! ```
//! use triquint_planner::{Job, Objective, Options, PlanError, plan};
//!
//! let job = Job::builder()
//!     .objective(Objective::MinTime)
//!     .points_mm([[-90.0, 90.0, 680.0], [-86.0, 83.66, 597.66]])
//!     .build()?;
//! let p = plan(&job, &Options::default())?;
//! let mid = p.at(p.duration() / 2.0).expect("a plan has segments");
//! assert!(mid.v.iter().any(|v| v.abs() > 0.0));
//! assert!(triquint_planner::check(&p)?.iter().all(|row| row.ok));
//!
//! // An infeasible job says which limit binds and what would work.
//! let short = job.to_builder().objective(Objective::MinMaxJerk).total_time(0.3).build()?;
//! match plan(&short, &Options::default()) {
//!     Err(PlanError::Infeasible { shortest_total_time: Some(t), .. }) => assert!(t > 0.3),
//!     other => panic!("{other:?}"),
//! }
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! How it works: for fixed intervals the min-max-jerk spline is one exact
//! second-order-cone program (`local`); a deterministic multistart
//! trust-region search moves the intervals (`search`); the minimum time is
//! found by a descent on the total time from the jerk-only optimum's
//! shapes, each iterate time-scaled until it meets every limit; intervals
//! are rounded to whole microseconds (what the drives run) and repaired
//! until every limit holds.

mod banded;
mod bounded_read;
mod check;
mod error;
pub mod evolution;
mod extrema;
mod jerk_only;
mod job;
#[cfg(feature = "toml")]
mod job_file;
mod load;
mod local;
mod lp;
mod options;
mod planning;
mod points_file;
mod readable;
mod search;
mod spline;
mod stats;
mod sturm;
mod time_descent;
mod watch;

#[cfg(test)]
mod scale_tests;
#[cfg(test)]
mod search_tests;

pub use bounded_read::{MAX_JOB_BYTES, MAX_PLAN_BYTES, MAX_POINTS_FILE_BYTES, read_text};
pub use check::{CheckRow, check, max_abs};
pub use error::{CancelReason, Limit, PlanError, PointKind};
pub use job::{Job, JobBuilder, LIMIT_RANGE, MAX_POINTS, MAX_SEGMENT_S};
pub use load::{LoadError, parse_plan, validate_plan};
pub use options::{Control, Observer, Options, Progress, Stage};
pub use planning::{plan, plan_with};
pub use points_file::{PointsFileError, parse_points};
pub use readable::readable;
pub use stats::{PlanStats, Quantity, SegmentStats, StatsError, plan_stats, segment_torque};
pub use triquint_shared::plan::{Objective, Plan};
pub use triquint_shared::{Limits, Robot};

/// Polynomial helpers the reports share with the statistics.
pub mod poly {
    pub use crate::extrema::{
        antiderivative, argmax_abs_on_interval, derivative, eval, integral_abs_on_interval,
        max_abs_on_interval, roots_in,
    };
}
