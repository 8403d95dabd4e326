//! What a shaped plan records (format 5, docs/plan-format.md): the shaper
//! it was convolved with and the unshaped plan, so that `check` can
//! convolve again and compare. The impulses themselves are the planner's.

use alloc::vec::Vec;
use core::fmt;
use core::str::FromStr;

use serde::{Deserialize, Serialize};

use super::{MaxAbs, Segment};

/// The input shapers of Klipper's `input_shaper` that are a few positive
/// impulses, by Klipper's names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum Shaper {
    /// Zero vibration: two impulses over half a period.
    #[serde(rename = "zv")]
    Zv,
    /// Modified ZV: three impulses over 3/4 of a period.
    #[serde(rename = "mzv")]
    Mzv,
    /// Zero vibration and derivative: three impulses over a period.
    #[serde(rename = "zvd")]
    Zvd,
    /// Extra insensitive (5 % tolerance): three impulses over a period.
    #[serde(rename = "ei")]
    Ei,
    /// Two-hump extra insensitive: four impulses over 1.5 periods.
    #[serde(rename = "2hump_ei")]
    TwoHumpEi,
}

impl Shaper {
    pub const ALL: [Shaper; 5] = [
        Shaper::Zv,
        Shaper::Mzv,
        Shaper::Zvd,
        Shaper::Ei,
        Shaper::TwoHumpEi,
    ];

    /// Klipper's name (`zv`, `mzv`, `zvd`, `ei`, `2hump_ei`).
    pub fn name(self) -> &'static str {
        match self {
            Shaper::Zv => "zv",
            Shaper::Mzv => "mzv",
            Shaper::Zvd => "zvd",
            Shaper::Ei => "ei",
            Shaper::TwoHumpEi => "2hump_ei",
        }
    }
}

impl fmt::Display for Shaper {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A name that is not one of [`Shaper::ALL`].
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("unknown shaper `{0}`: one of zv, mzv, zvd, ei, 2hump_ei")]
pub struct UnknownShaper(pub alloc::string::String);

impl FromStr for Shaper {
    type Err = UnknownShaper;
    /// Klipper's names, in any case, `-` for `_`.
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        let want = s.to_ascii_lowercase().replace('-', "_");
        Shaper::ALL
            .into_iter()
            .find(|k| k.name() == want)
            .ok_or_else(|| UnknownShaper(s.into()))
    }
}

/// Klipper's default damping ratio when none is given.
pub const DEFAULT_DAMPING: f64 = 0.1;

fn default_damping() -> f64 {
    DEFAULT_DAMPING
}

/// A shaper for a mode: the job's `[shaper]` table and the plan's record.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ShaperSpec {
    #[serde(rename = "type")]
    pub shaper: Shaper,
    pub frequency_hz: f64,
    /// The mode's damping ratio ([`DEFAULT_DAMPING`] if not given).
    #[serde(default = "default_damping")]
    pub damping: f64,
}

/// The unshaped plan inside a shaped one: its path, motion and total-time
/// limit, the rest (robot, the other limits, travel, ceilings, objective)
/// being the shaped plan's.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Unshaped {
    pub via_points_m: Vec<[f64; 3]>,
    pub knots_m: Vec<[f64; 3]>,
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub free_knots: Vec<usize>,
    pub intervals_s: Vec<f64>,
    pub total_time_s: f64,
    pub segments: Vec<Segment>,
    pub max_abs: MaxAbs,
    /// Its limit on the total time (s); the shaped plan's adds the shaper's
    /// duration.
    pub total_time_limit_s: f64,
    /// The slow-down s > 1 the planner gave its plan so that the shaped one
    /// streams: the planned intervals × s, rounded to whole microseconds and
    /// solved again at the same knots. Absent when the plan was not retimed.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub retimed: Option<f64>,
}

/// A shaped plan's record (format 5).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Shaping {
    pub shaper: ShaperSpec,
    pub unshaped: Unshaped,
}
