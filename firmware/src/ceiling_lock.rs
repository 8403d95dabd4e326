//! The ceiling lock: once a drive holds a configuration, a new one may
//! tighten its ceilings (`ceiling_*`) and travel (`soft_limit_min`,
//! `soft_limit_max`) but not raise or widen them, unless the host opened a
//! maintenance window first (`UnlockCeilings`, with the active
//! configuration's CRC, Idle only); a board's own stored configuration,
//! replayed at start, is not a host's and is taken as it is
//! (docs/safety.md, "The ceiling lock").

use triquint_shared::protocol::DriveConfig;
use triquint_shared::protocol::contract::MAINTENANCE_WINDOW_US;

/// One parameter of a configuration.
type Param = fn(&DriveConfig) -> f32;

/// Parameter indices of the locked bounds that may only go down.
const CEILINGS: [(u8, Param); 5] = [
    (40, |c| c.soft_limit_max),
    (55, |c| c.ceiling_velocity),
    (56, |c| c.ceiling_acceleration),
    (57, |c| c.ceiling_jerk),
    (58, |c| c.ceiling_torque),
];
/// Index of the travel's low end, which may only go up.
const TRAVEL_MIN: u8 = 39;

/// The index of the first locked parameter in which `new` is wider than
/// `active`: a ceiling or the travel's high end raised, its low end
/// lowered. None: `new` is as tight or tighter. A NaN counts as wider.
pub fn first_widening(active: &DriveConfig, new: &DriveConfig) -> Option<u8> {
    if !at_most(active.soft_limit_min, new.soft_limit_min) {
        return Some(TRAVEL_MIN);
    }
    CEILINGS
        .iter()
        .find(|(_, f)| !at_most(f(new), f(active)))
        .map(|(i, _)| *i)
}

/// x ≤ y, false with a NaN on either side.
fn at_most(x: f32, y: f32) -> bool {
    x.partial_cmp(&y).is_some_and(|o| o.is_le())
}

/// The maintenance window `UnlockCeilings` opens: until a local time (µs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Window {
    until_us: Option<u64>,
}

impl Window {
    /// Opens it at local time `now_us` for [`MAINTENANCE_WINDOW_US`].
    pub fn open(&mut self, now_us: u64) {
        self.until_us = Some(now_us.saturating_add(MAINTENANCE_WINDOW_US));
    }

    pub fn close(&mut self) {
        self.until_us = None;
    }

    /// Open at local time `now_us`?
    pub fn is_open(&self, now_us: u64) -> bool {
        self.until_us.is_some_and(|t| now_us < t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use triquint_shared::protocol::PARAMS;
    use triquint_shared::protocol::config::DriveSettings;
    use triquint_shared::{Limits, Robot};

    fn config() -> DriveConfig {
        DriveConfig::new(
            &Robot::default(),
            &Limits::default(),
            0,
            &DriveSettings::default(),
            0.8,
            0.3,
        )
    }

    #[test]
    fn the_indices_name_the_parameters_they_read() {
        let c = config();
        let v = c.to_values();
        for (i, f) in CEILINGS {
            assert_eq!(v[i as usize], f(&c), "{}", PARAMS[i as usize].name);
        }
        assert_eq!(PARAMS[TRAVEL_MIN as usize].name, "soft_limit_min");
        assert_eq!(PARAMS[40].name, "soft_limit_max");
        assert!(
            PARAMS[55..=58]
                .iter()
                .all(|p| p.name.starts_with("ceiling_"))
        );
    }

    #[test]
    fn tighter_or_equal_passes_and_each_widening_is_named() {
        let a = config();
        assert_eq!(first_widening(&a, &a), None);
        let mut tight = a;
        tight.ceiling_velocity *= 0.5;
        tight.ceiling_torque *= 0.5;
        tight.soft_limit_min += 0.01;
        tight.soft_limit_max -= 0.01;
        // Other parameters are not locked.
        tight.kp *= 3.0;
        tight.following_error_max *= 3.0;
        assert_eq!(first_widening(&a, &tight), None);
        // Back from tight to a is a widening.
        assert_eq!(first_widening(&tight, &a), Some(39));
        type Change = fn(&mut DriveConfig);
        let cases: [(Change, &str); 7] = [
            (|c| c.soft_limit_min -= 1e-6, "soft_limit_min"),
            (|c| c.soft_limit_max += 1e-6, "soft_limit_max"),
            (|c| c.ceiling_velocity *= 1.001, "ceiling_velocity"),
            (|c| c.ceiling_acceleration *= 1.001, "ceiling_acceleration"),
            (|c| c.ceiling_jerk *= 1.001, "ceiling_jerk"),
            (|c| c.ceiling_torque *= 1.001, "ceiling_torque"),
            (|c| c.ceiling_jerk = f32::NAN, "ceiling_jerk"),
        ];
        for (f, name) in cases {
            let mut w = a;
            f(&mut w);
            let i = first_widening(&a, &w).map(|i| PARAMS[i as usize].name);
            assert_eq!(i, Some(name));
        }
    }

    #[test]
    fn the_window_closes_on_time_and_on_demand() {
        let mut w = Window::default();
        assert!(!w.is_open(0));
        w.open(1_000);
        assert!(w.is_open(1_000) && w.is_open(MAINTENANCE_WINDOW_US + 999));
        assert!(!w.is_open(MAINTENANCE_WINDOW_US + 1_000));
        w.close();
        assert!(!w.is_open(1_001));
        w.open(u64::MAX - 1);
        assert!(w.is_open(u64::MAX - 1));
    }
}
