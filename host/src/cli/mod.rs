//! One module per `triquint` subcommand.

pub mod check;
pub mod fk;
pub mod ik;
pub mod monitor;
pub mod move_to;
pub mod plan;
pub mod report;
pub mod simulate;
pub mod torque;
pub mod upload;

use nalgebra::Vector3;

use crate::exit::{CliError, CliResult};

/// Parses "a,b,c" into three finite numbers, naming the option on error.
pub fn parse_triple(option: &str, text: &str) -> CliResult<Vector3<f64>> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(CliError::bad_input(format!(
            "{option}: expected three comma-separated numbers, got {} in `{text}`",
            parts.len()
        )));
    }
    let mut v = Vector3::zeros();
    for (i, p) in parts.iter().enumerate() {
        v[i] = finite(&format!("{option} value {}", i + 1), p)?;
    }
    Ok(v)
}

/// Parses one finite number, naming what it is on error.
pub fn finite(what: &str, text: &str) -> CliResult<f64> {
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) => Err(CliError::bad_input(format!(
            "{what}: `{text}` is {x}, not a finite number"
        ))),
        Err(_) => Err(CliError::bad_input(format!(
            "{what}: `{text}` is not a number"
        ))),
    }
}

/// Prints three values with labels and a unit, for people.
pub fn fmt_triple(labels: [&str; 3], v: &Vector3<f64>, decimals: usize) -> String {
    (0..3)
        .map(|i| format!("{} {:>10.*}", labels[i], decimals, v[i]))
        .collect::<Vec<_>>()
        .join("  ")
}

/// With `--robot FILE`, a plan made for another robot is bad input: the
/// error names the first parameter that differs.
pub fn same_robot(robot_file: Option<&std::path::Path>, plan: &std::path::Path) -> CliResult {
    let Some(file) = robot_file else {
        return Ok(());
    };
    let robot = crate::robot_file::load_robot(Some(file))?;
    let p = load_plan(plan)?;
    if p.robot == robot {
        return Ok(());
    }
    let (a, b) = (
        serde_json::to_value(&p.robot).unwrap_or_default(),
        serde_json::to_value(&robot).unwrap_or_default(),
    );
    let field = a
        .as_object()
        .and_then(|m| m.iter().find(|(k, v)| b.get(k.as_str()) != Some(*v)))
        .map(|(k, v)| {
            format!(
                "`{k}` is {v} in the plan, {} in {}",
                b[k.as_str()],
                file.display()
            )
        })
        .unwrap_or_default();
    Err(CliError::bad_input(format!(
        "{}: planned for another robot than {}: {field}",
        plan.display(),
        file.display()
    )))
}

/// Reads a plan file through the planner's one loader; any failure is bad
/// input (exit 2), with the path in the one-line message.
pub fn load_plan(path: &std::path::Path) -> CliResult<triquint_planner::Plan> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| CliError::bad_input(format!("{}: {e}", path.display())))?;
    triquint_planner::parse_plan(&text)
        .map_err(|e| CliError::bad_input(format!("{}: not a valid plan: {e}", path.display())))
}
