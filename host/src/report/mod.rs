//! Plan reports: the paper's tables and figures, as text and SVG.
//!
//! - [`extrema`]: exact maxima and absolute integrals of polynomials (reused by the planner).
//! - [`load`]: reading and validating a plan file.
//! - [`stats`]: per-joint max and mean |v|, |a|, |jerk|, |τ| and per-segment maxima.
//! - [`tables`]: the statistics as aligned text tables (paper Tables 4/5/7/8).
//! - [`plots`]: SVG profiles against time and the platform path (paper Figures 10/12).
//! - [`sim_plots`]: SVG traces of a simulation run.

pub mod extrema;
pub mod load;
pub mod plots;
pub mod sim_plots;
pub mod stats;
pub mod tables;

pub use extrema::{argmax_abs_on_interval, integral_abs_on_interval, max_abs_on_interval};
pub use load::{load_plan, parse_plan};
pub use stats::{PlanStats, Quantity, SegmentStats, plan_stats};

/// Why a report cannot be made from a plan.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The plan file is structurally wrong (beyond what serde checks).
    #[error("not a valid plan: {0}")]
    Invalid(String),
    /// The dynamics (forward kinematics) failed along the trajectory.
    #[error("segment {segment} at t = {time_s:.6} s: {source}")]
    Kinematics {
        segment: usize,
        time_s: f64,
        source: triquint_shared::KinematicsError,
    },
}
