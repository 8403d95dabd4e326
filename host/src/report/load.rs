//! Reading a plan file and checking what serde cannot: format tag, counts,
//! finite positive durations, finite coefficients, valid robot and limits.

use std::path::Path;

use triquint_shared::plan::{PLAN_FORMAT, Plan};

use super::ReportError;
use crate::exit::{CliError, CliResult};

/// Parses and validates plan JSON (serde errors keep their line and column).
pub fn parse_plan(text: &str) -> Result<Plan, ReportError> {
    let plan: Plan = serde_json::from_str(text).map_err(|e| ReportError::Invalid(e.to_string()))?;
    validate_plan(&plan)?;
    Ok(plan)
}

/// Structural checks every tool reading a plan relies on.
pub fn validate_plan(plan: &Plan) -> Result<(), ReportError> {
    let bad = |m: String| Err(ReportError::Invalid(m));
    if plan.format != PLAN_FORMAT {
        return bad(format!(
            "format is `{}`, expected `{PLAN_FORMAT}`",
            plan.format
        ));
    }
    let n = plan.segments.len();
    if n == 0 {
        return bad("no segments".into());
    }
    if plan.intervals_s.len() != n {
        return bad(format!(
            "{} intervals for {n} segments",
            plan.intervals_s.len()
        ));
    }
    for (name, len) in [
        ("via_points_m", plan.via_points_m.len()),
        ("knots_m", plan.knots_m.len()),
    ] {
        if len != n + 1 {
            return bad(format!(
                "{name} has {len} points for {n} segments (expected {})",
                n + 1
            ));
        }
    }
    for (i, s) in plan.segments.iter().enumerate() {
        if !(s.duration_s.is_finite() && s.duration_s > 0.0) {
            return bad(format!(
                "segment {} duration_s is {}, not finite and > 0",
                i + 1,
                s.duration_s
            ));
        }
        if !s.t0_s.is_finite() || s.coeffs.iter().flatten().any(|c| !c.is_finite()) {
            return bad(format!("segment {} has a non-finite number", i + 1));
        }
    }
    let finite = |p: &[f64; 3]| p.iter().all(|x| x.is_finite());
    if !plan.via_points_m.iter().all(finite) || !plan.knots_m.iter().all(finite) {
        return bad("a via point or knot is not finite".into());
    }
    plan.robot
        .validate()
        .map_err(|e| ReportError::Invalid(e.to_string()))?;
    plan.limits
        .validate()
        .map_err(|e| ReportError::Invalid(e.to_string()))?;
    Ok(())
}

/// Reads and validates a plan file; any failure is bad input (exit 2), with
/// the path in the one-line message.
pub fn load_plan(path: &Path) -> CliResult<Plan> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::bad_input(format!("{}: {e}", path.display())))?;
    parse_plan(&text).map_err(|e| CliError::bad_input(format!("{}: {e}", path.display())))
}
