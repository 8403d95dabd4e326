//! The stop ramp a Stop, QuickStop or FeedHold carries for the path ahead
//! of its instant (docs/protocol.md, "A ramp for the path ahead"): the
//! largest of the drives' own ramps (the same f32 rule on the same wire
//! segments, `wire_ramps`) over the segments a stop from there can pass
//! through. The drives run it only if it covers the ramps of the segments
//! they hold in that window, so a wrong estimate of where the plan is
//! costs the shorter stop, never a harder one.

use triquint_shared::protocol::segment_maxima::wire_ramps;
use triquint_shared::protocol::{DriveConfig, WireSegment};

/// Room on each side of the host's estimate of the plan time (µs): its
/// error at σ = 1 with nothing held or overridden is the clocks' sync
/// error, well under this.
const ESTIMATE_MARGIN_US: f64 = 20_000.0;

/// The unit of the command's ramp field (µs).
const UNIT_US: u64 = 100;

#[derive(Clone, Debug)]
pub(crate) struct PathRamps {
    /// Each segment's plan-time span (µs) and its own controlled and quick
    /// ramps (µs).
    segments: Vec<(f64, f64, [f64; 2])>,
    /// The ramps every transition runs with (µs): the configured ones.
    full_us: [f64; 2],
    /// The override cap σ the stop distance is sized for.
    cap: f64,
}

impl PathRamps {
    pub fn new(segments: &[WireSegment], c: &DriveConfig) -> Self {
        let mut start = 0.0;
        let mut full_us = [c.stop_time as f64 * 1e6, c.quick_stop_time as f64 * 1e6];
        let rows = segments
            .iter()
            .map(|w| {
                let ramps = wire_ramps(w, c.max_jerk, c.ceiling_jerk, c.override_cap)
                    .map_or([f64::INFINITY; 2], |(s, q)| {
                        [s as f64 * 1e6, q as f64 * 1e6]
                    });
                let end = start + w.duration_us as f64;
                let row = (start, end, ramps);
                start = end;
                full_us = [full_us[0].max(ramps[0]), full_us[1].max(ramps[1])];
                row
            })
            .collect();
        Self {
            segments: rows,
            full_us,
            cap: (c.override_cap as f64).max(1.0),
        }
    }

    /// The command's ramp field (100 µs units, rounded up) for a stop
    /// (`quick`: the quick stop's) at estimated plan time `plan_us`: the
    /// largest own ramp over the segments a stop from within
    /// [`ESTIMATE_MARGIN_US`] of it can pass through at σ up to the cap;
    /// 0 (the drives' full ramp) when that is not shorter.
    pub fn dated(&self, plan_us: f64, quick: bool) -> u16 {
        let k = usize::from(quick);
        let full = self.full_us[k];
        let lo = plan_us - ESTIMATE_MARGIN_US;
        let hi = plan_us + ESTIMATE_MARGIN_US + 0.5 * full * self.cap * self.cap;
        let ahead = self
            .segments
            .iter()
            .filter(|&&(a, b, _)| b > lo && a < hi)
            .map(|s| s.2[k])
            .fold(0.0, f64::max);
        // 1 µs over: the drives round their own ramp from f32.
        let units = ((ahead + 1.0) / UNIT_US as f64).ceil();
        if ahead > 0.0 && units * (UNIT_US as f64) < full && units <= u16::MAX as f64 {
            units as u16
        } else {
            0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::configs::{DriveConfigs, committed_plan};
    use triquint_shared::protocol::DriveSettings;

    #[test]
    fn never_longer_than_the_full_ramp_and_never_below_the_segment_it_is_in() {
        let p = committed_plan("case2-spline");
        let configs = DriveConfigs::for_plan(&p, &DriveSettings::default()).unwrap();
        let w = p.wire_segments().unwrap();
        let r = PathRamps::new(&w, &configs.nodes[0]);
        let total = r.segments.last().unwrap().1;
        let mut shorter = 0;
        for i in 0..=100 {
            let t = total * i as f64 / 100.0;
            for quick in [false, true] {
                let d = r.dated(t, quick) as f64 * UNIT_US as f64;
                let k = usize::from(quick);
                if d == 0.0 {
                    continue;
                }
                shorter += 1;
                assert!(d < r.full_us[k], "{t}: {d}");
                for &(a, b, ramps) in &r.segments {
                    if b > t - ESTIMATE_MARGIN_US && a < t + ESTIMATE_MARGIN_US + 0.5 * d {
                        assert!(ramps[k] <= d, "{t}: segment's {} > {d}", ramps[k]);
                    }
                }
            }
        }
        assert!(shorter > 0);
    }
}
