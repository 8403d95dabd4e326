//! A fault-injecting bridge between two CAN interfaces (`triquint-sim
//! proxy`): every frame received on side A is passed through the seeded
//! fault model of the in-process bus ([`FaultInjector`]: the same code, the
//! same fault kinds) and written to side B, and the other way round. With the
//! host on A and the drives on B, the host's frames and the drives' answers
//! cross the same faulty "wire" as in the in-process tests.
//!
//! Fault windows are timed from the first frame side A sends (the host's
//! first frame), so a schedule reads "from 300 ms into the upload". On a real
//! bridge the receiver timestamps a frame when the proxy writes it, so delay,
//! late and jitter faults all become extra latency of delivery. Decisions are
//! seeded, but which frame meets which draw depends on how the two streams
//! interleave in real time: over vcan a run is reproducible in its fault
//! rates and kinds, not frame for frame (the in-process bus is).

use std::collections::VecDeque;
use std::os::fd::AsRawFd;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::SystemTime;

use triquint_firmware::sync::OUTLIER_US;
use triquint_shared::protocol::{Frame, SegmentEvent, SegmentRx, TimeSync, decode};

use crate::bus::Delivery;
use crate::faults::{FaultInjector, FaultStats, FaultWindow};
use triquint_link::socketcan::{SocketCanError, SocketCanPort};

/// Station number of side A in the fault model (its frames go to [`B`]).
pub const A: usize = 0;
/// Station number of side B.
pub const B: usize = 1;

/// What the proxy counted.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct ProxyReport {
    /// Frames received on A (for B), and on B (for A).
    pub from_a: u64,
    pub from_b: u64,
    /// Frames written to B, and to A.
    pub to_b: u64,
    pub to_a: u64,
    /// What the fault model did.
    pub faults: FaultStats,
    /// (sequence, body CRC-32) of every version of a segment side A sent,
    /// reassembled before the faults (a compact segment rebuilt on the one
    /// before it, a resend in full), since the proxy started: a drive that
    /// executed segment k must report one of those of k. A resent first
    /// segment does not restart the list: a drive may already run the
    /// version sent before it.
    pub segments_from_a: Vec<(u16, u32)>,
    /// How late frames were written, beyond their receive time plus the
    /// injected delay: the proxy's own latency (µs), worst and mean.
    pub max_latency_us: f64,
    pub mean_latency_us: f64,
    /// Time syncs the proxy itself delayed by more than the drives' outlier
    /// gate (`firmware::sync::OUTLIER_US`): each is discarded by the drives,
    /// and a run of them for `sync_timeout` is a lost sync (a safe stop).
    pub late_syncs: u64,
    /// Wall time from the proxy's start to side A's first frame (s).
    pub first_a_frame_s: Option<f64>,
    pub wall_time_s: f64,
}

/// The bridge without sockets: frames in from either side, frames out when due.
pub struct Bridge {
    /// The schedule, with times relative to side A's first frame.
    spec: Vec<FaultWindow>,
    inj: FaultInjector,
    t0_ns: Option<u64>,
    /// Side A's segment stream, as sent.
    tap: SegmentRx,
    /// Frames handed out by [`Bridge::ready`].
    delivered: u64,
    pub report: ProxyReport,
}

impl Bridge {
    /// A bridge with fault windows timed from side A's first frame.
    pub fn new(spec: Vec<FaultWindow>, seed: u64) -> Self {
        Self {
            spec,
            // No window is active until side A has spoken.
            inj: FaultInjector::new(Vec::new(), seed, 2),
            t0_ns: None,
            tap: SegmentRx::default(),
            delivered: 0,
            report: ProxyReport::default(),
        }
    }

    /// A frame received on side `from` ([`A`] or [`B`]) with receive time `t_ns`.
    pub fn received(&mut self, from: usize, frame: Frame, t_ns: u64, now_ns: u64) {
        if from == A && self.t0_ns.is_none() {
            self.t0_ns = Some(t_ns);
            self.inj.windows = self
                .spec
                .iter()
                .map(|w| FaultWindow {
                    from_ns: t_ns.saturating_add(w.from_ns),
                    until_ns: t_ns.saturating_add(w.until_ns),
                    ..w.clone()
                })
                .collect();
        }
        if from == A {
            self.report.from_a += 1;
            self.tap(&frame);
        } else {
            self.report.from_b += 1;
        }
        let d = Delivery {
            frame,
            t_ns,
            own: false,
            from,
        };
        self.inj.deliver(1 - from, d, now_ns);
        self.report.faults = self.inj.stats;
    }

    fn tap(&mut self, f: &Frame) {
        let Ok((msg, _)) = decode(f) else {
            return;
        };
        if let Some(SegmentEvent::Complete { segment, crc, .. }) =
            self.tap.push(msg.kind(), f.payload())
        {
            let list = &mut self.report.segments_from_a;
            if !list.contains(&(segment.seq, crc)) {
                list.push((segment.seq, crc));
            }
        }
    }

    /// The next frame due for side `to` at `now_ns`.
    pub fn ready(&mut self, to: usize, now_ns: u64) -> Option<Frame> {
        let d = self.inj.ready(to, now_ns)?;
        let late_us = now_ns.saturating_sub(d.t_ns) as f64 * 1e-3;
        self.delivered += 1;
        let r = &mut self.report;
        r.max_latency_us = r.max_latency_us.max(late_us);
        if d.frame.id == TimeSync::DEF.addr.id(0) && late_us > OUTLIER_US as f64 {
            r.late_syncs += 1;
        }
        r.mean_latency_us += (late_us - r.mean_latency_us) / self.delivered as f64;
        Some(d.frame)
    }

    /// When the next held frame (either side) is due.
    pub fn next_due(&self) -> Option<u64> {
        [A, B].iter().filter_map(|&s| self.inj.next_due(s)).min()
    }

    /// Time (ns) of side A's first frame.
    pub fn t0_ns(&self) -> Option<u64> {
        self.t0_ns
    }
}

/// Waits until a socket is readable or `timeout_ns` passed.
fn wait(fds: [i32; 2], timeout_ns: u64) {
    let mut p = fds.map(|fd| libc::pollfd {
        fd,
        events: libc::POLLIN,
        revents: 0,
    });
    let ts = libc::timespec {
        tv_sec: (timeout_ns / 1_000_000_000) as libc::time_t,
        tv_nsec: (timeout_ns % 1_000_000_000) as libc::c_long,
    };
    // SAFETY: `p` and `ts` are valid for the call; an error (EINTR on a
    // signal) just ends the wait early.
    unsafe {
        libc::ppoll(p.as_mut_ptr(), 2, &ts, std::ptr::null());
    }
}

/// Longest sleep between two looks at the stop flag.
const IDLE_NS: u64 = 50_000_000;

/// Opens side A and side B (classic CAN, or CAN-FD with `fd`).
pub fn open(a: &str, b: &str, fd: bool) -> Result<[SocketCanPort; 2], SocketCanError> {
    let epoch = SystemTime::now();
    // No echo of our own writes: a frame written to B is never read back as
    // one from B.
    Ok([
        SocketCanPort::open(a, fd, false, epoch)?,
        SocketCanPort::open(b, fd, false, epoch)?,
    ])
}

/// Bridges the two ports of [`open`] until `stop` is set; `bridge.report`
/// holds the counts either way.
pub fn run(
    mut ports: [SocketCanPort; 2],
    bridge: &mut Bridge,
    stop: &AtomicBool,
) -> Result<(), SocketCanError> {
    let fds = [ports[A].as_raw_fd(), ports[B].as_raw_fd()];
    let start = ports[A].now_ns();
    let mut outbox: [VecDeque<Frame>; 2] = [VecDeque::new(), VecDeque::new()];
    let result = loop {
        if stop.load(Ordering::Relaxed) {
            break Ok(());
        }
        let now = ports[A].now_ns();
        if let Err(e) = pump(&mut ports, bridge, &mut outbox, now) {
            break Err(e);
        }
        let mut sleep = bridge
            .next_due()
            .map_or(IDLE_NS, |d| d.saturating_sub(now).min(IDLE_NS));
        if outbox.iter().any(|q| !q.is_empty()) {
            // A full transmit queue: try again shortly.
            sleep = sleep.min(200_000);
        }
        wait(fds, sleep.max(1));
    };
    let end = ports[A].now_ns();
    bridge.report.wall_time_s = end.saturating_sub(start) as f64 * 1e-9;
    bridge.report.first_a_frame_s = bridge
        .t0_ns()
        .map(|t| t.saturating_sub(start) as f64 * 1e-9);
    result
}

/// Reads both sides into the bridge and writes out what is due.
fn pump(
    ports: &mut [SocketCanPort; 2],
    bridge: &mut Bridge,
    outbox: &mut [VecDeque<Frame>; 2],
    now: u64,
) -> Result<(), SocketCanError> {
    for side in [A, B] {
        while let Some(r) = ports[side].recv()? {
            bridge.received(side, r.frame, r.t_ns, now);
        }
    }
    for to in [A, B] {
        while let Some(f) = bridge.ready(to, now) {
            outbox[to].push_back(f);
        }
        while let Some(f) = outbox[to].front() {
            if !ports[to].send(f)? {
                break;
            }
            outbox[to].pop_front();
            if to == A {
                bridge.report.to_a += 1;
            } else {
                bridge.report.to_b += 1;
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::faults::Fault;

    const MS: u64 = 1_000_000;

    /// Frames 0..n from `from`, one every ms from `t0`, and what came out
    /// (looking every 0.1 ms until 1 s after the last).
    fn stream(bridge: &mut Bridge, from: usize, t0: u64, n: u8) -> Vec<(u64, Frame)> {
        let mut out = Vec::new();
        for step in 0..(n as u64 + 1000) * 10 {
            let t = t0 + step * MS / 10;
            if step % 10 == 0 && step / 10 < n as u64 {
                let mut f = Frame::new(0x100, 8, false);
                f.data[0] = (step / 10) as u8;
                bridge.received(from, f, t, t);
            }
            while let Some(f) = bridge.ready(1 - from, t) {
                out.push((t, f));
            }
        }
        out
    }

    #[test]
    fn clean_bridge_passes_every_frame_both_ways_at_once() {
        let mut br = Bridge::new(Vec::new(), 1);
        let ab = stream(&mut br, A, 5 * MS, 50);
        let ba = stream(&mut br, B, 100 * MS, 50);
        for out in [&ab, &ba] {
            assert_eq!(out.len(), 50);
            assert!(
                out.iter()
                    .enumerate()
                    .all(|(k, (_, f))| f.data[0] == k as u8)
            );
        }
        assert!(ab.iter().all(|(t, f)| *t == 5 * MS + f.data[0] as u64 * MS));
        assert_eq!((br.report.from_a, br.report.from_b), (50, 50));
        assert_eq!(br.t0_ns(), Some(5 * MS));
    }

    #[test]
    fn faults_are_seeded_and_timed_from_side_a_first_frame() {
        // Loss of everything from 20 ms to 30 ms after A's first frame.
        let spec = vec![FaultWindow::new(
            Fault::Loss { rate: 1.0 },
            20 * MS,
            30 * MS,
        )];
        let mut br = Bridge::new(spec, 3);
        // B's frames before A has spoken are never faulted.
        let early = stream(&mut br, B, 0, 40);
        assert_eq!(early.len(), 40);
        let ab = stream(&mut br, A, 2000 * MS, 60);
        let got: Vec<u8> = ab.iter().map(|(_, f)| f.data[0]).collect();
        let want: Vec<u8> = (0..60).filter(|k| !(20..30).contains(k)).collect();
        assert_eq!(got, want);
        assert_eq!(br.report.faults.lost, 10);

        // The same seed and the same frames: the same faults; jitter delays
        // delivery by at most its bound and keeps the order.
        let spec = |s: core::ops::RangeInclusive<u16>| {
            vec![
                FaultWindow::new(Fault::Duplicate { rate: 0.2 }, 0, u64::MAX),
                FaultWindow::new(Fault::Jitter { max_ns: 300_000 }, 0, u64::MAX),
            ]
            .into_iter()
            .map(move |w: FaultWindow| w.on_ids(s.clone()))
            .collect::<Vec<_>>()
        };
        let mut x = Bridge::new(spec(0x100..=0x100), 9);
        let mut y = Bridge::new(spec(0x100..=0x100), 9);
        let (ox, oy) = (stream(&mut x, A, 0, 100), stream(&mut y, A, 0, 100));
        assert_eq!(ox, oy);
        assert_eq!(ox.len() as u64, 100 + x.report.faults.duplicated);
        assert!(x.report.faults.duplicated > 5);
        assert!(ox.windows(2).all(|w| w[0].1.data[0] <= w[1].1.data[0]));
        assert!(
            ox.iter()
                .all(|(t, f)| *t >= f.data[0] as u64 * MS && *t <= f.data[0] as u64 * MS + MS / 2)
        );
        // Identifiers outside the window's range pass untouched.
        let mut z = Bridge::new(spec(0x200..=0x2FF), 9);
        assert_eq!(stream(&mut z, A, 0, 100).len(), 100);
    }

    #[test]
    fn the_tap_lists_side_a_segments_as_sent_before_the_faults() {
        // Short segments from rest: the first one goes compact too.
        let plan = crate::testplan::point_to_point(15, 0.9, 0.1).unwrap();
        let wire = plan.wire_segments().unwrap();
        let n = wire.len();
        let spec = vec![FaultWindow::new(Fault::Corrupt { rate: 0.3 }, 0, u64::MAX)];
        let mut br = Bridge::new(spec, 4);
        let mut t = 0;
        let mut out = SegmentRx::default();
        let mut through = 0;
        let mut chain = triquint_shared::protocol::compact::Chain::default();
        let mut want: Vec<(u16, u32)> = Vec::new();
        // Every segment twice, the second time resent in full as the host
        // does (the first one's too): each version listed once.
        for (i, s) in wire.iter().chain(&wire).enumerate() {
            let sent = if i < n {
                chain.next(s, wire.get(s.seq as usize + 1))
            } else {
                chain.full(s)
            };
            let v = (s.seq, sent.held().body_crc());
            if !want.contains(&v) {
                want.push(v);
            }
            for f in sent.frames(false) {
                t += 100_000;
                br.received(A, f, t, t);
                while let Some(g) = br.ready(B, t) {
                    let Ok((msg, _)) = decode(&g) else {
                        continue;
                    };
                    through += matches!(
                        out.push(msg.kind(), g.payload()),
                        Some(SegmentEvent::Complete { .. })
                    ) as usize;
                }
            }
        }
        // Compact versions, and the resends' own.
        assert!(want.len() > n, "{} versions of {n} segments", want.len());
        // The first segment's compact version and its resend in full: a
        // drive may run either.
        assert_eq!(want.iter().filter(|v| v.0 == 0).count(), 2, "{want:?}");
        assert_eq!(br.report.segments_from_a, want);
        // What crossed the faulty wire did get corrupted.
        let corrupted = br.report.faults.corrupted;
        assert!(
            corrupted > 10 && through < 2 * n - 1,
            "{corrupted} corrupted, {through} through"
        );
    }

    /// The VM suite's CRC test (test_faults.py: Case I through the proxy,
    /// `--seed 12 --corrupt 0.02`) must see a corrupted part: Case I's
    /// first pass, as the host sends it (first segment from rest, then
    /// continuations), already has one, and the tap refuses it.
    #[test]
    fn the_vm_crc_scenario_corrupts_a_part_of_case_one() {
        let path = concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../testdata/hil/paper-case1.json"
        );
        let plan: triquint_shared::plan::Plan =
            serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let wire = plan.wire_segments().unwrap();
        let spec = vec![FaultWindow::new(Fault::Corrupt { rate: 0.02 }, 0, u64::MAX)];
        let mut br = Bridge::new(spec, 12);
        let mut chain = triquint_shared::protocol::compact::Chain::default();
        let (mut t, mut frames, mut complete) = (0, 0, 0);
        let mut out = SegmentRx::default();
        for (i, s) in wire.iter().enumerate() {
            for f in chain.next(s, wire.get(i + 1)).frames(false) {
                frames += 1;
                t += 100_000;
                br.received(A, f, t, t);
                while let Some(g) = br.ready(B, t) {
                    let Ok((msg, _)) = decode(&g) else {
                        continue;
                    };
                    complete += matches!(
                        out.push(msg.kind(), g.payload()),
                        Some(SegmentEvent::Complete { .. })
                    ) as usize;
                }
            }
        }
        let corrupted = br.report.faults.corrupted;
        eprintln!("Case I: {frames} classic frames, {corrupted} corrupted");
        assert!(
            corrupted > 0 && complete < wire.len(),
            "{corrupted} {complete}"
        );
    }
}
