//! One module per `triquint` subcommand.

pub mod check;
pub mod clear;
pub mod estop;
pub mod feed;
pub mod feed_override;
pub mod fk;
pub mod hold;
pub mod home;
pub mod ik;
pub mod keys;
pub mod monitor;
pub mod move_to;
pub mod plan;
pub mod report;
pub mod resume;
pub mod simulate;
pub mod status;
pub mod stop;
pub mod torque;
pub mod upload;

use nalgebra::Vector3;

use triquint_cli_common::output::io_reason;
pub use triquint_cli_common::parse::{finite, parse_triple};

use crate::exit::{CliError, CliResult};

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
    let text =
        triquint_planner::read_text(path, triquint_planner::MAX_PLAN_BYTES, "a plan file")
            .map_err(|e| CliError::bad_input(format!("{}: {}", path.display(), io_reason(&e))))?;
    triquint_planner::files::parse_plan(&text)
        .map_err(|e| CliError::bad_input(format!("{}: not a valid plan: {e}", path.display())))
}

/// Text from the command line as quoted in an error: at most 32
/// characters, so a pasted blob keeps the message one short line.
pub fn shortened(text: &str) -> String {
    match text.char_indices().nth(32) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None => text.to_string(),
    }
}
