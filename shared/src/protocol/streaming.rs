//! Streamability: what a plan's segment durations need so that drives with
//! a queue of `capacity` segments never underrun while the host streams it
//! (docs/protocol.md, "Streamability").
//!
//! A drive faults with `Underrun` when the plan time it holds ahead falls
//! below its look-ahead L = T_s/2 + `underrun_margin` (at σ = 1) and its
//! last queued segment is not the plan's last. It holds at most `capacity`
//! segments; the slot segment i − 1 frees when it ends is refilled only
//! after the host learns of it (a SegmentAck or the next heartbeat) and
//! sends the next segment: the refill delay δ. So while segment i runs,
//! until δ after it began, the queue may end with segment i + capacity − 2.
//! The rule: every run of capacity − 1 consecutive segments that does not
//! end with the plan's last segment lasts at least L + δ. A plan of at most
//! `capacity` segments is queued whole before Start and always streams.
//!
//! [`StreamRule::for_plan`] is the rule a plan meets on the default
//! drives ([`QUEUE_CAPACITY`], the stop ramp the host configures for it,
//! `override_cap`): what `check` reports and the planner keeps to.

/// Segments a drive queues: the firmware's queue is this long, and the
/// planner and `check` hold plans to it (drives report their own capacity,
/// which `upload` checks against).
pub const QUEUE_CAPACITY: usize = 16;

/// The rule for one machine: queue capacity, look-ahead and refill delay.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamRule {
    /// Segments a drive queues.
    pub capacity: usize,
    /// Look-ahead L: plan time a drive must hold ahead (µs).
    pub lookahead_us: u64,
    /// Refill delay δ: a freed slot holds a new segment this long after (µs).
    pub refill_us: u64,
}

/// The first run of segments too short to stream.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shortfall {
    /// First and last segment of the run (0-based, inclusive).
    pub first: usize,
    pub last: usize,
    /// Its duration (µs).
    pub run_us: u64,
    /// What it needs, L + δ (µs).
    pub need_us: u64,
}

/// Allowance for putting one segment on the bus behind other traffic
/// (part of δ; a classic segment alone takes under 3 ms at 1 Mbit/s).
pub const SEGMENT_TRANSFER_US: u64 = 10_000;

impl StreamRule {
    /// The rule for drives of queue `capacity` configured with the stop
    /// ramp `stop_time_s`, `underrun_margin_s` and `heartbeat_period_s`
    /// (δ: a heartbeat period plus [`SEGMENT_TRANSFER_US`]).
    pub fn new(
        capacity: usize,
        stop_time_s: f64,
        underrun_margin_s: f64,
        heartbeat_period_s: f64,
    ) -> Self {
        let us = |s: f64| {
            if s.is_finite() && s > 0.0 {
                libm::ceil(s * 1e6) as u64
            } else {
                0
            }
        };
        Self {
            capacity,
            lookahead_us: us(0.5 * stop_time_s) + us(underrun_margin_s),
            refill_us: us(heartbeat_period_s) + SEGMENT_TRANSFER_US,
        }
    }

    /// The rule for `plan` on drives of queue `capacity` with `settings`:
    /// the stop ramp the host configures for the plan (sized for its
    /// override cap, [`crate::plan::override_cap`]) from the exact maxima
    /// of its segments. `None` when the plan has no motion or non-finite
    /// maxima (no ramp to size; nothing to stream).
    #[cfg(feature = "alloc")]
    pub fn for_plan(
        plan: &crate::plan::Plan,
        settings: &super::config::DriveSettings,
        capacity: usize,
    ) -> Option<Self> {
        use crate::plan::override_cap::{Maxima, override_scaling};
        let k = crate::plan::figures::kinematics(&plan.segments);
        let finite = [k.velocity, k.acceleration, k.jerk]
            .iter()
            .flatten()
            .all(|x| x.is_finite());
        let [v, a, j] = k.largest();
        if !finite || v + a + j == 0.0 {
            return None;
        }
        let s = override_scaling(plan, Maxima { v, a, j }, settings.max_override);
        let ts = super::segment_maxima::for_plan(plan, settings, &s).stop_time_s;
        Some(Self::new(
            capacity,
            ts,
            settings.underrun_margin,
            settings.heartbeat_period,
        ))
    }

    /// What every run of `capacity − 1` segments needs, L + δ (µs).
    pub fn need_us(&self) -> u64 {
        self.lookahead_us.saturating_add(self.refill_us)
    }

    /// The shortest run of `capacity − 1` segments that does not end
    /// with the plan's last (the first of equal ones), from the segment
    /// durations (µs, in order); `None` when the plan fits the queue whole.
    pub fn shortest_run(&self, durations_us: &[u32]) -> Option<Shortfall> {
        let n = durations_us.len();
        if n <= self.capacity {
            return None;
        }
        let w = self.capacity.saturating_sub(1);
        // Runs d[i .. i + w] with i + w < n; n > capacity, so at least one.
        let mut run: u64 = durations_us[..w].iter().map(|&d| d as u64).sum();
        let mut best: Option<Shortfall> = None;
        for i in 0..n - w {
            if i > 0 && w > 0 {
                run = run - durations_us[i - 1] as u64 + durations_us[i + w - 1] as u64;
            }
            if best.is_none_or(|b| run < b.run_us) {
                best = Some(Shortfall {
                    first: i,
                    last: i + w.max(1) - 1,
                    run_us: run,
                    need_us: self.need_us(),
                });
            }
        }
        best
    }

    /// Checks a plan's segment durations (µs, in order) against the rule:
    /// the shortest run, if it is too short.
    pub fn check(&self, durations_us: &[u32]) -> Result<(), Shortfall> {
        match self.shortest_run(durations_us) {
            Some(s) if s.run_us < s.need_us => Err(s),
            _ => Ok(()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::vec::Vec;

    fn rule(capacity: usize) -> StreamRule {
        StreamRule {
            capacity,
            lookahead_us: 700_000,
            refill_us: 110_000,
        }
    }

    /// The rule by brute force: the shortest window of capacity − 1
    /// segments whose last is not the plan's last, if too short.
    fn brute(r: &StreamRule, d: &[u32]) -> Option<usize> {
        if d.len() <= r.capacity {
            return None;
        }
        let w = r.capacity - 1;
        let sum = |i: usize| d[i..i + w].iter().map(|&x| x as u64).sum::<u64>();
        let i = (0..d.len() - w).min_by_key(|&i| (sum(i), i))?;
        (sum(i) < r.need_us()).then_some(i)
    }

    #[test]
    fn sliding_window_agrees_with_brute_force() {
        let mut x: u32 = 12345;
        for case in 0..2000 {
            let cap = 1 + case % 12;
            let n = case % 40;
            let d: Vec<u32> = (0..n)
                .map(|_| {
                    x = x.wrapping_mul(1_103_515_245).wrapping_add(12_345);
                    1 + (x >> 8) % 300_000
                })
                .collect();
            let r = rule(cap);
            let got = r.check(&d).err().map(|s| s.first);
            assert_eq!(got, brute(&r, &d), "cap {cap}, {d:?}");
            if let Err(s) = r.check(&d) {
                let sum: u64 = d[s.first..=s.last].iter().map(|&x| x as u64).sum();
                assert_eq!(s.run_us, if cap > 1 { sum } else { 0 });
                assert_eq!(s.last - s.first + 1, (cap - 1).max(1));
                assert!(s.last + 1 < d.len());
            }
        }
    }

    #[test]
    fn short_plans_stream_and_many_short_segments_do_not() {
        let r = rule(8);
        // 15 segments of 60 ms: 7 of them hold 420 ms, not 810 ms.
        let fifteen = [60_000u32; 15];
        let e = r.check(&fifteen).unwrap_err();
        assert_eq!((e.first, e.last, e.run_us), (0, 6, 420_000));
        // The same plan fits a queue of 16 whole.
        assert_eq!(rule(16).check(&fifteen), Ok(()));
        // 200 ms segments stream: 7 × 200 ms = 1.4 s.
        assert_eq!(r.check(&[200_000; 100]), Ok(()));
        // A 2 ms segment every tenth among 200 ms ones still does.
        let mixed: Vec<u32> = (0..100)
            .map(|i| if i % 10 == 9 { 2_000 } else { 200_000 })
            .collect();
        assert_eq!(r.check(&mixed), Ok(()));
        // Queue of one: nothing streams beyond a single segment.
        assert!(rule(1).check(&[1_000_000; 2]).is_err());
        assert_eq!(rule(1).check(&[1_000_000; 1]), Ok(()));
    }

    #[test]
    fn configuration_gives_lookahead_and_refill() {
        let r = StreamRule::new(8, 1.434, 0.05, 0.1);
        assert_eq!(r.lookahead_us, 717_000 + 50_000);
        assert_eq!(r.refill_us, 100_000 + SEGMENT_TRANSFER_US);
        let bad = StreamRule::new(8, f64::NAN, -1.0, f64::INFINITY);
        assert_eq!((bad.lookahead_us, bad.refill_us), (0, SEGMENT_TRANSFER_US));
    }
}
