//! Plan reports: the paper's tables and figures, as text and SVG. The
//! statistics they show come from the planner library.
//!
//! - [`tables`]: the statistics as aligned text tables (paper Tables 4/5/7/8).
//! - [`plots`]: SVG profiles against time and the platform path (paper Figures 10/12).
//! - [`sim_plots`]: SVG traces of a simulation run.

pub mod knot_labels;
pub mod plots;
pub mod sim_plots;
pub mod tables;

/// The polynomial helpers of the planner, as the plots use them.
pub(crate) use triquint_planner::poly as extrema;

/// The planner's plan statistics, as the tables and plots use them.
pub(crate) mod stats {
    pub use triquint_planner::stats::{PlanStats, Quantity, segment_torque};
}

pub use triquint_planner::stats::{PlanStats, plan_stats};

/// Why a report cannot be made from a plan.
#[derive(Debug, thiserror::Error)]
pub enum ReportError {
    /// The plan file is structurally wrong (beyond what serde checks).
    #[error("not a valid plan: {0}")]
    Invalid(String),
    /// A chart could not be drawn.
    #[error(transparent)]
    Plot(#[from] triquint_plot::PlotError),
    /// The dynamics (forward kinematics) failed along the trajectory.
    #[error("segment {segment} at t = {time_s:.6} s: {source}")]
    Kinematics {
        segment: usize,
        time_s: f64,
        source: triquint_shared::KinematicsError,
    },
}

impl From<triquint_planner::stats::StatsError> for ReportError {
    fn from(e: triquint_planner::stats::StatsError) -> Self {
        ReportError::Kinematics {
            segment: e.segment,
            time_s: e.time_s,
            source: e.source,
        }
    }
}
