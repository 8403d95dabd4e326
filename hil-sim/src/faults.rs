//! Seeded, reproducible fault injection between the in-process [`Bus`] and
//! its stations: every frame the bus completes passes through a
//! [`FaultInjector`] on its way to each receiver, which may lose it, flip a
//! bit of it, deliver it twice, swap it with the next one, or hold it back;
//! a station can go bus-off (neither sends nor receives) and a babbling
//! station can flood the bus with a high-priority identifier. Faults are
//! active in time windows and may be limited to an identifier range, so one
//! schedule describes e.g. "lose every TimeSync from 1.2 s on".
//!
//! The injector also keeps every station's CAN error counters by the
//! fault-confinement rules ([`crate::confinement`], ISO 11898-1): a frame
//! lost at a receiver is an error that receiver detected (its REC + 1, the
//! sender's TEC + 8, once per frame), a duplicate is the sender's error in
//! the last bit of the frame (TEC + 8; it resends a frame the receivers
//! took), a frame received well is REC − 1 and a frame no receiver lost
//! TEC − 1. A sender whose TEC exceeds 255 is bus-off until it has seen
//! 128 × 11 recessive bits, then rejoins with both counters cleared. The
//! simulator puts the counters into the drives' HeartbeatExt. Taking a
//! bus-off station off the bus is [`FaultInjector::enforce_bus_off`]. Over vcan
//! (the proxy) the drives' counters stay zero: the kernel's vcan has no
//! error signalling, so the proxy's faults are not bus errors to them.
//!
//! Bit corruption is applied to segment parts only (full and compact): every other message is
//! a single frame guarded by CAN's own CRC-15, whereas a segment is
//! reassembled from parts and guarded by the protocol's CRC-32, which is
//! what this fault exercises (a flip the CAN CRC missed, or one made in a
//! controller's buffer).

use std::collections::VecDeque;

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_shared::protocol::Frame;
use triquint_shared::protocol::compact::{SEGMENT_COMPACT, SEGMENT_COMPACT_FD};
use triquint_shared::protocol::segment::{SEGMENT_PART, SEGMENT_PART_FD};

use crate::bus::{Bus, Delivery};
use crate::confinement::{BUS_OFF_ABOVE, ErrorCounters, RECOVERY_NS};

/// Frames per sender whose outcome (some receiver lost it or none) the
/// injector remembers: deliveries of one frame to its receivers come
/// interleaved with later frames when the stations are serviced apart.
const RECENT_FRAMES: usize = 32;

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
#[derive(Clone)]
pub struct FaultInjector {
    pub windows: Vec<FaultWindow>,
    rng: ChaCha8Rng,
    /// Per receiving station: deliveries waiting for their (delayed) time.
    held: Vec<VecDeque<(u64, Delivery)>>,
    /// Per receiving station: a frame held back to be swapped with the next.
    swapped: Vec<Option<Delivery>>,
    pub stats: FaultStats,
    /// Per station: CAN error counters.
    counters: Vec<ErrorCounters>,
    /// Per station: bus-off by its counters until this true time (ns).
    off_until: Vec<Option<u64>>,
    /// Per sender: (completion time, lost somewhere) of its recent frames.
    recent: Vec<VecDeque<(u64, bool)>>,
    /// Take a station whose TEC passed 255 off the bus (until it recovers).
    /// Off by default: the scenarios' loss and duplication rates are far
    /// beyond what a physical bus survives, and their figures are about the
    /// protocol's recovery; the counters are kept and reported either way.
    pub enforce_bus_off: bool,
}

fn is_segment_part(id: u16) -> bool {
    [
        SEGMENT_PART,
        SEGMENT_PART_FD,
        SEGMENT_COMPACT,
        SEGMENT_COMPACT_FD,
    ]
    .iter()
    .any(|m| m.addr.id(0) == id)
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
            counters: vec![ErrorCounters::default(); stations],
            off_until: vec![None; stations],
            recent: vec![VecDeque::new(); stations],
            enforce_bus_off: false,
        }
    }

    /// Is `station` bus-off at `t_ns` (by a BusOff window or by its error counters)?
    pub fn bus_off(&self, station: usize, t_ns: u64) -> bool {
        self.windows
            .iter()
            .any(|w| w.active(t_ns) && w.fault == Fault::BusOff { station })
            || self.enforce_bus_off
                && self
                    .off_until
                    .get(station)
                    .is_some_and(|u| u.is_some_and(|u| t_ns < u))
    }

    /// `station`'s error counters at `t_ns` (a recovered bus-off station
    /// starts again from zero).
    pub fn error_counters(&mut self, station: usize, t_ns: u64) -> ErrorCounters {
        self.recover(station, t_ns);
        self.counters.get(station).copied().unwrap_or_default()
    }

    /// A bus-off station whose recovery time has passed rejoins from zero.
    fn recover(&mut self, station: usize, t_ns: u64) {
        if let Some(until) = self.off_until.get(station).copied().flatten()
            && t_ns >= until
        {
            self.off_until[station] = None;
            self.counters[station] = ErrorCounters::default();
        }
    }

    /// Fault confinement for one delivery of a frame from `from` completed
    /// at `t`: `lost` at this receiver (its error), `resent` (the sender's error).
    fn confine(&mut self, station: usize, from: usize, t: u64, lost: bool, resent: bool) {
        if let Some(c) = self.counters.get_mut(station) {
            if lost {
                c.rx_error();
            } else {
                c.rx_ok();
            }
        }
        let Some(recent) = self.recent.get_mut(from) else {
            return;
        };
        let Some(c) = self.counters.get_mut(from) else {
            return;
        };
        match recent.iter_mut().find(|(ft, _)| *ft == t) {
            // A later receiver of a frame counted good: now it was an error.
            Some((_, seen_lost)) if lost && !*seen_lost => {
                *seen_lost = true;
                c.tx_error();
                c.tec = c.tec.saturating_add(1); // undo the frame's −1
            }
            Some(_) => {}
            None => {
                if recent.len() == RECENT_FRAMES {
                    recent.pop_front();
                }
                recent.push_back((t, lost));
                // A resent frame: the error first, then the frame's own outcome.
                if resent {
                    c.tx_error();
                }
                if lost {
                    c.tx_error();
                } else {
                    c.tx_ok();
                }
            }
        }
        if self.enforce_bus_off && c.tec > BUS_OFF_ABOVE && self.off_until[from].is_none() {
            self.off_until[from] = Some(t + RECOVERY_NS);
        }
    }

    fn chance(&mut self, rate: f64) -> bool {
        rate > 0.0 && self.rng.random::<f64>() < rate
    }

    /// Takes one delivery the bus made to `station` at true time `now_ns`.
    pub fn deliver(&mut self, station: usize, mut d: Delivery, now_ns: u64) {
        let t = d.t_ns;
        self.recover(station, t);
        self.recover(d.from, t);
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
                        self.confine(station, d.from, t, true, false);
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
        self.confine(station, d.from, t, false, copies > 1);
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

    /// The host (station 0) sends `n` frames 200 µs apart to nodes 1–3.
    fn confined(windows: Vec<FaultWindow>, n: u16) -> FaultInjector {
        let mut bus = Bus::new(BusConfig::default(), 4);
        let mut inj = FaultInjector::new(windows, 7, 4);
        for k in 0..n {
            bus.send(0, Frame::new(0x100, 8, false), k as u64 * 200_000);
        }
        let mut t = 0;
        while t < n as u64 * 200_000 + 1_000_000 {
            t += 50_000;
            bus.advance(t);
            for s in 0..4 {
                while let Some(d) = bus.receive(s) {
                    inj.deliver(s, d, t);
                }
                while inj.ready(s, t).is_some() {}
            }
        }
        inj
    }

    #[test]
    fn injected_errors_move_the_counters_by_the_confinement_rules() {
        // Clean: nothing counts.
        let mut c = confined(vec![], 100);
        assert_eq!(c.error_counters(0, 0).registers(), (0, 0));
        // Every frame completing from 10 ms to 12 ms lost at every receiver.
        let w = FaultWindow::new(Fault::Loss { rate: 1.0 }, 10_000_000, 12_000_000);
        let mut inj = confined(vec![w], 70);
        assert_eq!(
            inj.stats.lost, 30,
            "10 frames at 3 receivers: {:?}",
            inj.stats
        );
        // Each receiver: REC + 1 per lost frame, − 1 per good one after.
        // The sender: + 8 per lost frame, − 1 per good one.
        let host = inj.error_counters(0, u64::MAX);
        let n1 = inj.error_counters(1, u64::MAX);
        assert_eq!(n1.rec, 0, "10 errors, then 10 good frames");
        assert_eq!(host.tec, 80 - 10, "8 per error, then 10 good frames");
        // A shorter run: the counters stand where the errors left them.
        let w = FaultWindow::new(Fault::Loss { rate: 1.0 }, 10_000_000, 12_000_000);
        let mut inj = confined(vec![w], 55);
        assert_eq!(inj.error_counters(2, u64::MAX).registers(), (0, 5));
        assert_eq!(inj.error_counters(0, u64::MAX).registers(), (40, 0));
        // Duplicates are the sender's errors only.
        let d = FaultWindow::new(Fault::Duplicate { rate: 1.0 }, 0, u64::MAX).on_ids(0x100..=0x100);
        let mut dup = confined(vec![d], 10);
        assert_eq!(dup.error_counters(0, u64::MAX).tec, 70);
        assert_eq!(dup.error_counters(1, u64::MAX).rec, 0);
    }

    #[test]
    fn a_sender_past_255_goes_bus_off_and_recovers_when_enforced() {
        let all = || vec![FaultWindow::new(Fault::Loss { rate: 1.0 }, 0, u64::MAX)];
        // Reported, not enforced (the default): every frame still goes out.
        let mut seen = confined(all(), 100);
        assert_eq!(seen.stats.bus_off_dropped, 0);
        assert_eq!(seen.error_counters(0, u64::MAX).registers().0, 255);
        let mut bus = Bus::new(BusConfig::default(), 4);
        let mut inj = FaultInjector::new(all(), 7, 4);
        inj.enforce_bus_off = true;
        for k in 0..100u64 {
            bus.send(0, Frame::new(0x100, 8, false), k * 200_000);
        }
        let mut t = 0;
        // Bus-off periods of the host and the frames each receiver lost.
        let (mut periods, mut was_off) = (0, false);
        while t < 21_000_000 {
            t += 50_000;
            bus.advance(t);
            for s in 0..4 {
                while let Some(d) = bus.receive(s) {
                    inj.deliver(s, d, t);
                }
            }
            let off = inj.bus_off(0, t);
            periods += (off && !was_off) as u32;
            was_off = off;
        }
        // TEC > 255 after 32 errors; bus-off for 1.408 ms (about 7 frames
        // 200 µs apart), then counters cleared, 32 more errors, off again,
        // and the rest lost: two periods in 100 frames, errors after each.
        assert_eq!(periods, 2, "{:?}", inj.stats);
        let lost = inj.stats.lost / 3;
        assert!((32 * 2 + 1..100).contains(&lost), "{:?}", inj.stats);
    }
}
