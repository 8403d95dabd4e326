//! One module per `triquint` subcommand, and what several of them share
//! of the terminal: `bus_args`, `keys`, `terminal_watch`, `status_text`,
//! `upload_summary`, `feed` (the feed commands' one run).

pub mod bus_args;
pub mod check;
pub mod clear;
pub mod configure;
pub mod drives_args;
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
pub mod resonance;
pub mod resume;
pub mod simulate;
pub mod status;
pub mod status_text;
pub mod stop;
pub mod terminal_watch;
pub mod torque;
pub mod upload;
pub mod upload_summary;

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

/// Reads a plan file through the planner's one loader; any failure is bad
/// input (exit 2), with the path in the one-line message.
pub fn load_plan(path: &std::path::Path) -> CliResult<triquint_planner::Plan> {
    let text =
        triquint_planner::read_text(path, triquint_planner::MAX_PLAN_BYTES, "a plan file")
            .map_err(|e| CliError::bad_input(format!("{}: {}", path.display(), io_reason(&e))))?;
    triquint_planner::files::parse_plan(&text)
        .map_err(|e| CliError::bad_input(format!("{}: not a valid plan: {e}", path.display())))
}

/// Refuses `--plot -`: plots are a folder of files, and `-` (standard
/// output, as `plan -o -` takes it) would become a folder named `-`.
pub fn check_plot_folder(dir: Option<&std::path::Path>) -> CliResult {
    match dir {
        Some(d) if d.as_os_str() == "-" => Err(CliError::bad_input(
            "--plot -: plots are SVG files in a folder, not standard output; give a folder name"
                .to_string(),
        )),
        _ => Ok(()),
    }
}

/// Text from the command line as quoted in an error: at most 32
/// characters, so a pasted blob keeps the message one short line.
pub fn shortened(text: &str) -> String {
    match text.char_indices().nth(32) {
        Some((cut, _)) => format!("{}…", &text[..cut]),
        None => text.to_string(),
    }
}
