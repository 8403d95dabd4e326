//! In-process CAN bus: stations queue frames, the bus arbitrates by
//! identifier when idle (lowest wins, as on a real bus), each frame occupies
//! the bus for its bit time (with a stuffing estimate), and is delivered to
//! every other station (and echoed to its sender with the transmit time).

use std::collections::VecDeque;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_shared::protocol::{Frame, MsgKind, frame_time_ns};

/// The identifiers of segment frames, full and compact (broadcast: node 0).
const SEGMENT_IDS: [u16; 4] = [
    MsgKind::SegmentPart.def().addr.id(0),
    MsgKind::SegmentCompact.def().addr.id(0),
    MsgKind::SegmentPartFd.def().addr.id(0),
    MsgKind::SegmentCompactFd.def().addr.id(0),
];

/// Bus timing and fault injection.
#[derive(Clone, Debug, PartialEq)]
pub struct BusConfig {
    pub nominal_bps: u64,
    pub data_bps: u64,
    /// Probability that one receiver misses a frame (receive overrun), to
    /// exercise the protocol's acknowledgements and retransmission.
    pub rx_drop: f64,
    pub seed: u64,
    /// Keep every frame with its time (for captures and tests).
    pub capture: bool,
}

impl Default for BusConfig {
    fn default() -> Self {
        Self {
            nominal_bps: 1_000_000,
            data_bps: 5_000_000,
            rx_drop: 0.0,
            seed: 1,
            capture: false,
        }
    }
}

/// A frame delivered to a station.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Delivery {
    pub frame: Frame,
    /// True time (ns) when the frame completed on the bus.
    pub t_ns: u64,
    /// The station's own frame (transmit confirmation).
    pub own: bool,
    /// The station that sent it.
    pub from: usize,
}

/// The bus. Station 0 is the host, 1–3 the nodes.
#[derive(Clone)]
pub struct Bus {
    cfg: BusConfig,
    pending: Vec<VecDeque<(Frame, u64)>>,
    rx: Vec<VecDeque<Delivery>>,
    in_flight: Option<(usize, Frame, u64)>,
    idle_from: u64,
    busy_ns: u64,
    segment_busy_ns: u64,
    frames: u64,
    dropped: u64,
    rng: ChaCha8Rng,
    pub capture: Vec<(u64, usize, Frame)>,
}

impl Bus {
    pub fn new(cfg: BusConfig, stations: usize) -> Self {
        let rng = ChaCha8Rng::seed_from_u64(cfg.seed);
        Self {
            cfg,
            pending: vec![VecDeque::new(); stations],
            rx: vec![VecDeque::new(); stations],
            in_flight: None,
            idle_from: 0,
            busy_ns: 0,
            segment_busy_ns: 0,
            frames: 0,
            dropped: 0,
            rng,
            capture: Vec::new(),
        }
    }

    /// Queues a frame from `station` at true time `t_ns` (call `advance(t_ns)` first).
    pub fn send(&mut self, station: usize, frame: Frame, t_ns: u64) {
        if let Some(q) = self.pending.get_mut(station) {
            q.push_back((frame, t_ns));
        }
    }

    /// Frames a station has queued and not yet transmitted.
    pub fn pending(&self, station: usize) -> usize {
        self.pending.get(station).map_or(0, VecDeque::len)
    }

    /// Next delivery for `station`.
    pub fn receive(&mut self, station: usize) -> Option<Delivery> {
        self.rx.get_mut(station)?.pop_front()
    }

    fn duration(&self, f: &Frame) -> u64 {
        frame_time_ns(f, self.cfg.nominal_bps, self.cfg.data_bps)
    }

    /// Runs the bus up to true time `until_ns`.
    pub fn advance(&mut self, until_ns: u64) {
        loop {
            if let Some((station, frame, done)) = self.in_flight {
                if done > until_ns {
                    return;
                }
                self.in_flight = None;
                self.idle_from = done;
                self.frames += 1;
                if self.cfg.capture {
                    self.capture.push((done, station, frame));
                }
                let n = self.rx.len();
                let victim =
                    if self.cfg.rx_drop > 0.0 && self.rng.random::<f64>() < self.cfg.rx_drop {
                        let v = self.rng.random_range(0..n);
                        (v != station).then_some(v)
                    } else {
                        None
                    };
                for s in 0..n {
                    if Some(s) == victim {
                        self.dropped += 1;
                        continue;
                    }
                    if s != station || s == 0 {
                        self.rx[s].push_back(Delivery {
                            frame,
                            t_ns: done,
                            own: s == station,
                            from: station,
                        });
                    }
                }
            }
            // Arbitration when idle: among frames queued by the time the bus is free.
            // Each station's controller offers the frame at the head of its
            // FIFO (as SocketCAN and FIFO-mode controllers do).
            let earliest = self
                .pending
                .iter()
                .filter_map(|q| q.front().map(|x| x.1))
                .min();
            let Some(earliest) = earliest else {
                return;
            };
            let start = self.idle_from.max(earliest);
            if start > until_ns {
                return;
            }
            let mut best: Option<(u16, usize, usize)> = None;
            for (s, q) in self.pending.iter().enumerate() {
                if let Some((f, t)) = q.front()
                    && *t <= start
                    && best.is_none_or(|b| f.id < b.0)
                {
                    best = Some((f.id, s, 0));
                }
            }
            let Some((_, s, i)) = best else {
                return;
            };
            let Some((frame, _)) = self.pending[s].remove(i) else {
                return;
            };
            let d = self.duration(&frame);
            self.busy_ns += d;
            if SEGMENT_IDS.contains(&frame.id) {
                self.segment_busy_ns += d;
            }
            self.in_flight = Some((s, frame, start + d));
        }
    }

    /// Busy time so far (ns).
    pub fn busy_ns(&self) -> u64 {
        self.busy_ns
    }
    /// Busy time spent on segment parts (ns).
    pub fn segment_busy_ns(&self) -> u64 {
        self.segment_busy_ns
    }
    pub fn frames(&self) -> u64 {
        self.frames
    }
    pub fn dropped(&self) -> u64 {
        self.dropped
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn arbitration_by_identifier_and_bit_time() {
        let mut bus = Bus::new(BusConfig::default(), 4);
        // Three stations queue at the same instant: lowest id first.
        bus.send(3, Frame::new(0x703, 8, false), 0);
        bus.send(1, Frame::new(0x101, 8, false), 0);
        bus.send(0, Frame::new(0x020, 5, false), 0);
        bus.advance(1_000_000);
        let got: Vec<u16> = std::iter::from_fn(|| bus.receive(2))
            .map(|d| d.frame.id)
            .collect();
        assert_eq!(got, vec![0x020, 0x101, 0x703]);
        // The host sees its own frame as a transmit confirmation.
        let own = bus.receive(0).unwrap();
        assert!(own.own && own.frame.id == 0x020);
        // Frames are back to back: total busy time is the sum of bit times.
        let d = |n: usize| frame_time_ns(&Frame::new(0x100, n, false), 1_000_000, 5_000_000);
        assert_eq!(bus.busy_ns(), d(8) * 2 + d(5));
        assert_eq!(bus.frames(), 3);
    }

    #[test]
    fn later_frame_waits_for_the_bus() {
        let mut bus = Bus::new(BusConfig::default(), 2);
        bus.send(1, Frame::new(0x700, 8, false), 0);
        bus.advance(10_000);
        // A higher-priority frame arriving mid-transmission cannot preempt.
        bus.send(0, Frame::new(0x010, 8, false), 10_000);
        bus.advance(1_000_000);
        let first = bus.receive(0).unwrap();
        assert_eq!(first.frame.id, 0x700);
        let second = bus.receive(1).unwrap();
        assert_eq!(second.frame.id, 0x010);
        assert!(second.t_ns > first.t_ns);
    }
}
