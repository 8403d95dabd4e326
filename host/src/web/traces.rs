//! The traces the page plots: per axis, joint position (Telemetry),
//! following error and torque command (TelemetryExt), each sample with its
//! bus time, kept for [`KEEP_US`] in a ring buffer.

use std::collections::VecDeque;

use serde::Serialize;

/// How much history is kept (the page shows 10 s by default, up to this).
pub const KEEP_US: u64 = 60_000_000;
/// At most this many samples per series (telemetry at 1 kHz for 60 s).
pub const MAX_SAMPLES: usize = 60_000;

/// The plotted quantities, in the order of [`Traces::series`].
pub const QUANTITIES: [(&str, &str); 3] = [
    ("position", "mm"),
    ("following_error", "µm"),
    ("torque", "N·m"),
];

/// One series: (time µs, value) pairs, oldest first.
#[derive(Clone, Debug, Default)]
pub struct Series {
    pub samples: VecDeque<(u64, f64)>,
}

impl Series {
    fn push(&mut self, t_us: u64, v: f64) {
        self.samples.push_back((t_us, v));
        while self.samples.len() > MAX_SAMPLES
            || self
                .samples
                .front()
                .is_some_and(|&(t, _)| t + KEEP_US < t_us)
        {
            self.samples.pop_front();
        }
    }

    /// The samples after `t_us` (exclusive).
    pub fn since(&self, t_us: Option<u64>) -> impl Iterator<Item = &(u64, f64)> {
        let start = match t_us {
            None => 0,
            Some(t) => self.samples.partition_point(|&(s, _)| s <= t),
        };
        self.samples.range(start..)
    }
}

/// Samples of every series newer than a cursor, for the stream and the API.
#[derive(Clone, Debug, Default, Serialize)]
pub struct Delta {
    /// `[quantity][axis]` → `[[t_s, value], …]`.
    pub series: Vec<Vec<Vec<[f64; 2]>>>,
}

/// Every series: `series[quantity][axis]`.
#[derive(Clone, Debug, Default)]
pub struct Traces {
    pub series: [[Series; 3]; 3],
    /// Bus time of the newest sample.
    pub newest_us: Option<u64>,
}

impl Traces {
    /// Joint position `q` (m) of `axis` at `t_us`.
    pub fn position(&mut self, axis: usize, t_us: u64, q: f32) {
        self.push(0, axis, t_us, f64::from(q) * 1e3);
    }

    /// Following error (m) and torque command (N·m) of `axis` at `t_us`.
    pub fn ext(&mut self, axis: usize, t_us: u64, following_error: f32, torque: f32) {
        self.push(1, axis, t_us, f64::from(following_error) * 1e6);
        self.push(2, axis, t_us, f64::from(torque));
    }

    fn push(&mut self, quantity: usize, axis: usize, t_us: u64, v: f64) {
        if !v.is_finite() {
            return;
        }
        self.series[quantity][axis].push(t_us, v);
        self.newest_us = Some(self.newest_us.map_or(t_us, |n| n.max(t_us)));
    }

    /// The samples newer than `t_us` (all with `None`), at most `max` per
    /// series (the newest ones).
    pub fn delta(&self, t_us: Option<u64>, max: usize) -> Delta {
        Delta {
            series: self
                .series
                .iter()
                .map(|axes| {
                    axes.iter()
                        .map(|s| {
                            let v: Vec<[f64; 2]> =
                                s.since(t_us).map(|&(t, v)| [t as f64 * 1e-6, v]).collect();
                            let skip = v.len().saturating_sub(max);
                            v[skip..].to_vec()
                        })
                        .collect()
                })
                .collect(),
        }
    }

    /// The latest sample of each series: `[quantity][axis]` → value.
    pub fn latest(&self) -> [[Option<f64>; 3]; 3] {
        self.series
            .each_ref()
            .map(|axes| axes.each_ref().map(|s| s.samples.back().map(|&(_, v)| v)))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn old_samples_leave_and_deltas_start_after_the_cursor() {
        let mut t = Traces::default();
        for i in 0..100u64 {
            t.position(0, i * 1_000_000, i as f32 * 1e-3);
        }
        let s = &t.series[0][0].samples;
        assert_eq!(s.front().unwrap().0, 39_000_000);
        assert_eq!(s.len(), 61);
        let d = t.delta(Some(97_000_000), 100);
        let got: Vec<(f64, f64)> = d.series[0][0].iter().map(|p| (p[0], p[1])).collect();
        assert_eq!(got.len(), 2);
        assert_eq!((got[0].0, got[1].0), (98.0, 99.0));
        assert!((got[1].1 - 99.0).abs() < 1e-4);
        assert_eq!(t.delta(None, 5).series[0][0].len(), 5);
        assert!((t.latest()[0][0].unwrap() - 99.0).abs() < 1e-4);
        assert_eq!(t.latest()[1][0], None);
    }
}
