//! Job files: what to plan (TOML).
//!
//! ```toml
//! objective = "min-max-jerk"        # or "min-time"
//! [robot]                            # optional; defaults = paper Table 1
//! [limits]                           # defaults = paper Table 3
//! [path]
//! units = "mm"                       # or "m"
//! points = [[-90, 90, 680], [-90, 90, 660]]
//! ```

use std::path::Path;

use nalgebra::Vector3;
use serde::Deserialize;
use triquint_shared::kinematics::Pose;
use triquint_shared::plan::Objective;
use triquint_shared::{Limits, Robot};

use crate::exit::{CliError, CliResult};
use crate::robot_file::one_line;

/// Length unit of the via-points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
pub enum Units {
    #[serde(rename = "mm")]
    Millimetres,
    #[serde(rename = "m")]
    Metres,
}

#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PathSpec {
    pub units: Units,
    pub points: Vec<[f64; 3]>,
}

/// A planning job.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Job {
    #[serde(default)]
    pub objective: Objective,
    #[serde(default)]
    pub robot: Robot,
    #[serde(default)]
    pub limits: Limits,
    pub path: PathSpec,
}

impl Job {
    /// Parses and validates a job; errors name the file and what is wrong where.
    pub fn from_toml(text: &str, origin: &str) -> CliResult<Self> {
        let job: Job = toml::from_str(text)
            .map_err(|e| CliError::bad_input(format!("{origin}: {}", one_line(&e.to_string()))))?;
        job.validate()
            .map_err(|e| CliError::bad_input(format!("{origin}: {e}")))?;
        Ok(job)
    }

    pub fn load(path: &Path) -> CliResult<Self> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CliError::bad_input(format!("{}: {e}", path.display())))?;
        Self::from_toml(&text, &path.display().to_string())
    }

    /// Via-points in metres.
    pub fn points_m(&self) -> Vec<Vector3<f64>> {
        let scale = match self.path.units {
            Units::Millimetres => 1e-3,
            Units::Metres => 1.0,
        };
        self.path
            .points
            .iter()
            .map(|p| Vector3::from(*p) * scale)
            .collect()
    }

    fn validate(&self) -> Result<(), String> {
        self.robot.validate().map_err(|e| format!("[robot] {e}"))?;
        self.limits
            .validate()
            .map_err(|e| format!("[limits] {e}"))?;
        let pts = &self.path.points;
        if pts.len() < 2 {
            return Err(format!("[path] needs at least 2 points, got {}", pts.len()));
        }
        let unit = match self.path.units {
            Units::Millimetres => "mm",
            Units::Metres => "m",
        };
        let model = self.robot.model::<f64>();
        for (i, (p, m)) in pts.iter().zip(self.points_m()).enumerate() {
            if p.iter().any(|x| !x.is_finite()) {
                return Err(format!("[path] point {} {p:?} is not finite", i + 1));
            }
            if let Err(e) = Pose::from_cartesian(&model, m) {
                return Err(format!(
                    "[path] point {} ({}, {}, {}) {unit} is outside the workspace: {e}",
                    i + 1,
                    p[0],
                    p[1],
                    p[2]
                ));
            }
            if i > 0 && (m - self.points_m()[i - 1]).norm() < 1e-9 {
                return Err(format!(
                    "[path] point {} repeats point {}: consecutive via-points must differ",
                    i + 1,
                    i
                ));
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exit::Status;

    fn err(text: &str) -> String {
        let e = Job::from_toml(text, "job.toml").unwrap_err();
        assert_eq!(e.status, Status::BadInput);
        e.message
    }

    #[test]
    fn rejects_bad_jobs_with_where() {
        let ok = "[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [10, 0, 600]]\n";
        assert!(Job::from_toml(ok, "job.toml").is_ok());
        assert!(err("bogus = 1\n[path]\nunits = \"mm\"\npoints = []\n").contains("line 1"));
        assert!(err("[path]\nunits = \"inch\"\npoints = []\n").contains("line 2"));
        assert!(err("[path]\nunits = \"mm\"\npoints = [[0, 0, 600]]\n").contains("at least 2"));
        assert!(
            err("[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [900, 0, 600]]\n")
                .contains("point 2 (900, 0, 600) mm is outside the workspace")
        );
        assert!(
            err(
                "[limits]\njerk = -1\n[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [1, 0, 600]]\n"
            )
            .contains("jerk")
        );
        assert!(
            err("[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [0, 0, 600]]\n")
                .contains("repeats")
        );
        assert!(
            err("[path]\nunits = \"m\"\npoints = [[0, 0, nan], [0, 0, 0.6]]\n")
                .contains("not finite")
        );
    }
}
