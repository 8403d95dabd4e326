//! Bus statistics: frame rates per message and an estimate of the bus load
//! over the last second of bus time.

use std::collections::{BTreeMap, VecDeque};

use serde::Serialize;
use triquint_shared::protocol::Frame;

/// Nominal bit rate of the load estimate (classic CAN, and the arbitration
/// phase of CAN-FD).
pub const NOMINAL_BPS: f64 = 1_000_000.0;
/// CAN-FD data-phase bit rate of the estimate.
pub const DATA_BPS: f64 = 5_000_000.0;
const WINDOW_US: u64 = 1_000_000;

/// Bits a frame takes on the bus (with worst-case stuffing), as time at
/// the nominal rate.
pub fn frame_bit_time_s(f: &Frame) -> f64 {
    let n = f.payload().len() as f64;
    if f.fd {
        // Arbitration ~30 bits at the nominal rate; control, data and CRC
        // (21-bit CRC beyond 16 bytes) at the data rate, ~10 % stuffing.
        let crc = if n > 16.0 { 21.0 } else { 17.0 };
        30.0 / NOMINAL_BPS + (n * 8.0 + crc + 30.0) * 1.1 / DATA_BPS
    } else {
        // 47 bits of overhead, 8 per byte, worst-case stuffing of 34 + 8n.
        (47.0 + 8.0 * n + ((34.0 + 8.0 * n - 1.0) / 4.0).floor()) / NOMINAL_BPS
    }
}

/// Frames heard in the last second, by message name.
#[derive(Clone, Debug, Default)]
pub struct BusStats {
    window: VecDeque<(u64, &'static str, f64)>,
    /// Frames since start.
    pub total: u64,
    /// Frames that decode as no protocol message.
    pub unknown: u64,
}

/// What the page shows.
#[derive(Clone, Debug, Serialize)]
pub struct BusReport {
    pub frames_total: u64,
    pub unknown_frames: u64,
    pub frames_per_s: f64,
    /// Estimated share of bus time in use (0–1).
    pub load: f64,
    pub nominal_bps: f64,
    /// Frames per second by message name.
    pub rates: BTreeMap<&'static str, f64>,
}

impl BusStats {
    /// One frame at bus time `t_us` of message `name` (`None`: not ours).
    pub fn take(&mut self, t_us: u64, f: &Frame, name: Option<&'static str>) {
        self.total += 1;
        if name.is_none() {
            self.unknown += 1;
        }
        self.window
            .push_back((t_us, name.unwrap_or("unknown"), frame_bit_time_s(f)));
        while self
            .window
            .front()
            .is_some_and(|&(t, _, _)| t + WINDOW_US < t_us)
        {
            self.window.pop_front();
        }
    }

    /// Rates over the window ending at `now_us`.
    pub fn report(&self, now_us: u64) -> BusReport {
        let mut rates = BTreeMap::new();
        let mut busy = 0.0;
        let mut n = 0u64;
        for &(t, name, bits) in &self.window {
            if t + WINDOW_US >= now_us {
                *rates.entry(name).or_insert(0.0) += 1.0;
                busy += bits;
                n += 1;
            }
        }
        BusReport {
            frames_total: self.total,
            unknown_frames: self.unknown,
            frames_per_s: n as f64,
            load: busy.min(1.0),
            nominal_bps: NOMINAL_BPS,
            rates,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rates_over_the_last_second() {
        let mut s = BusStats::default();
        let f = Frame::with_payload(0x701, &[0; 8], false);
        for i in 0..30u64 {
            s.take(i * 100_000, &f, Some("Heartbeat"));
        }
        let r = s.report(2_900_000);
        assert_eq!(r.frames_total, 30);
        assert_eq!(r.rates["Heartbeat"], 11.0);
        // 8-byte classic frame: 135 bits worst case.
        assert!((frame_bit_time_s(&f) - 135e-6).abs() < 1e-9);
        assert!((r.load - 11.0 * 135e-6).abs() < 1e-9);
    }
}
