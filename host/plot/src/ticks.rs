//! Round-number axis ticks and their labels.

use std::ops::Range;

use plotters::coord::ranged1d::{KeyPointHint, NoDefaultFormatting, Ranged, ValueFormatter};

/// A step of 1, 2, 2.5 or 5 × 10^k giving about `target` intervals over `span`.
pub fn nice_step(span: f64, target: usize) -> f64 {
    let span = if span.is_finite() && span > 0.0 {
        span
    } else {
        1.0
    };
    let raw = span / target.max(1) as f64;
    let mag = 10f64.powf(raw.log10().floor());
    let m = raw / mag;
    let f = if m <= 1.0 {
        1.0
    } else if m <= 2.0 {
        2.0
    } else if m <= 2.5 {
        2.5
    } else if m <= 5.0 {
        5.0
    } else {
        10.0
    };
    f * mag
}

/// Decimals that print every multiple of `step` exactly (0.25 → 2, 5 → 0).
pub fn decimals(step: f64) -> usize {
    if !(step.is_finite() && step > 0.0) {
        return 0;
    }
    let mut d = 0usize;
    // The smallest d at which the step is a whole number of 10^-d (to rounding).
    while d < 12 {
        let s = step * 10f64.powi(d as i32);
        if (s - s.round()).abs() < 1e-6 * s.max(1.0) {
            break;
        }
        d += 1;
    }
    d
}

/// `value` with `decimals` decimals, a real minus sign, and no "−0".
pub fn format(value: f64, decimals: usize) -> String {
    let s = format!("{value:.decimals$}");
    let zero = s
        .trim_start_matches('-')
        .chars()
        .all(|c| c == '0' || c == '.');
    if zero {
        s.trim_start_matches('-').to_string()
    } else if let Some(rest) = s.strip_prefix('-') {
        format!("−{rest}")
    } else {
        s
    }
}

/// One axis: its drawn range, its tick values and the decimals of their labels.
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    pub lo: f64,
    pub hi: f64,
    pub ticks: Vec<f64>,
    pub decimals: usize,
}

impl Axis {
    /// An axis over the data range [lo, hi]: `snap` widens the range to whole
    /// steps (value axes); without it the range is kept (time axes).
    /// Non-finite or empty ranges become a unit range, so no input fails.
    pub fn new(lo: f64, hi: f64, target: usize, snap: bool) -> Self {
        let (mut lo, mut hi) = if lo.is_finite() && hi.is_finite() && lo <= hi {
            (lo, hi)
        } else {
            (0.0, 1.0)
        };
        // A flat series still gets an axis around its value.
        let scale = lo.abs().max(hi.abs());
        if hi - lo <= 1e-9 * scale.max(1e-300) || hi - lo < 1e-300 {
            let half = if scale > 0.0 { 0.05 * scale } else { 1.0 };
            lo -= half;
            hi += half;
        }
        let step = nice_step(hi - lo, target);
        let d = decimals(step);
        // k × step, rounded to the label's decimals (0.6, not 0.6000000000000001).
        let at = |k: f64| {
            let p = 10f64.powi(d as i32);
            (k * step * p).round() / p
        };
        if snap {
            lo = at((lo / step - 1e-9).floor());
            hi = at((hi / step + 1e-9).ceil());
        }
        let first = (lo / step - 1e-9).ceil() as i64;
        let last = (hi / step + 1e-9).floor() as i64;
        // Bounded: at most a hundred ticks whatever the input.
        let ticks = (first..=last.min(first + 100))
            .map(|k| at(k as f64))
            .collect();
        Self {
            lo,
            hi,
            ticks,
            decimals: d,
        }
    }

    /// The label of tick value `v`.
    pub fn label(&self, v: f64) -> String {
        format(v, self.decimals)
    }
}

/// The axis as a plotters coordinate: exactly our ticks, labelled by us.
impl Ranged for Axis {
    type FormatOption = NoDefaultFormatting;
    type ValueType = f64;

    fn map(&self, v: &f64, limit: (i32, i32)) -> i32 {
        let t = (v - self.lo) / (self.hi - self.lo);
        let px = limit.0 as f64 + t * (limit.1 - limit.0) as f64;
        // Far-off values (clipped anyway) must not overflow the pixel type.
        px.clamp(-1e6, 1e6).round() as i32
    }

    fn key_points<H: KeyPointHint>(&self, _hint: H) -> Vec<f64> {
        self.ticks.clone()
    }

    fn range(&self) -> Range<f64> {
        self.lo..self.hi
    }
}

impl ValueFormatter<f64> for Axis {
    fn format(value: &f64) -> String {
        format!("{value}")
    }
    fn format_ext(&self, value: &f64) -> String {
        self.label(*value)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn steps_are_round() {
        assert_eq!(nice_step(10.0, 5), 2.0);
        assert_eq!(nice_step(1.0, 4), 0.25);
        assert_eq!(nice_step(7.58e-5, 5), 2e-5);
        assert_eq!(decimals(0.25), 2);
        assert_eq!(decimals(5.0), 0);
        assert_eq!(decimals(2e-5), 5);
    }

    #[test]
    fn labels_have_as_many_decimals_as_the_step() {
        let a = Axis::new(-0.37, 0.52, 5, true);
        assert_eq!((a.lo, a.hi), (-0.4, 0.6));
        let labels: Vec<String> = a.ticks.iter().map(|&v| a.label(v)).collect();
        assert_eq!(labels, ["−0.4", "−0.2", "0.0", "0.2", "0.4", "0.6"]);
    }

    #[test]
    fn time_axis_keeps_its_range() {
        let a = Axis::new(0.0, 3.37, 6, false);
        assert_eq!((a.lo, a.hi), (0.0, 3.37));
        assert_eq!(a.ticks.last(), Some(&3.0));
    }

    #[test]
    fn degenerate_input_gives_an_axis() {
        for (lo, hi) in [(f64::NAN, 1.0), (2.0, 2.0), (0.0, 0.0), (5.0, -5.0)] {
            let a = Axis::new(lo, hi, 5, true);
            assert!(a.lo < a.hi && !a.ticks.is_empty(), "{lo} {hi}: {a:?}");
        }
    }
}
