//! Seeded, reproducible fault injection between the in-process [`Bus`] and
//! its stations: every frame the bus completes passes through a
//! [`FaultInjector`] on its way to each receiver, which may lose it, flip a
//! bit of it, deliver it twice, swap it with the next one, or hold it back;
//! a station can go bus-off (neither sends nor receives) and a babbling
//! station can flood the bus with a high-priority identifier. Faults are
//! active in time windows and may be limited to an identifier range, so one
//! schedule describes e.g. "lose every TimeSync from 1.2 s on".
//!
//! Bit corruption is applied to segment parts only: every other message is
//! a single frame guarded by CAN's own CRC-15, whereas a segment is
//! reassembled from parts and guarded by the protocol's CRC-32, which is
//! what this fault exercises (a flip the CAN CRC missed, or one made in a
//! controller's buffer).

use std::collections::VecDeque;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_shared::protocol::Frame;
use triquint_shared::protocol::segment::{SEGMENT_PART, SEGMENT_PART_FD};

use crate::bus::{Bus, Delivery};

/// Station number of the babbling node on a bus with faults (host 0, nodes 1–3).
pub const BABBLER: usize = 4;

/// One kind of fault.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Fault {
    /// Each receiver misses each frame with probability `rate`.
    Loss { rate: f64 },
    /// A segment part reaches a receiver with one random payload bit flipped.
    Corrupt { rate: f64 },
    /// A frame reaches a receiver twice.
    Duplicate { rate: f64 },
    /// A frame reaches a receiver after the next frame to that receiver.
    Reorder { rate: f64 },
    /// Each frame is handed to each receiver's software late by a uniform
    /// 0..=`max_ns` (a slow service loop); the hardware receive timestamp is
    /// unchanged and order per receiver is kept.
    Delay { max_ns: u64 },
    /// Each frame's receive timestamp (and delivery) is late by a uniform
    /// 0..=`max_ns`: timestamping jitter.
    Jitter { max_ns: u64 },
    /// Each frame's receive timestamp (and delivery) is exactly `ns` late.
    Late { ns: u64 },
    /// The station's controller is bus-off: it neither receives nor
    /// transmits (a node keeps its frames queued; the host's are lost).
    BusOff { station: usize },
    /// A babbling station floods the bus with identifier `id` (8-byte frames).
    Babble { id: u16 },
}

impl Fault {
    /// Short name for tables.
    pub fn name(&self) -> &'static str {
        match self {
            Fault::Loss { .. } => "loss",
            Fault::Corrupt { .. } => "corrupt",
            Fault::Duplicate { .. } => "duplicate",
            Fault::Reorder { .. } => "reorder",
            Fault::Delay { .. } => "delay",
            Fault::Jitter { .. } => "jitter",
            Fault::Late { .. } => "late",
            Fault::BusOff { .. } => "bus-off",
            Fault::Babble { .. } => "babble",
        }
    }
}

/// A fault active from `from_ns` to `until_ns` (true time), on frames with
/// identifiers in `ids`.
#[derive(Clone, Debug, PartialEq)]
pub struct FaultWindow {
    pub fault: Fault,
    pub from_ns: u64,
    pub until_ns: u64,
    pub ids: core::ops::RangeInclusive<u16>,
}

impl FaultWindow {
    /// `fault` on every identifier between the two times.
    pub fn new(fault: Fault, from_ns: u64, until_ns: u64) -> Self {
        Self {
            fault,
            from_ns,
            until_ns,
            ids: 0..=0x7FF,
        }
    }
    /// Limits the window to identifiers `ids`.
    pub fn on_ids(mut self, ids: core::ops::RangeInclusive<u16>) -> Self {
        self.ids = ids;
        self
    }
    fn active(&self, t_ns: u64) -> bool {
        (self.from_ns..self.until_ns).contains(&t_ns)
    }
    fn applies(&self, t_ns: u64, id: u16) -> bool {
        self.active(t_ns) && self.ids.contains(&id)
    }
}

/// What the injector did (per fault kind, summed over receivers).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize)]
pub struct FaultStats {
    pub lost: u64,
    pub corrupted: u64,
    pub duplicated: u64,
    pub reordered: u64,
    pub delayed: u64,
    pub bus_off_dropped: u64,
    pub babbled: u64,
}

/// The fault layer of one bus.
pub struct FaultInjector {
    pub windows: Vec<FaultWindow>,
    rng: ChaCha8Rng,
    /// Per receiving station: deliveries waiting for their (delayed) time.
    held: Vec<VecDeque<(u64, Delivery)>>,
    /// Per receiving station: a frame held back to be swapped with the next.
    swapped: Vec<Option<Delivery>>,
    pub stats: FaultStats,
}

fn is_segment_part(id: u16) -> bool {
    id == SEGMENT_PART.addr.id(0) || id == SEGMENT_PART_FD.addr.id(0)
}

impl FaultInjector {
    /// An injector for `stations` receivers with the given schedule and seed.
    pub fn new(windows: Vec<FaultWindow>, seed: u64, stations: usize) -> Self {
        Self {
            windows,
            rng: ChaCha8Rng::seed_from_u64(seed),
            held: vec![VecDeque::new(); stations],
            swapped: vec![None; stations],
            stats: FaultStats::default(),
        }
    }

    /// Is `station` bus-off at `t_ns`?
    pub fn bus_off(&self, station: usize, t_ns: u64) -> bool {
        self.windows
            .iter()
            .any(|w| w.active(t_ns) && w.fault == Fault::BusOff { station })
    }

    fn chance(&mut self, rate: f64) -> bool {
        rate > 0.0 && self.rng.random::<f64>() < rate
    }

    /// Takes one delivery the bus made to `station` at true time `now_ns`.
    pub fn deliver(&mut self, station: usize, mut d: Delivery, now_ns: u64) {
        let t = d.t_ns;
        if self.bus_off(station, t) || self.bus_off(d.from, t) {
            self.stats.bus_off_dropped += 1;
            return;
        }
        if d.own {
            // The controller's own transmit confirmation never crosses the wire.
            self.push(station, now_ns.max(t), d);
            return;
        }
        let mut copies = 1;
        let mut due = t;
        let mut stamp = t;
        let mut swap = false;
        for k in 0..self.windows.len() {
            let w = &self.windows[k];
            if !w.applies(t, d.frame.id) {
                continue;
            }
            match w.fault {
                Fault::Loss { rate } => {
                    if self.chance(rate) {
                        self.stats.lost += 1;
                        return;
                    }
                }
                Fault::Corrupt { rate } => {
                    if is_segment_part(d.frame.id) && d.frame.len > 0 && self.chance(rate) {
                        let bits = d.frame.len as usize * 8;
                        let b = self.rng.random_range(0..bits);
                        d.frame.data[b / 8] ^= 1 << (b % 8);
                        self.stats.corrupted += 1;
                    }
                }
                Fault::Duplicate { rate } => {
                    if self.chance(rate) {
                        copies = 2;
                        self.stats.duplicated += 1;
                    }
                }
                Fault::Reorder { rate } => {
                    if self.chance(rate) {
                        swap = true;
                    }
                }
                Fault::Delay { max_ns } => {
                    let extra = self.rng.random_range(0..=max_ns);
                    if extra > 0 {
                        self.stats.delayed += 1;
                    }
                    due = due.max(t + extra);
                }
                Fault::Jitter { max_ns } => {
                    let extra = self.rng.random_range(0..=max_ns);
                    if extra > 0 {
                        self.stats.delayed += 1;
                    }
                    stamp = stamp.max(t + extra);
                }
                Fault::Late { ns } => {
                    self.stats.delayed += 1;
                    stamp = stamp.max(t + ns);
                }
                Fault::BusOff { .. } | Fault::Babble { .. } => {}
            }
        }
        d.t_ns = stamp;
        let due = due.max(stamp);
        if swap && self.swapped[station].is_none() {
            self.swapped[station] = Some(d);
            self.stats.reordered += 1;
            return;
        }
        for _ in 0..copies {
            self.push(station, due, d);
        }
        if let Some(held) = self.swapped[station].take() {
            self.push(station, due, held);
        }
    }

    fn push(&mut self, station: usize, due: u64, d: Delivery) {
        let q = &mut self.held[station];
        // Keep per-receiver order: a later frame is never due before an earlier one.
        let due = q.back().map_or(due, |b| due.max(b.0));
        q.push_back((due, d));
    }

    /// The next delivery to `station` that is due at `now_ns`.
    pub fn ready(&mut self, station: usize, now_ns: u64) -> Option<Delivery> {
        let q = self.held.get_mut(station)?;
        match q.front() {
            Some((due, _)) if *due <= now_ns => q.pop_front().map(|x| x.1),
            _ => None,
        }
    }

    /// When the next delivery to `station` is due (`None`: nothing held).
    pub fn next_due(&self, station: usize) -> Option<u64> {
        self.held.get(station)?.front().map(|x| x.0)
    }

    /// Keeps the babbler's transmit queue full while a Babble window is active
    /// (and drains what the bus delivered to it).
    pub fn feed_babbler(&mut self, bus: &mut Bus, now_ns: u64) {
        while bus.receive(BABBLER).is_some() {}
        let Some(id) = self.windows.iter().find_map(|w| match w.fault {
            Fault::Babble { id } if w.active(now_ns) => Some(id),
            _ => None,
        }) else {
            return;
        };
        while bus.pending(BABBLER) < 2 {
            let mut f = Frame::new(id, 8, false);
            f.data[..8].copy_from_slice(&self.rng.random::<u64>().to_le_bytes());
            bus.send(BABBLER, f, now_ns);
            self.stats.babbled += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bus::BusConfig;

    fn run(windows: Vec<FaultWindow>, seed: u64) -> (Vec<Delivery>, FaultStats) {
        let mut bus = Bus::new(BusConfig::default(), 5);
        let mut inj = FaultInjector::new(windows, seed, 5);
        for k in 0..200u16 {
            let mut f = Frame::new(0x100, 8, false);
            f.data[0] = k as u8;
            bus.send(0, f, k as u64 * 200_000);
        }
        let mut out = Vec::new();
        let mut t = 0;
        while t < 60_000_000 {
            t += 50_000;
            inj.feed_babbler(&mut bus, t);
            bus.advance(t);
            while let Some(d) = bus.receive(1) {
                inj.deliver(1, d, t);
            }
            while let Some(d) = inj.ready(1, t) {
                out.push(d);
            }
        }
        (out, inj.stats)
    }

    #[test]
    fn same_seed_same_faults_and_each_fault_does_what_it_says() {
        let all = |f| vec![FaultWindow::new(f, 0, u64::MAX)];
        let (clean, _) = run(vec![], 1);
        assert_eq!(clean.len(), 200);
        let (a, sa) = run(all(Fault::Loss { rate: 0.2 }), 5);
        let (b, sb) = run(all(Fault::Loss { rate: 0.2 }), 5);
        assert_eq!(a, b);
        assert_eq!(sa, sb);
        assert_eq!(a.len() as u64 + sa.lost, 200);
        assert!((20..=60).contains(&sa.lost), "{sa:?}");
        let (c, sc) = run(all(Fault::Corrupt { rate: 0.5 }), 2);
        let changed = c
            .iter()
            .zip(&clean)
            .filter(|(x, y)| x.frame != y.frame)
            .count();
        assert_eq!(changed as u64, sc.corrupted);
        assert!(changed > 50);
        let (d, sd) = run(all(Fault::Duplicate { rate: 0.3 }), 3);
        assert_eq!(d.len() as u64, 200 + sd.duplicated);
        let (r, sr) = run(all(Fault::Reorder { rate: 0.3 }), 4);
        assert_eq!(r.len(), 200);
        let swaps = r
            .windows(2)
            .filter(|w| w[0].frame.data[0] > w[1].frame.data[0])
            .count();
        assert_eq!(swaps as u64, sr.reordered);
        // Delay: late delivery, same timestamps, same order.
        let (l, sl) = run(all(Fault::Delay { max_ns: 3_000_000 }), 6);
        assert_eq!(l, clean);
        assert!(sl.delayed > 150);
        // Jitter: timestamps late by at most the bound.
        let (j, _) = run(all(Fault::Jitter { max_ns: 30_000 }), 6);
        assert!(
            j.iter()
                .zip(&clean)
                .all(|(x, y)| x.t_ns >= y.t_ns && x.t_ns <= y.t_ns + 30_000)
        );
        assert!(j.iter().zip(&clean).any(|(x, y)| x.t_ns > y.t_ns + 10_000));
        // Bus-off of the receiver from 10 s to 20 s: the 50 frames sent then are lost.
        let (o, so) = run(
            vec![FaultWindow::new(
                Fault::BusOff { station: 1 },
                10_000_000,
                20_000_000,
            )],
            1,
        );
        assert_eq!(so.bus_off_dropped, 50);
        assert_eq!(o.len(), 150);
        // A babbler on 0x001 from 0 to 30 ms wins every arbitration: nothing
        // of the host's gets through until it stops.
        let (g, sg) = run(
            vec![FaultWindow::new(Fault::Babble { id: 0x001 }, 0, 30_000_000)],
            1,
        );
        assert!(sg.babbled > 200);
        let firsts: Vec<&Delivery> = g.iter().filter(|d| d.frame.id == 0x100).collect();
        assert_eq!(firsts.len(), 200);
        // (the first frame was on the bus before the babbler started)
        assert!(firsts[1].t_ns >= 30_000_000);
    }
}
