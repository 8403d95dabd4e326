//! Job files (TOML):
//!
//! ```toml
//! objective = "min-max-jerk"        # or "min-time"
//! knots = "fixed"                    # or "free" (min-time: two via-points;
//!                                    # min-max-jerk: knots added),
//!                                    # or { placement = "free", segments = 7 }
//! [robot]                            # optional; defaults = paper Table 1
//! [limits]                           # defaults = paper Table 3
//! [path]
//! units = "mm"                       # or "m"
//! points = [[-90, 90, 680], [-90, 90, 660]]
//! # or: file = "points.csv"         # relative to the job file
//! max_deviation_mm = 0.5             # optional: off the straight segments
//! ```
//!
//! ```
//! let job = triquint_planner::Job::from_toml(
//!     "[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [10, 0, 600]]\n",
//! )?;
//! assert_eq!(job.points_m()[1], [0.01, 0.0, 0.6]);
//! # Ok::<(), triquint_planner::PlanError>(())
//! ```

use std::path::{Path, PathBuf};

use serde::Deserialize;
use triquint_shared::machine::Machine;
use triquint_shared::plan::Objective;
use triquint_shared::plan::shaping::ShaperSpec;
use triquint_shared::{Limits, Robot};

use crate::bounded_read::{MAX_JOB_BYTES, MAX_POINTS_FILE_BYTES, io_reason, read_text};
use crate::error::PlanError;
use crate::job::{Job, KnotPlacement};
use crate::points_file::parse_points;

/// Length unit of the via-points.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
enum Units {
    #[serde(rename = "mm")]
    Millimetres,
    #[serde(rename = "m")]
    Metres,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct PathSpec {
    units: Units,
    points: Option<Vec<Point>>,
    file: Option<String>,
    max_deviation_mm: Option<f64>,
}

/// `knots`: a placement, or a table of the placement and a segment count.
enum KnotsSpec {
    Placement(KnotPlacement),
    Table(KnotsTable),
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct KnotsTable {
    placement: KnotPlacement,
    segments: Option<i64>,
}

/// A via-point `[x, y, z]`: exactly three numbers (serde's `[f64; 3]`
/// drops a fourth), as the points file demands.
struct Point([f64; 3]);

impl<'de> Deserialize<'de> for Point {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct Visitor;
        impl<'de> serde::de::Visitor<'de> for Visitor {
            type Value = Point;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a point [x, y, z]")
            }
            fn visit_seq<A: serde::de::SeqAccess<'de>>(
                self,
                mut seq: A,
            ) -> Result<Point, A::Error> {
                let mut p = [0.0; 3];
                let mut n = 0;
                while let Some(x) = seq.next_element::<f64>()? {
                    if n < 3 {
                        p[n] = x;
                    }
                    n += 1;
                }
                if n != 3 {
                    return Err(serde::de::Error::custom(format!(
                        "expected 3 values (x, y, z), found {n}"
                    )));
                }
                Ok(Point(p))
            }
        }
        d.deserialize_seq(Visitor)
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JobFile {
    #[serde(default)]
    objective: Objective,
    robot: Option<Robot>,
    #[serde(default)]
    limits: Limits,
    knots: Option<toml::Value>,
    shaper: Option<ShaperSpec>,
    path: PathSpec,
}

impl Job {
    /// Parses a job; a `[path] file` is read relative to the working directory.
    pub fn from_toml(text: &str) -> Result<Job, PlanError> {
        parse(text, "job", Path::new("."), &mut Vec::new(), None)
    }

    /// [`Job::from_toml`] for `machine` ([`JobBuilder::machine`](crate::job::JobBuilder::machine)):
    /// a `[robot]` in the job must equal the machine's.
    pub fn from_toml_for(text: &str, machine: &Machine) -> Result<Job, PlanError> {
        parse(text, "job", Path::new("."), &mut Vec::new(), Some(machine))
    }

    /// Reads a job file; a `[path] file` is read relative to the job file.
    /// Errors of the file itself carry its path and line.
    pub fn load(path: &Path) -> Result<Job, PlanError> {
        Self::load_with_files(path).map(|(job, _)| job)
    }

    /// [`Job::load`], and the files it read: the job file and its points
    /// file if it names one (so a command can refuse to overwrite them).
    pub fn load_with_files(path: &Path) -> Result<(Job, Vec<PathBuf>), PlanError> {
        Self::load_for(path, None)
    }

    /// [`Job::load_with_files`], for `machine` if given
    /// ([`JobBuilder::machine`](crate::job::JobBuilder::machine)): a `[robot]`
    /// in the job must equal the machine's.
    pub fn load_for(
        path: &Path,
        machine: Option<&Machine>,
    ) -> Result<(Job, Vec<PathBuf>), PlanError> {
        let origin = path.display().to_string();
        let text =
            read_text(path, MAX_JOB_BYTES, "a job file").map_err(|e| PlanError::JobFile {
                origin: origin.clone(),
                line: None,
                reason: io_reason(&e),
            })?;
        let dir = path.parent().unwrap_or(Path::new("."));
        let mut files = vec![path.to_path_buf()];
        let job = parse(&text, &origin, dir, &mut files, machine)?;
        Ok((job, files))
    }
}

fn parse(
    text: &str,
    origin: &str,
    dir: &Path,
    files: &mut Vec<PathBuf>,
    machine: Option<&Machine>,
) -> Result<Job, PlanError> {
    let file_error = |line: Option<usize>, reason: String| PlanError::JobFile {
        origin: origin.to_string(),
        line,
        reason,
    };
    let f: JobFile = toml::from_str(text).map_err(|e| {
        let line = e
            .span()
            .map(|s| text[..s.start.min(text.len())].matches('\n').count() + 1);
        file_error(line, e.message().replace('\n', " "))
    })?;
    let points = match (f.path.points, f.path.file) {
        (Some(p), None) => p.into_iter().map(|p| p.0).collect(),
        (None, Some(name)) => {
            let path = dir.join(&name);
            let shown = path.display().to_string();
            files.push(path.clone());
            let text = read_text(&path, MAX_POINTS_FILE_BYTES, "a points file").map_err(|e| {
                PlanError::JobFile {
                    origin: shown.clone(),
                    line: None,
                    reason: io_reason(&e),
                }
            })?;
            parse_points(&text).map_err(|e| {
                // The file's line goes into `origin:line`, not twice.
                let text = e.to_string();
                let reason = e
                    .line()
                    .and_then(|l| text.strip_prefix(&format!("line {l}: ")))
                    .map_or_else(|| text.clone(), str::to_string);
                PlanError::JobFile {
                    origin: shown,
                    line: e.line(),
                    reason,
                }
            })?
        }
        _ => {
            return Err(PlanError::invalid(
                "path",
                "give exactly one of `points` and `file`",
            ));
        }
    };
    let scale = match f.path.units {
        Units::Millimetres => 1e-3,
        Units::Metres => 1.0,
    };
    let builder = match machine {
        Some(m) => Job::builder().machine(m),
        None => Job::builder(),
    };
    let builder = match f.robot {
        Some(r) => builder.robot(r),
        None => builder,
    };
    let builder = match f.knots.map(knots_spec).transpose()? {
        Some(KnotsSpec::Placement(k)) => builder.knots(k),
        Some(KnotsSpec::Table(t)) => {
            let builder = builder.knots(t.placement);
            match t.segments {
                Some(n) => builder.knot_segments(usize::try_from(n).map_err(|_| {
                    PlanError::invalid("knots.segments", format!("{n} is not a count"))
                })?),
                None => builder,
            }
        }
        None => builder,
    };
    let builder = match f.path.max_deviation_mm {
        Some(mm) => builder.max_deviation_mm(mm),
        None => builder,
    };
    builder
        .objective(f.objective)
        .limits(f.limits)
        .shaper(f.shaper)
        .points_m(points.into_iter().map(|p| p.map(|x| x * scale)))
        .build()
}

/// The `knots` value, or what is wrong with it.
fn knots_spec(v: toml::Value) -> Result<KnotsSpec, PlanError> {
    let wrong = |e: toml::de::Error| PlanError::invalid("knots", e.message().replace('\n', " "));
    match v {
        toml::Value::String(_) => KnotPlacement::deserialize(v)
            .map(KnotsSpec::Placement)
            .map_err(wrong),
        toml::Value::Table(_) => KnotsTable::deserialize(v)
            .map(KnotsSpec::Table)
            .map_err(wrong),
        other => Err(PlanError::invalid(
            "knots",
            format!(
                "{other} is neither \"fixed\", \"free\" nor {{ placement = \"free\", segments = N }}"
            ),
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        Job::from_toml(text).unwrap_err().to_string()
    }

    #[test]
    fn rejects_bad_jobs_with_where() {
        let ok = "[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [10, 0, 600]]\n";
        assert!(Job::from_toml(ok).is_ok());
        assert!(err("bogus = 1\n[path]\nunits = \"mm\"\npoints = []\n").contains("job:1"));
        assert!(err("[path]\nunits = \"inch\"\npoints = []\n").contains("job:2"));
        assert!(err("[path]\nunits = \"mm\"\npoints = [[0, 0, 600]]\n").contains("at least 2"));
        assert!(
            err("[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [900, 0, 600]]\n")
                .contains("point 2 (900, 0, 600) mm is outside the workspace")
        );
        assert!(
            err(
                "[limits]\njerk = -1\n[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [1, 0, 600]]\n"
            )
            .contains("limits.jerk")
        );
        assert!(
            err("[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [0, 0, 600]]\n")
                .contains("repeats")
        );
        assert!(
            err("[path]\nunits = \"m\"\npoints = [[0, 0, nan], [0, 0, 0.6]]\n")
                .contains("not finite")
        );
        assert!(err("[path]\nunits = \"mm\"\n").contains("exactly one"));
        // A fourth coordinate is a mistake, not dropped; so is a second.
        let four = "[path]\nunits = \"mm\"\npoints = [[0, 0, 600],\n [10, 0, 600, 5]]\n";
        let e = err(four);
        assert!(e.contains("job:4") && e.contains("found 4"), "{e}");
        let two = "[path]\nunits = \"mm\"\npoints = [[0, 0, 600], [10, 0]]\n";
        assert!(err(two).contains("found 2"), "{}", err(two));
        let both =
            "[path]\nunits = \"mm\"\nfile = \"a.csv\"\npoints = [[0, 0, 600], [1, 0, 600]]\n";
        assert!(err(both).contains("exactly one"));
    }

    #[test]
    fn points_from_a_file_beside_the_job() {
        let dir = std::env::temp_dir().join(format!("triquint-jobfile-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(
            dir.join("pts.csv"),
            "x,y,z\n# a comment\n0, 0, 600\n10 0 600 # trailing\n20,0,610\n",
        )
        .unwrap();
        std::fs::write(dir.join("bad.csv"), "0,0,600\n10,0\n").unwrap();
        let job_path = dir.join("job.toml");
        std::fs::write(&job_path, "[path]\nunits = \"mm\"\nfile = \"pts.csv\"\n").unwrap();
        let job = Job::load(&job_path).unwrap();
        assert_eq!(job.points_m().len(), 3);
        assert!((job.points_m()[2][2] - 0.61).abs() < 1e-12);
        std::fs::write(&job_path, "[path]\nunits = \"mm\"\nfile = \"bad.csv\"\n").unwrap();
        let e = Job::load(&job_path).unwrap_err();
        assert!(
            matches!(e, PlanError::JobFile { line: Some(2), .. }),
            "{e:?}"
        );
        assert!(
            e.to_string()
                .ends_with("bad.csv:2: expected 3 values (x, y, z), found 2"),
            "{e}"
        );
        std::fs::write(&job_path, "[path]\nunits = \"mm\"\nfile = \"none.csv\"\n").unwrap();
        assert!(
            Job::load(&job_path)
                .unwrap_err()
                .to_string()
                .contains("none.csv")
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
