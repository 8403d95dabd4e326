//! The plan time the drives have reached, as the host estimates it from
//! what they report: it advances at the feed override while no drive
//! reports a hold, and stands still while one does. The upload's deadline
//! for finishing follows it, so a long hold or a slow override is not a
//! timeout.

use triquint_shared::protocol::flags;

use super::nodes::Nodes;

/// Rate assumed for an override a drive reports without the host knowing
/// its value (a drive whose answer to Arm does not carry it): the slowest
/// the drives take (1 per mille), so the deadline errs late, never early;
/// a drive that falls silent still ends the session.
const UNKNOWN_OVERRIDE: f64 = 0.001;

#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PlanClock {
    /// Estimated plan time reached (µs).
    plan_us: f64,
    /// Host time of the last update (µs; 0 before the start).
    last_us: u64,
    /// The override the drives hold (per mille; acknowledged, or from Arm).
    pub override_permille: Option<u32>,
    /// Whether any drive reported a hold at the last update.
    pub held: bool,
}

impl PlanClock {
    /// Advances to host time `now` (from the start `start_us` on).
    pub fn update(&mut self, now: u64, start_us: u64, nodes: &Nodes) {
        if start_us == 0 || now <= start_us {
            return;
        }
        let from = self.last_us.max(start_us);
        self.held = nodes.any(|v| v.flags & flags::HELD != 0);
        let overridden = nodes.any(|v| v.flags & flags::OVERRIDE != 0);
        let rate = match (self.held, overridden, self.override_permille) {
            (true, _, _) => 0.0,
            (false, false, _) => 1.0,
            (false, true, Some(pm)) => pm as f64 / 1000.0,
            (false, true, None) => UNKNOWN_OVERRIDE,
        };
        self.plan_us += now.saturating_sub(from) as f64 * rate;
        self.last_us = now;
    }

    /// Estimated plan time reached (µs).
    pub fn plan_us(&self) -> u64 {
        self.plan_us as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use triquint_shared::protocol::NODES;

    #[test]
    fn stands_still_while_held_and_follows_the_override() {
        let mut nodes = Nodes::new(NODES);
        let mut c = PlanClock::default();
        c.update(500, 1000, &nodes);
        assert_eq!(c.plan_us(), 0, "before the start");
        c.update(2000, 1000, &nodes);
        assert_eq!(c.plan_us(), 1000);
        nodes.0[1].flags = flags::HELD;
        c.update(10_000_000, 1000, &nodes);
        assert_eq!(c.plan_us(), 1000, "held");
        nodes.0[1].flags = flags::OVERRIDE;
        c.override_permille = Some(500);
        c.update(10_002_000, 1000, &nodes);
        assert_eq!(c.plan_us(), 2000, "half speed");
        c.override_permille = None;
        c.update(10_012_000, 1000, &nodes);
        assert_eq!(c.plan_us(), 2010, "unknown override: the slowest");
    }
}
