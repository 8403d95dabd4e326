//! When a board feeds its hardware watchdog: only when both contexts of a
//! node have checked in since the last feed, the control tick (from its
//! timer interrupt) and the CAN side (from the receive task's executor),
//! so a hung tick or a hung CAN side both end in the watchdog's reset. The
//! timeout sits above the longest stall the node causes itself: a flash
//! erase of the configuration store (the flash stalls every fetch from it
//! while it erases), see `docs/measured-margins.md`.

/// The longest the configuration store stalls the node, in µs: one store
/// may erase both of its 2 KB pages (40 ms each at most) and program a
/// configuration (a few milliseconds).
pub const STORE_STALL_US: u32 = 85_000;

/// The watchdog's timeout, in µs: well above [`STORE_STALL_US`], and still
/// short against the time a runaway axis needs to reach its end stop.
pub const TIMEOUT_US: u32 = 250_000;

const _: () = assert!(TIMEOUT_US >= 2 * STORE_STALL_US);

/// How often a board offers to feed, in µs: several chances per timeout,
/// so one late check-in does not reset a healthy node.
pub const FEED_PERIOD_US: u32 = TIMEOUT_US / 10;

const _: () = assert!(TIMEOUT_US > STORE_STALL_US + FEED_PERIOD_US);
const _: () = assert!(TIMEOUT_US / FEED_PERIOD_US >= 4);

/// The feed policy: what checked in since the last feed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FeedPolicy {
    tick: bool,
    can: bool,
    feeds: u32,
}

impl FeedPolicy {
    pub const fn new() -> Self {
        Self {
            tick: false,
            can: false,
            feeds: 0,
        }
    }

    /// The control tick ran.
    pub fn tick_checked_in(&mut self) {
        self.tick = true;
    }

    /// The CAN side ran (its executor is not stuck).
    pub fn can_checked_in(&mut self) {
        self.can = true;
    }

    /// Whether to feed now: true only when both checked in since the last
    /// feed; a feed starts the next round with neither.
    pub fn take_feed(&mut self) -> bool {
        if self.tick && self.can {
            self.tick = false;
            self.can = false;
            self.feeds = self.feeds.wrapping_add(1);
            true
        } else {
            false
        }
    }

    /// Feeds so far.
    pub fn feeds(&self) -> u32 {
        self.feeds
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fed_only_when_both_checked_in_since_the_last_feed() {
        let mut p = FeedPolicy::new();
        assert!(!p.take_feed(), "nothing checked in");
        p.tick_checked_in();
        assert!(!p.take_feed(), "the CAN side did not check in");
        p.can_checked_in();
        assert!(p.take_feed());
        // The next round starts empty: the old check-ins do not count.
        assert!(!p.take_feed());
        p.can_checked_in();
        p.can_checked_in();
        assert!(!p.take_feed(), "the tick did not check in");
        p.tick_checked_in();
        assert!(p.take_feed());
        assert_eq!(p.feeds(), 2);
    }

    /// A hung tick: the CAN side keeps checking in, and the watchdog is
    /// never fed again, so it expires within its timeout.
    #[test]
    fn a_stopped_tick_or_can_side_stops_the_feeding() {
        for hung_tick in [true, false] {
            let mut p = FeedPolicy::new();
            let mut last_feed = 0u32;
            let mut t = 0u32;
            while t < 2 * TIMEOUT_US {
                let healthy = t < TIMEOUT_US / 2;
                if healthy || !hung_tick {
                    p.tick_checked_in();
                }
                if healthy || hung_tick {
                    p.can_checked_in();
                }
                if p.take_feed() {
                    last_feed = t;
                }
                t += FEED_PERIOD_US;
            }
            assert!(last_feed < TIMEOUT_US / 2, "fed after the hang");
        }
    }
}
