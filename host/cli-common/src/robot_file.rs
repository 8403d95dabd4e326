//! `--robot FILE.toml`: machine parameters overriding the paper's Table 1,
//! shared by `triquint` and `triquint-sim`, and its `[homing]` table: the
//! switch heights and homing limits, in one place for the host (which
//! configures the drives with them) and the simulator (whose guideways
//! have their switches there).

use std::path::Path;

use serde::Deserialize;
use triquint_shared::Robot;
use triquint_shared::protocol::config::HomingSettings;

use crate::exit::{CliError, CliResult};
use crate::input::{MAX_ROBOT_BYTES, read_text};
use crate::output::io_reason;

/// The `[homing]` table (SI units); every key optional, defaults from
/// [`HomingSettings::default`].
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct HomingTable {
    velocity: Option<f64>,
    acceleration: Option<f64>,
    jerk: Option<f64>,
    direction: Option<f64>,
    /// One height for every axis, or one per axis.
    switch_height: Option<Heights>,
    backoff: Option<f64>,
    max_travel: Option<f64>,
    timeout: Option<f64>,
    following_error_max: Option<f64>,
    max_skew: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(untagged)]
enum Heights {
    One(f64),
    Each([f64; 3]),
}

#[derive(Debug, Default, Deserialize)]
struct HomingOnly {
    #[serde(default)]
    homing: Option<HomingTable>,
}

impl HomingTable {
    fn settings(self) -> Result<HomingSettings, String> {
        let d = HomingSettings::default();
        let h = HomingSettings {
            velocity: self.velocity.unwrap_or(d.velocity),
            acceleration: self.acceleration.unwrap_or(d.acceleration),
            jerk: self.jerk.unwrap_or(d.jerk),
            direction: self.direction.unwrap_or(d.direction),
            switch_height: match self.switch_height {
                None => d.switch_height,
                Some(Heights::One(x)) => [x; 3],
                Some(Heights::Each(x)) => x,
            },
            backoff: self.backoff.unwrap_or(d.backoff),
            max_travel: self.max_travel.unwrap_or(d.max_travel),
            timeout: self.timeout.unwrap_or(d.timeout),
            following_error_max: self.following_error_max.unwrap_or(d.following_error_max),
            max_skew: self.max_skew.unwrap_or(d.max_skew),
        };
        let positive = [
            ("velocity", h.velocity),
            ("acceleration", h.acceleration),
            ("jerk", h.jerk),
            ("max_travel", h.max_travel),
            ("timeout", h.timeout),
            ("following_error_max", h.following_error_max),
            ("max_skew", h.max_skew),
        ];
        for (k, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(format!("[homing] {k} = {v}: must be a positive number"));
            }
        }
        if h.direction != 1.0 && h.direction != -1.0 {
            return Err(format!(
                "[homing] direction = {}: must be 1 or -1",
                h.direction
            ));
        }
        if !(h.backoff.is_finite() && h.backoff >= 0.0) {
            return Err(format!("[homing] backoff = {}: must be ≥ 0", h.backoff));
        }
        if h.switch_height.iter().any(|x| !x.is_finite()) {
            return Err("[homing] switch_height: must be finite".to_string());
        }
        Ok(h)
    }
}

/// The text with its `[homing]` table blanked out (lines kept, so the
/// robot's errors keep their line numbers).
fn without_homing(text: &str) -> String {
    let mut inside = false;
    text.lines()
        .map(|l| {
            let t = l.trim_start();
            if t.starts_with('[') {
                inside = t.starts_with("[homing]");
            }
            if inside { "" } else { l }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// The robot and its homing settings from a `--robot` file (or the defaults).
pub fn read_machine(path: Option<&Path>) -> Result<(Robot, HomingSettings), String> {
    let Some(path) = path else {
        return Ok((Robot::default(), HomingSettings::default()));
    };
    let text = read_text(path, MAX_ROBOT_BYTES, "a robot file")
        .map_err(|e| format!("{}: {}", path.display(), io_reason(&e)))?;
    let err = |e: toml::de::Error| format!("{}: {}", path.display(), one_line(&e.to_string()));
    let robot = toml::from_str::<Robot>(&without_homing(&text)).map_err(err)?;
    robot.validate().map_err(|e| e.to_string())?;
    let homing = toml::from_str::<HomingOnly>(&text)
        .map_err(err)?
        .homing
        .unwrap_or_default()
        .settings()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    Ok((robot, homing))
}

/// [`read_machine`] with the error as bad input (exit 2).
pub fn load_machine(path: Option<&Path>) -> CliResult<(Robot, HomingSettings)> {
    read_machine(path).map_err(CliError::bad_input)
}

/// Reads a TOML file that sets any of [`Robot`]'s fields (unknown keys rejected
/// with line and column); without a file, the paper's Table 1. The error is
/// one line naming the file.
pub fn read_robot(path: Option<&Path>) -> Result<Robot, String> {
    read_machine(path).map(|(robot, _)| robot)
}

/// [`read_robot`] with the error as bad input (exit 2).
pub fn load_robot(path: Option<&Path>) -> CliResult<Robot> {
    read_robot(path).map_err(CliError::bad_input)
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

    fn file(name: &str, text: &str) -> std::path::PathBuf {
        let p =
            std::env::temp_dir().join(format!("triquint-robot-{}-{name}.toml", std::process::id()));
        std::fs::write(&p, text).unwrap();
        p
    }

    #[test]
    fn homing_table_is_read_with_the_robot() {
        let p = file(
            "ok",
            "lead = 0.012\n[homing]\nswitch_height = [0.40, 0.41, 0.42]\nvelocity = 0.02\n",
        );
        let (robot, h) = read_machine(Some(&p)).unwrap();
        assert_eq!(robot.lead, 0.012);
        assert_eq!(h.switch_height, [0.40, 0.41, 0.42]);
        assert_eq!(h.velocity, 0.02);
        assert_eq!(h.backoff, HomingSettings::default().backoff);
        let p = file("one", "[homing]\nswitch_height = 0.5\n");
        assert_eq!(read_machine(Some(&p)).unwrap().1.switch_height, [0.5; 3]);
        // Unknown keys, in either table, name their line.
        let p = file("bad", "lead = 0.01\n[homing]\nspeed = 1\n");
        let e = read_machine(Some(&p)).unwrap_err();
        assert!(e.contains("speed") && e.contains("line 3"), "{e}");
        let p = file("bad2", "[homing]\nvelocity = 1\n[other]\nx = 1\n");
        assert!(read_machine(Some(&p)).is_err());
        let p = file("neg", "[homing]\nvelocity = -1\n");
        assert!(read_machine(Some(&p)).unwrap_err().contains("velocity"));
    }
}
