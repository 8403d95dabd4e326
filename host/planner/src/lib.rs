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
//! How it works, one module a step, each using only those before it
//! (`tests/layers.rs` holds the order): `problem` is the problem at fixed
//! knots and its exact evaluation; `program` its second-order-cone program
//! at a point; `inner` the exact min-max-jerk knot derivatives at fixed
//! intervals, by a method (cutting planes, the jerk-only direct solve
//! of `jerk_only`, through the relaxation); `step` the trust-region step
//! over the intervals; `search` the deterministic multistart of those steps;
//! `time_scaling`, `time_descent` and `min_time` the minimum time, by a
//! descent on the total time from the jerk-only optimum's shapes, each
//! iterate time-scaled until it meets every limit; `rounding` the intervals
//! in whole microseconds (what the drives run), repaired until every limit
//! holds; `planning` the entry point, [`plan`], which writes no plan that
//! breaks the streaming rule of the default drives (`streaming`).
//!
//! Beside the planner: [`files`] reads plan and points files, [`stats`]
//! and [`poly`] are the figures of a plan for reports, [`bounds`] the
//! bounds a job must stay within.

mod banded;
mod bounded_read;
mod check;
mod coarse_start;
mod error;
#[cfg(any(test, feature = "evolution"))]
pub mod evolution;
mod extrema;
mod free_knots;
mod holding;
mod inner;
mod jerk_knots;
mod jerk_only;
mod job;
#[cfg(feature = "toml")]
mod job_file;
mod load;
mod lp;
mod min_time;
mod options;
mod planning;
mod points_file;
mod problem;
mod program;
mod rounding;
mod run_state;
mod search;
mod second_order;
mod shaper;
pub mod shaping;
mod spline;
pub mod stats;
mod step;
mod streaming;
mod sturm;
mod time_descent;
mod time_scaling;
mod workers;

#[cfg(test)]
mod scale_tests;
#[cfg(test)]
mod search_tests;

pub use bounded_read::{MAX_JOB_BYTES, MAX_PLAN_BYTES, MAX_POINTS_FILE_BYTES, read_text};
pub use check::{CheckRow, check, check_deviation};
pub use error::{CancelReason, Limit, PlanError, PointKind};
pub use job::{FREE_KNOTS_BY_DEFAULT, Job, JobBuilder, KnotPlacement};
pub use options::{Control, MAX_STARTS, Observer, Options, Progress, Stage};
pub use planning::{plan, plan_with};
pub use triquint_shared::plan::{Objective, Plan};
pub use triquint_shared::{Limits, Robot};

/// Plan and points files: parsing, with their typed errors.
pub mod files {
    pub use crate::load::{LoadError, parse_plan, validate_plan};
    pub use crate::points_file::{PointsFileError, parse_points};
}

/// The bounds a [`Job`] must stay within (checked by [`JobBuilder::build`]).
pub mod bounds {
    pub use crate::job::{KNOT_SEGMENTS, LIMIT_RANGE, MAX_DEVIATION_MM, MAX_POINTS, MAX_SEGMENT_S};
}

/// Exact extrema and integrals of polynomials in segment-local time (power
/// coefficients, lowest first), the ones the search and [`stats`] use, for
/// reports on a plan.
pub mod poly {
    pub use crate::extrema::{
        antiderivative, argmax_abs_on_interval, derivative, eval, integral_abs_on_interval,
        max_abs_on_interval, roots_in,
    };
}

/// The planner's guide, `docs/planner.md`: its Rust examples are compiled
/// and run as doctests (`cargo test -p triquint-planner --doc`).
#[cfg(doctest)]
#[doc = include_str!("../../../docs/planner.md")]
pub struct PlannerGuide;
