//! `--machine FILE.toml` (alias `--robot`): the machine file both binaries
//! and the Python package read (docs/machine.md). Tables `[robot]`,
//! `[homing]`, `[drive]`, `[axis.1]`…`[axis.3]` and `[ceilings]`, every key
//! optional with the paper machine's value as default; unknown keys and
//! values outside their range are refused with the key, the line and the
//! accepted range.

use std::collections::BTreeMap;
use std::path::Path;

use serde::Deserialize;
use triquint_shared::Robot;
use triquint_shared::machine::{Ceilings, Machine, MachineError};
use triquint_shared::readable::readable;

use crate::exit::{CliError, CliResult};
use crate::input::{MAX_MACHINE_BYTES, read_text};
use crate::output::io_reason;

/// Why a machine file was refused; each displays as one line.
#[derive(Debug, thiserror::Error)]
pub enum MachineFileError {
    #[error("{path}: {reason}")]
    Read { path: String, reason: String },
    /// Not TOML, an unknown key or table, or a value of the wrong type:
    /// the parser's message with its line.
    #[error("{0}")]
    Syntax(String),
    /// A robot parameter outside any table (the `--robot` files before
    /// the machine file put them there).
    #[error("line {line}: `{key}` is a robot parameter: it goes in the [robot] table")]
    OutsideRobotTable { key: String, line: usize },
    /// A value outside its range, or breaking a rule between values:
    /// the key as the file spells it (`axis.2.travel_max`, or
    /// `drive.current_limit` where that default set it).
    #[error("{}`{key}` = {}: {}", line.map_or(String::new(), |l| format!("line {l}: ")), readable(error.value), error.rule)]
    Value {
        key: String,
        line: Option<usize>,
        error: MachineError,
    },
}

/// The table a [`MachineError`]'s key belongs to, and the key within it.
fn table_and_key(e: &MachineError) -> (String, &'static str) {
    match (e.axis, e.key.split_once('.')) {
        (Some(n), _) => (format!("axis.{n}"), e.key),
        (None, Some((table, _))) => (table.to_string(), &e.key[table.len() + 1..]),
        (None, None) => ("robot".to_string(), e.key),
    }
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    robot: Option<Robot>,
    homing: Option<HomingTable>,
    drive: Option<DriveTable>,
    axis: Option<BTreeMap<String, AxisTable>>,
    ceilings: Option<CeilingsTable>,
    vibration: Option<VibrationTable>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct VibrationTable {
    screw_hz: Option<f64>,
    screw_damping: Option<f64>,
    platform_hz: Option<f64>,
    platform_damping: Option<f64>,
    current_loop_hz: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct HomingTable {
    velocity: Option<f64>,
    acceleration: Option<f64>,
    jerk: Option<f64>,
    direction: Option<f64>,
    backoff: Option<f64>,
    max_travel: Option<f64>,
    timeout: Option<f64>,
    following_error_max: Option<f64>,
    max_skew: Option<f64>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct DriveTable {
    bandwidth: Option<f64>,
    friction_coulomb: Option<f64>,
    friction_viscous: Option<f64>,
    following_error_max: Option<f64>,
    soft_limit_margin: Option<f64>,
    control_rate: Option<f64>,
    max_override: Option<f64>,
    /// Defaults for every axis.
    torque_constant: Option<f64>,
    current_limit: Option<f64>,
    brake: Option<bool>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct AxisTable {
    node_id: Option<u8>,
    counts_per_rev: Option<f64>,
    direction: Option<f64>,
    torque_constant: Option<f64>,
    current_limit: Option<f64>,
    switch_height: Option<f64>,
    travel_min: Option<f64>,
    travel_max: Option<f64>,
    brake: Option<bool>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct CeilingsTable {
    velocity: Option<f64>,
    acceleration: Option<f64>,
    jerk: Option<f64>,
    torque: Option<f64>,
}

fn set<T>(slot: &mut T, value: Option<T>) {
    if let Some(v) = value {
        *slot = v;
    }
}

/// Parses a machine file's text: the default machine with the file's values.
///
/// ```
/// let m = triquint_cli_common::machine_file::parse_machine(
///     "[robot]\nlead = 0.005\n[axis.2]\ncounts_per_rev = 4096\n",
/// ).unwrap();
/// assert_eq!(m.counts_per_metre(1), 4096.0 / 0.005);
/// let e = triquint_cli_common::machine_file::parse_machine("[axis.1]\ndirection = 2\n");
/// assert_eq!(e.unwrap_err().to_string(), "line 2: `axis.1.direction` = 2: must be 1 or -1");
/// ```
pub fn parse_machine(text: &str) -> Result<Machine, MachineFileError> {
    if let Some((key, line)) = robot_key_outside_a_table(text) {
        return Err(MachineFileError::OutsideRobotTable { key, line });
    }
    let file: File =
        toml::from_str(text).map_err(|e| MachineFileError::Syntax(one_line(&e.to_string())))?;
    let mut m = Machine::default();
    if let Some(r) = file.robot {
        m.robot = r;
    }
    let h = file.homing.unwrap_or_default();
    let hs = &mut m.homing;
    set(&mut hs.velocity, h.velocity);
    set(&mut hs.acceleration, h.acceleration);
    set(&mut hs.jerk, h.jerk);
    set(&mut hs.direction, h.direction);
    set(&mut hs.backoff, h.backoff);
    set(&mut hs.max_travel, h.max_travel);
    set(&mut hs.timeout, h.timeout);
    set(&mut hs.following_error_max, h.following_error_max);
    set(&mut hs.max_skew, h.max_skew);
    let d = file.drive.unwrap_or_default();
    let t = &mut m.drive;
    set(&mut t.bandwidth, d.bandwidth);
    set(&mut t.friction_coulomb, d.friction_coulomb);
    set(&mut t.friction_viscous, d.friction_viscous);
    set(&mut t.following_error_max, d.following_error_max);
    set(&mut t.soft_limit_margin, d.soft_limit_margin);
    set(&mut t.control_rate, d.control_rate);
    set(&mut t.max_override, d.max_override);
    for a in &mut m.axes {
        set(&mut a.torque_constant, d.torque_constant);
        set(&mut a.brake, d.brake);
        if d.current_limit.is_some() {
            a.current_limit = d.current_limit;
        }
    }
    for (name, ax) in file.axis.unwrap_or_default() {
        let n = match name.as_str() {
            "1" => 0,
            "2" => 1,
            "3" => 2,
            _ => {
                return Err(MachineFileError::Syntax(format!(
                    "{}[axis.{}]: the axes are 1, 2 and 3",
                    header_line(text, &format!("[axis.{name}]"))
                        .map_or(String::new(), |l| format!("line {l}: ")),
                    name.escape_default()
                )));
            }
        };
        let a = &mut m.axes[n];
        set(&mut a.node_id, ax.node_id);
        set(&mut a.counts_per_rev, ax.counts_per_rev);
        set(&mut a.direction, ax.direction);
        set(&mut a.torque_constant, ax.torque_constant);
        if ax.current_limit.is_some() {
            a.current_limit = ax.current_limit;
        }
        set(&mut a.switch_height, ax.switch_height);
        set(&mut a.travel_min, ax.travel_min);
        set(&mut a.travel_max, ax.travel_max);
        set(&mut a.brake, ax.brake);
    }
    let c = file.ceilings.unwrap_or_default();
    let cs: &mut Ceilings = &mut m.ceilings;
    set(&mut cs.velocity, c.velocity);
    set(&mut cs.acceleration, c.acceleration);
    set(&mut cs.jerk, c.jerk);
    set(&mut cs.torque, c.torque);
    let v = file.vibration.unwrap_or_default();
    let vs = &mut m.vibration;
    set(&mut vs.screw_hz, v.screw_hz);
    set(&mut vs.screw_damping, v.screw_damping);
    set(&mut vs.platform_hz, v.platform_hz);
    set(&mut vs.platform_damping, v.platform_damping);
    set(&mut vs.current_loop_hz, v.current_loop_hz);
    m.validate().map_err(|error| {
        let (table, key) = table_and_key(&error);
        // An axis key may have come from its machine-wide default.
        let (table, line) = match key_line(text, &table, key) {
            None if table.starts_with("axis.") && key_line(text, "drive", key).is_some() => {
                ("drive".to_string(), key_line(text, "drive", key))
            }
            line => (table, line),
        };
        MachineFileError::Value {
            key: format!("{table}.{key}"),
            line,
            error,
        }
    })?;
    Ok(m)
}

/// Reads a machine file; without one, the default machine.
pub fn read_machine(path: Option<&Path>) -> Result<Machine, MachineFileError> {
    let Some(path) = path else {
        return Ok(Machine::default());
    };
    let text = read_text(path, MAX_MACHINE_BYTES, "a machine file").map_err(|e| {
        MachineFileError::Read {
            path: path.display().to_string(),
            reason: io_reason(&e),
        }
    })?;
    parse_machine(&text).map_err(|e| match e {
        MachineFileError::Read { .. } => e,
        e => MachineFileError::Read {
            path: path.display().to_string(),
            reason: e.to_string(),
        },
    })
}

/// [`read_machine`] with the error as bad input (exit 2).
pub fn load_machine(path: Option<&Path>) -> CliResult<Machine> {
    read_machine(path).map_err(|e| CliError::bad_input(e.to_string()))
}

/// The first top-level `key = value` line naming a robot parameter, as
/// the `--robot` files before the machine file wrote them.
fn robot_key_outside_a_table(text: &str) -> Option<(String, usize)> {
    let fields = toml::Value::try_from(Robot::default()).ok()?;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.starts_with('[') {
            return None;
        }
        if let Some((k, _)) = t.split_once('=') {
            let k = k.trim();
            if fields.get(k).is_some() {
                return Some((k.to_string(), i + 1));
            }
        }
    }
    None
}

/// The 1-based line of a table header such as `[axis.2]`.
fn header_line(text: &str, header: &str) -> Option<usize> {
    text.lines()
        .position(|l| l.trim().replace(' ', "") == header)
        .map(|i| i + 1)
}

/// The 1-based line where `key` is set in `[table]`, if written there as
/// `key = value` (the default's key has none).
fn key_line(text: &str, table: &str, key: &str) -> Option<usize> {
    let header = format!("[{table}]");
    let mut inside = false;
    for (i, line) in text.lines().enumerate() {
        let t = line.trim();
        if t.starts_with('[') {
            inside = t.replace(' ', "") == header;
        } else if inside
            && let Some((k, _)) = t.split_once('=')
            && k.trim() == key
        {
            return Some(i + 1);
        }
    }
    None
}

/// Folds a multi-line parser message (toml prints a source excerpt) into one line.
pub fn one_line(msg: &str) -> String {
    msg.lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !is_excerpt(l))
        .collect::<Vec<_>>()
        .join(" ")
}

/// A source-excerpt line of a parser message: `|`, `3 | key = 1`, or `^^^`.
fn is_excerpt(line: &str) -> bool {
    let rest = line
        .trim_start_matches(|c: char| c.is_ascii_digit())
        .trim_start();
    rest.starts_with('|') || line.chars().all(|c| c == '^' || c == ' ')
}

#[cfg(test)]
mod tests {
    use super::*;

    fn err(text: &str) -> String {
        parse_machine(text).unwrap_err().to_string()
    }

    #[test]
    fn every_table_is_read() {
        let m = parse_machine(
            "[robot]\nlead = 0.012\n[homing]\nvelocity = 0.02\n[drive]\nbandwidth = 8\n\
             torque_constant = 0.05\n[axis.2]\ncounts_per_rev = 4096\ndirection = -1\n\
             switch_height = 0.41\ntravel_max = 0.40\n[ceilings]\njerk = 20\n",
        )
        .unwrap();
        assert_eq!(m.robot.lead, 0.012);
        assert_eq!(m.homing.velocity, 0.02);
        assert_eq!(m.drive.bandwidth, 8.0);
        assert_eq!(m.axes.each_ref().map(|a| a.torque_constant), [0.05; 3]);
        assert_eq!(m.counts_per_metre(1), -4096.0 / 0.012);
        assert_eq!(m.homing_settings().switch_height, [0.42, 0.41, 0.42]);
        assert_eq!(m.travel().max, [0.415, 0.40, 0.415]);
        assert_eq!(m.ceilings.jerk, 20.0);
        assert_eq!(parse_machine("").unwrap(), Machine::default());
    }

    #[test]
    fn the_vibration_table_is_read_and_held_to_its_ranges() {
        let m = parse_machine("[vibration]\nplatform_hz = 42\nscrew_damping = 0.08\n").unwrap();
        assert_eq!(m.vibration.platform_hz, 42.0);
        assert_eq!(m.vibration.screw_damping, 0.08);
        assert_eq!(m.vibration.screw_hz, Machine::default().vibration.screw_hz);
        assert_eq!(
            err("[vibration]\nscrew_hz = 60\nplatform_damping = 1.5\n"),
            "line 3: `vibration.platform_damping` = 1.5: must be in 0..0.99"
        );
        assert!(err("[vibration]\nmode_hz = 3\n").contains("unknown field"));
    }

    #[test]
    fn the_override_limit_is_read_held_to_its_range_and_configured() {
        let m = parse_machine("[drive]\nmax_override = 1.0\n").unwrap();
        assert_eq!(m.drive.max_override, 1.0);
        assert_eq!(m.drive_settings().max_override, 1.0);
        assert_eq!(Machine::default().drive_settings().max_override, 32.0);
        assert_eq!(
            err("[drive]\nmax_override = 0.5\n"),
            "line 2: `drive.max_override` = 0.5: must be in 1..32 (σ, 1 = 100 %)"
        );
    }

    #[test]
    fn brakes_are_read_per_axis_over_the_drive_default_and_configured() {
        let m = parse_machine("[drive]\nbrake = true\n[axis.2]\nbrake = false\n").unwrap();
        assert_eq!(m.axes.each_ref().map(|a| a.brake), [true, false, true]);
        assert_eq!(m.drive_settings().brake, [true, false, true]);
        let e = err("[axis.1]\nbrake = 1\n");
        assert!(e.contains("line 2") && e.contains("boolean"), "{e}");
        assert!(!Machine::default().axes.iter().any(|a| a.brake));
    }

    #[test]
    fn refusals_name_the_key_the_line_and_the_range() {
        assert_eq!(
            err("[axis.3]\nnode_id = 3\ntravel_max = 0.418\n"),
            "line 3: `axis.3.travel_max` = 0.418: must leave the homing back-off before the switch \
             (switch_height − homing.backoff above it, or + below)"
        );
        let e = err("[drive]\nbandwidth = 500\n");
        assert!(
            e.starts_with("line 2: `drive.bandwidth` = 500: must be in"),
            "{e}"
        );
        let e = err("[robot]\n\nlead = 0\n");
        assert!(e.starts_with("line 3: `robot.lead` = 0:"), "{e}");
        let e = err("[ceilings]\nvelocity = 1\nspeed = 2\n");
        assert!(e.contains("speed") && e.contains("line 3"), "{e}");
        let e = err("[axis.4]\ndirection = 1\n");
        assert_eq!(e, "line 1: [axis.4]: the axes are 1, 2 and 3");
        let e = err("lead = 0.01\n[homing]\n");
        assert_eq!(
            e,
            "line 1: `lead` is a robot parameter: it goes in the [robot] table"
        );
        let e = err("[drive]\ncurrent_limit = 1000\n");
        assert!(e.starts_with("line 2: `drive.current_limit` = 1000"), "{e}");
        assert!(!err("[homing]\nswitch_height = 0.5\n").contains('\n'));
    }
}
