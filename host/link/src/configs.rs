//! The drives' configurations for a run: the same plan limits and robot for
//! every node, gains from the settings' bandwidth, and the stop ramps —
//! controlled stop T_s and quick stop T_q — long enough to bring the
//! largest velocity and acceleration of the motion to rest within the jerk
//! budget (`stop_time`, docs/protocol.md, Stopping); for a plan, the feed
//! override cap (`override_cap.rs`).

use triquint_shared::plan::{MaxAbs, Plan};
use triquint_shared::protocol::DriveConfig;
use triquint_shared::protocol::config::{DriveSettings, stop_time};
use triquint_shared::{Limits, Robot};

use crate::override_cap::{Maxima, override_scaling};

/// Why a plan's recorded maxima cannot size the stop ramps.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ConfigError {
    #[error("max_abs.{field} in the plan is {value}, not a finite number ≥ 0")]
    Maxima { field: &'static str, value: f64 },
    #[error("the plan records no maxima (max_abs all zero); plan it again with `triquint plan`")]
    NotRecorded,
}

/// The three nodes' configurations (node i + 1 drives axis i).
#[derive(Clone, Debug, PartialEq)]
pub struct DriveConfigs {
    pub nodes: [DriveConfig; 3],
    /// The controlled-stop ramp T_s every node is configured with (s).
    pub stop_time_s: f64,
    /// The feed-override cap every node is configured with (σ, 1–32).
    pub override_cap: f64,
}

impl DriveConfigs {
    /// For `plan`, from the exact maxima the planner recorded in it
    /// (`plan.max_abs`, continuous-time, re-verified by `triquint check`).
    pub fn for_plan(plan: &Plan, settings: &DriveSettings) -> Result<Self, ConfigError> {
        let [v, a, j] = largest(&plan.max_abs)?;
        // The override cap, and the stop ramps sized for a stop from it.
        let s = override_scaling(plan, Maxima { v, a, j });
        let (robot, limits) = (&plan.robot, &plan.limits);
        let (ts, tq) = (s.stop_time_s, s.quick_stop_time_s);
        Ok(Self {
            nodes: [0, 1, 2].map(|i| {
                let mut c = DriveConfig::new(robot, limits, i, settings, ts, tq);
                c.override_cap = s.cap as f32;
                c
            }),
            stop_time_s: ts,
            override_cap: s.cap,
        })
    }

    /// [`DriveConfigs::override_cap`] in per mille, as the drives' answers
    /// and the `+`/`-` keys count it.
    pub fn override_cap_permille(&self) -> u16 {
        (self.override_cap * 1000.0).round() as u16
    }

    /// For any motion within `limits` (before there is a plan, e.g. to
    /// configure drives so they report their position): the limits
    /// themselves as the maxima.
    pub fn for_limits(robot: &Robot, limits: &Limits, settings: &DriveSettings) -> Self {
        Self::from_maxima(
            robot,
            limits,
            settings,
            limits.velocity,
            limits.acceleration,
            limits.jerk,
        )
    }

    /// Stop ramps for a motion whose largest joint velocity, acceleration
    /// and jerk are `v`, `a`, `j`: T_s within the jerk limit (less the
    /// motion's own jerk, at least half of it), T_q at three times the limit.
    pub fn from_maxima(
        robot: &Robot,
        limits: &Limits,
        settings: &DriveSettings,
        v: f64,
        a: f64,
        j: f64,
    ) -> Self {
        let ts = stop_time(v, a, j, limits.jerk);
        let tq = stop_time(v, a, 0.0, 3.0 * limits.jerk);
        Self {
            nodes: [0, 1, 2].map(|i| DriveConfig::new(robot, limits, i, settings, ts, tq)),
            stop_time_s: ts,
            // No plan to scale: no override above 100 %.
            override_cap: 1.0,
        }
    }
}

/// Largest |v|, |a|, |jerk| over the three joints.
fn largest(m: &MaxAbs) -> Result<[f64; 3], ConfigError> {
    let mut out = [0.0f64; 3];
    for (k, (field, per_joint)) in [
        ("velocity", m.velocity),
        ("acceleration", m.acceleration),
        ("jerk", m.jerk),
    ]
    .into_iter()
    .enumerate()
    {
        for value in per_joint {
            if !(value.is_finite() && value >= 0.0) {
                return Err(ConfigError::Maxima { field, value });
            }
            out[k] = out[k].max(value);
        }
    }
    if out.iter().all(|x| *x == 0.0) {
        return Err(ConfigError::NotRecorded);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_and_maxima_give_the_same_ramps_for_the_same_numbers() {
        let (robot, limits, s) = (
            Robot::default(),
            Limits::default(),
            DriveSettings::default(),
        );
        let a = DriveConfigs::for_limits(&robot, &limits, &s);
        let b = DriveConfigs::from_maxima(
            &robot,
            &limits,
            &s,
            limits.velocity,
            limits.acceleration,
            limits.jerk,
        );
        assert_eq!(a, b);
        // A slower motion stops sooner; never below the 50 ms floor.
        let c = DriveConfigs::from_maxima(&robot, &limits, &s, 0.01, 0.01, 0.1);
        assert!(c.stop_time_s < a.stop_time_s && c.stop_time_s >= 0.05);
        assert!(
            c.nodes
                .iter()
                .zip(&a.nodes)
                .all(|(x, y)| x.crc() != y.crc())
        );
    }

    #[test]
    fn bad_maxima_are_named() {
        let mut m = MaxAbs::default();
        assert_eq!(largest(&m), Err(ConfigError::NotRecorded));
        m.velocity = [0.1, 0.3, 0.2];
        m.jerk[2] = f64::NAN;
        let e = largest(&m).unwrap_err();
        assert!(e.to_string().starts_with("max_abs.jerk"), "{e}");
        m.jerk = [1.0, 2.0, 0.5];
        assert_eq!(largest(&m), Ok([0.3, 0.0, 2.0]));
    }
}
