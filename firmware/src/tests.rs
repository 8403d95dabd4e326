//! State-machine, queue and stop tests of the node core, driven by frames and
//! ticks with a perfect (or deliberately wrong) encoder.

extern crate std;
use std::vec::Vec;

use nalgebra::Vector3;
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::config::{DriveConfig, DriveSettings};
use triquint_shared::protocol::segment::{FLAG_FIRST, FLAG_LAST};
use triquint_shared::protocol::{
    Command, CommandCode, Emergency, FaultCode, Frame, Msg, Reject, State, TimeSync, WireSegment,
    config_write_frame, decode,
};
use triquint_shared::quintic::Quintic;
use triquint_shared::{Limits, Robot};

use crate::hal::{Encoder, MotorOutput, RxFrame};
use crate::node::Node;
use crate::scaling::Phase;

mod ceiling_lock;
mod hold;
mod homing;
mod reactions;

/// A one-axis plant under gravity for the enable check: position and
/// velocity (m, m/s), acceleration per motor torque (m/s² per N·m), the
/// torque that holds it (N·m), and the encoder's error (× counts).
#[derive(Clone, Copy, Debug)]
struct Plant {
    q: f64,
    v: f64,
    gain: f64,
    load: f64,
    encoder: f64,
    /// The torque commanded last tick, acting now (N·m).
    pending: f64,
}

const CAP: usize = 4;
const TICK: u64 = 1000;

struct Enc(i64);
impl Encoder for Enc {
    fn read_counts(&mut self) -> i64 {
        self.0
    }
}
struct Motor(f32, bool);
impl MotorOutput for Motor {
    fn set_torque(&mut self, t: f32) {
        self.0 = t;
    }
    fn enable(&mut self, on: bool) {
        self.1 = on;
    }
}

/// One node (axis 1 = node 2) with host time = local time.
struct Rig {
    node: Node<CAP>,
    cfg: DriveConfig,
    t: u64,
    /// Encoder offset from the reference (m).
    offset: f32,
    /// Where the axis stands before it is armed (m).
    parked: f32,
    sync_seq: u8,
    next_sync: u64,
    syncing: bool,
    sent: Vec<Frame>,
    max_stop_jerk: f32,
    token: u8,
    /// The ideal encoder cannot answer the enable check (it follows the
    /// reference, not a torque): count it as passed, unless a test says not.
    trusted: bool,
    /// The power stage at the last tick.
    powered: bool,
    /// The axis as a plant (else it follows the reference ideally).
    plant: Option<Plant>,
}

fn q_at(z: f64, x: f64) -> Vector3<f64> {
    let m = Robot::default().model::<f64>();
    Pose::from_cartesian(&m, Vector3::new(x, -x, z)).unwrap().q
}

/// Rest-to-rest segments of equal joint steps, `h` seconds each: equal
/// steps make the end jerk 60Δ/h³ equal on both sides of every knot (C3).
fn segments(n: usize, h: f64) -> Vec<WireSegment> {
    segments_of(&std::vec![h; n])
}

/// [`segments`] with durations `hs`, each segment rest to rest, its step
/// scaled by (h/h_max)³ so that the end jerks still match (C3): a longer
/// segment is the faster one.
fn segments_of(hs: &[f64]) -> Vec<WireSegment> {
    let n = hs.len();
    let q0 = q_at(0.62, 0.0);
    let step = q_at(0.63, 0.01) - q0;
    let longest = hs.iter().copied().fold(0.0, f64::max);
    let mut ends = std::vec![q0];
    for h in hs {
        let last = ends[ends.len() - 1];
        ends.push(last + step * (h / longest).powi(3));
    }
    (0..n)
        .map(|i| {
            let h = hs[i];
            let (a, b) = (ends[i], ends[i + 1]);
            let mut coeffs = [[0.0; 6]; 3];
            for j in 0..3 {
                let d = b[j] - a[j];
                coeffs[j] = [
                    a[j],
                    0.0,
                    0.0,
                    10.0 * d / h.powi(3),
                    -15.0 * d / h.powi(4),
                    6.0 * d / h.powi(5),
                ];
            }
            let mut flags = 0;
            if i == 0 {
                flags |= FLAG_FIRST;
            }
            if i + 1 == n {
                flags |= FLAG_LAST;
            }
            WireSegment::from_quintic(
                i as u16,
                &Quintic {
                    coeffs,
                    duration: h,
                },
                flags,
            )
            .unwrap()
        })
        .collect()
}

impl Rig {
    /// The receive side's item for `frame`, received now (the tick is not run).
    fn receive(&mut self, frame: Frame) -> Option<crate::inbox::Item> {
        let rx = RxFrame {
            frame,
            timestamp_us: self.t,
        };
        self.node.receiver.on_frame(&rx, self.node.drive.snapshot())
    }

    fn new() -> Self {
        Self::with_stop_time(0.4)
    }

    fn with_stop_time(stop: f64) -> Self {
        // The test segments are short rest-to-rest moves: limits wide enough
        // for the node's own limit check to accept them.
        let limits = Limits {
            velocity: 1.0,
            acceleration: 10.0,
            jerk: 50.0,
            ..Limits::default()
        };
        let cfg = DriveConfig::new(
            &Robot::default(),
            &limits,
            1,
            &DriveSettings::default(),
            stop,
            0.2,
        );
        let mut r = Self {
            node: Node::new(2),
            cfg,
            t: 1_000_000,
            offset: 0.0,
            parked: 0.0,
            sync_seq: 0,
            next_sync: 0,
            syncing: true,
            sent: Vec::new(),
            max_stop_jerk: 0.0,
            token: 0,
            trusted: true,
            powered: false,
            plant: None,
        };
        r.tick();
        r
    }

    fn rx(&mut self, f: Frame) {
        self.node.on_frame(&RxFrame {
            frame: f,
            timestamp_us: self.t,
        });
        while let Some(f) = self.node.pop_tx() {
            self.sent.push(f);
        }
    }

    fn configure(&mut self) {
        for (k, v) in self.cfg.to_values().iter().enumerate() {
            self.rx(config_write_frame(2, k as u8, *v));
        }
        let crc = self.cfg.crc();
        self.command(CommandCode::ConfigCommit, crc);
        assert_eq!(self.node.config_crc(), crc);
    }

    fn command(&mut self, c: CommandCode, arg: u32) -> u8 {
        self.command_to(c, arg, 0).map_or(255, |(result, _)| result)
    }

    /// The last answer (result, value) to a command sent to `node`'s
    /// address (0: broadcast), if any.
    fn command_to(&mut self, c: CommandCode, arg: u32, node: u8) -> Option<(u8, u32)> {
        self.command_with(c, arg, 0, node)
    }

    /// A Stop carrying `dated_100us` while Running: the ticks (ms) from it
    /// to Idle.
    fn dated_stop_ms(&mut self, dated_100us: u16) -> i64 {
        self.stop_ms(CommandCode::Stop, 0, dated_100us)
    }

    /// Ticks from a command `c` (Stop or FeedHold) for host time `arg` (0:
    /// on receipt) carrying `dated_100us` until the node is at rest.
    fn stop_ms(&mut self, c: CommandCode, arg: u32, dated_100us: u16) -> i64 {
        let t = self.command_with(c, arg, dated_100us, 0);
        assert_eq!(t.map(|a| a.0), Some(0));
        let mut ms = 0;
        let moving = |r: &Self| match c {
            CommandCode::FeedHold => r.node.scaling_phase() != Phase::Rest,
            _ => r.node.state() == State::Stopping,
        };
        while moving(self) && ms < 10_000 {
            self.tick();
            ms += 1;
        }
        if c != CommandCode::FeedHold {
            assert_eq!(self.node.state(), State::Idle);
        }
        ms
    }

    /// [`Rig::command_to`] with `arg2`.
    fn command_with(&mut self, c: CommandCode, arg: u32, arg2: u16, node: u8) -> Option<(u8, u32)> {
        let n = self.sent.len();
        self.token = self.token.wrapping_add(1);
        self.rx(Command {
            command: c as u8,
            token: self.token,
            arg,
            arg2,
        }
        .to_frame(node));
        self.sent[n..]
            .iter()
            .filter_map(|f| match decode(f) {
                Ok((Msg::CommandAck(a), _)) => Some((a.result, a.value)),
                _ => None,
            })
            .next_back()
    }

    fn tick(&mut self) {
        if self.syncing && self.t >= self.next_sync {
            self.sync_seq = self.sync_seq.wrapping_add(1);
            let prev = self.next_sync.saturating_sub(20_000) as u32;
            self.rx(TimeSync {
                seq: self.sync_seq,
                prev_tx_us: prev,
            }
            .to_frame(0));
            self.next_sync = self.t + 20_000;
        }
        let reference = self.node.stats.reference.q[1];
        // The axis follows the reference and stays where it came to rest.
        let q = match self.node.state() {
            State::Idle | State::Loaded => self.parked + self.offset,
            _ => {
                self.parked = reference;
                reference + self.offset
            }
        };
        let cpm = self.cfg.counts_per_metre as f64;
        let counts = match self.plant {
            Some(p) => (p.q * cpm * p.encoder).round() as i64,
            None => (q as f64 * cpm).round() as i64,
        };
        let mut m = Motor(0.0, self.powered);
        self.node.tick(self.t, &mut Enc(counts), &mut m);
        self.powered = m.1;
        if let Some(p) = self.plant.as_mut().filter(|_| m.1) {
            let dt = TICK as f64 * 1e-6;
            // A command acts from the next tick on, for one tick.
            let a = (p.pending - p.load) * p.gain;
            p.pending = m.0 as f64;
            p.q += p.v * dt + 0.5 * a * dt * dt;
            p.v += a * dt;
        }
        if self.trusted {
            self.node.drive.assume_verified();
        }
        if self.node.state() == State::Stopping {
            let j = self.node.stats.reference.qddd.amax();
            self.max_stop_jerk = self.max_stop_jerk.max(j);
        }
        while let Some(f) = self.node.pop_tx() {
            self.sent.push(f);
        }
        self.t += TICK;
    }

    fn run(&mut self, ms: u64) {
        for _ in 0..ms {
            self.tick();
        }
    }

    fn send_segment(&mut self, s: &WireSegment) -> Option<(Reject, u8)> {
        let n = self.sent.len();
        for f in s.frames(false) {
            self.rx(f);
        }
        self.acks_since(n).last().copied()
    }

    fn acks_since(&self, n: usize) -> Vec<(Reject, u8)> {
        self.sent[n..]
            .iter()
            .filter_map(|f| match decode(f) {
                Ok((Msg::SegmentAck(a), _)) => Reject::from_u8(a.result).map(|r| (r, a.depth)),
                _ => None,
            })
            .collect()
    }

    /// The Emergency frames it sent.
    fn emergency_frames(&self) -> Vec<Emergency> {
        self.sent
            .iter()
            .filter_map(|f| match decode(f) {
                Ok((Msg::Emergency(e), 2)) => Some(e),
                _ => None,
            })
            .collect()
    }

    fn emergencies(&self) -> Vec<u8> {
        self.emergency_frames().iter().map(|e| e.code).collect()
    }

    /// The ramps its Emergency frames carried (100 µs units).
    fn emergency_ramps_100us(&self) -> Vec<u16> {
        self.emergency_frames()
            .iter()
            .map(|e| e.ramp_100us)
            .collect()
    }

    /// Configured, synced (with a settled hold position at the plan start), loaded.
    fn loaded(segs: &[WireSegment]) -> Self {
        Self::loaded_with(Self::new(), segs)
    }

    fn loaded_with(mut r: Self, segs: &[WireSegment]) -> Self {
        r.parked = segs[0].normalised_f32()[1][0];
        r.configure();
        r.run(100);
        for s in segs.iter().take(CAP) {
            assert_eq!(r.send_segment(s).map(|a| a.0), Some(Reject::Accepted));
        }
        r
    }

    fn start(&mut self) {
        assert_eq!(self.command(CommandCode::Arm, 0), 0, "arm");
        assert_eq!(self.node.state(), State::Armed);
        let at = (self.t + 10_000) as u32;
        assert_eq!(self.command(CommandCode::Start, at), 0, "start");
    }
}

#[test]
fn happy_path_through_every_state_to_completion() {
    let segs = segments(6, 0.3);
    let mut r = Rig::new();
    r.parked = segs[0].normalised_f32()[1][0];
    assert_eq!(r.node.state(), State::Idle);
    r.configure();
    r.run(100);
    assert!(r.node.is_synced());
    assert_eq!(r.send_segment(&segs[0]), Some((Reject::Accepted, 1)));
    assert_eq!(r.node.state(), State::Loaded);
    for s in &segs[1..4] {
        assert_eq!(r.send_segment(s).map(|a| a.0), Some(Reject::Accepted));
    }
    // Queue full: the fifth is refused, not lost.
    assert_eq!(
        r.send_segment(&segs[4]).map(|a| a.0),
        Some(Reject::QueueFull)
    );
    r.start();
    r.run(9);
    assert_eq!(r.node.state(), State::Armed);
    r.run(2);
    assert_eq!(r.node.state(), State::Running);
    // Stream the rest as the queue drains (flow control by queue depth).
    let mut next = 4;
    for _ in 0..3000 {
        if next < segs.len() && r.node.queue_depth() < CAP {
            assert_eq!(
                r.send_segment(&segs[next]).map(|a| a.0),
                Some(Reject::Accepted)
            );
            next += 1;
        }
        r.tick();
        if r.node.state() == State::Idle {
            break;
        }
    }
    assert_eq!(next, segs.len());
    assert_eq!(r.node.state(), State::Idle, "completed");
    assert_eq!(r.node.fault(), FaultCode::None);
    assert!(r.emergencies().is_empty());
    // Holds the plan's end.
    let end = segs[5].normalised_f64()[1].iter().sum::<f64>();
    assert!((r.node.stats.reference.q[1] as f64 - end).abs() < 1e-6);
}

#[test]
fn segments_are_rejected_with_reasons() {
    let segs = segments(4, 0.3);
    let mut r = Rig::new();
    // No configuration yet: wrong state.
    assert_eq!(
        r.send_segment(&segs[0]).map(|a| a.0),
        Some(Reject::WrongState)
    );
    r.configure();
    r.run(50);
    assert_eq!(
        r.send_segment(&segs[0]).map(|a| a.0),
        Some(Reject::Accepted)
    );
    assert_eq!(
        r.send_segment(&segs[0]).map(|a| a.0),
        Some(Reject::Duplicate)
    );
    assert_eq!(
        r.send_segment(&segs[2]).map(|a| a.0),
        Some(Reject::OutOfOrder)
    );
    // A corrupted part: the CRC over the whole segment catches it.
    let n = r.sent.len();
    for (k, mut f) in segs[1].frames(false).enumerate() {
        if k == 9 {
            f.data[5] ^= 0x01;
        }
        r.rx(f);
    }
    assert_eq!(r.acks_since(n).last().map(|a| a.0), Some(Reject::BadCrc));
    // A jump in position.
    let mut bad = segs[2];
    bad.seq = 1;
    bad.flags = 0;
    assert_eq!(
        r.send_segment(&bad).map(|a| a.0),
        Some(Reject::Discontinuous)
    );
    // The right one still goes in.
    assert_eq!(
        r.send_segment(&segs[1]).map(|a| a.0),
        Some(Reject::Accepted)
    );
    assert_eq!(r.node.next_seq(), 2);
    assert!(r.node.stats.reason_counts[Reject::Duplicate as usize] >= 1);
    assert!(r.node.stats.rejects >= 4);
}

#[test]
fn arm_is_refused_without_sync_far_from_start_or_empty() {
    let segs = segments(2, 0.3);
    // Not synced.
    let mut r = Rig::new();
    r.syncing = false;
    r.configure();
    r.run(20);
    r.send_segment(&segs[0]);
    assert_eq!(r.command(CommandCode::Arm, 0), FaultCode::NotSynced as u8);
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.emergencies(), std::vec![FaultCode::NotSynced as u8]);
    assert_eq!(r.command(CommandCode::ClearFault, 0), 0);
    assert_eq!(r.node.state(), State::Idle);
    assert_eq!(r.node.next_seq(), 0);
    // Far from the plan start.
    let mut r = Rig::loaded(&segs);
    r.offset = 1e-3;
    r.run(5);
    assert_eq!(r.command(CommandCode::Arm, 0), FaultCode::ArmTooFar as u8);
    // A refusal: still Loaded, no fault, no Emergency; nearer, it arms.
    assert_eq!(r.node.state(), State::Loaded);
    assert_eq!(r.node.fault(), FaultCode::None);
    assert!(r.emergencies().is_empty());
    r.offset = 0.0;
    r.run(5);
    assert_eq!(r.command(CommandCode::Arm, 0), 0);
    assert_eq!(r.node.state(), State::Armed);
    // Arm in Idle: wrong state, no fault.
    let mut r = Rig::new();
    r.configure();
    assert_eq!(r.command(CommandCode::Arm, 0), FaultCode::WrongState as u8);
    assert_eq!(r.node.state(), State::Idle);
}

#[test]
fn start_in_the_past_faults_and_stop_disarms() {
    let segs = segments(2, 0.3);
    let mut r = Rig::loaded(&segs);
    assert_eq!(r.command(CommandCode::Arm, 0), 0);
    assert_eq!(r.command(CommandCode::Stop, 0), 0);
    assert_eq!(r.node.state(), State::Loaded);
    assert_eq!(r.command(CommandCode::Arm, 0), 0);
    let past = (r.t - 50_000) as u32;
    assert_eq!(
        r.command(CommandCode::Start, past),
        FaultCode::StartInPast as u8
    );
    assert_eq!(r.node.state(), State::Fault);
    // Reset is refused in Fault; ClearFault then Reset work.
    assert_eq!(
        r.command(CommandCode::Reset, 0),
        FaultCode::WrongState as u8
    );
    assert_eq!(r.command(CommandCode::ClearFault, 0), 0);
    assert_eq!(r.command(CommandCode::Reset, 0), 0);
    assert_eq!(r.node.state(), State::Idle);
}

/// Underrun: only part of a longer plan arrives; the node stops along the
/// path with a jerk-limited time-scaling, inside the buffered path, then faults.
#[test]
fn underrun_stops_along_the_path_with_bounded_jerk() {
    let h = 0.8;
    let segs = segments(8, h);
    // The plan's own maxima (rest-to-rest quintics: 1.875Δ/h, 5.774Δ/h², 60Δ/h³).
    let delta = segs
        .iter()
        .flat_map(|s| {
            let b = s.normalised_f64();
            (0..3).map(move |j| b[j][1..].iter().sum::<f64>().abs())
        })
        .fold(0.0, f64::max);
    let (v, a, j) = (
        1.875 * delta / h,
        5.7735 * delta / (h * h),
        60.0 * delta / h.powi(3),
    );
    let limit = Limits::default().jerk;
    let ts = triquint_shared::protocol::stop_ramp::stop_time(v, a, j, limit, 1.0);
    let mut r = Rig::with_stop_time(ts);
    r.cfg.max_jerk = limit as f32;
    let mut r = Rig::loaded_with(r, &segs[..3]);
    r.start();
    let mut stop_at = None;
    for _ in 0..6000 {
        r.tick();
        if stop_at.is_none() && r.node.state() == State::Stopping {
            stop_at = Some(r.t);
        }
        if r.node.state() == State::Fault {
            break;
        }
    }
    let stop_at = stop_at.expect("underrun detected");
    // Its own fault: the ramp it vouches for, carried to the peers, shorter
    // than the one the configuration was sized with.
    let carried = r.emergency_ramps_100us();
    std::eprintln!("stopped in {} µs, carried {carried:?}", r.t - stop_at);
    assert_eq!(carried.len(), 1);
    assert!(
        carried[0] > 0 && (carried[0] as f64) * 1e-4 < ts,
        "{carried:?}"
    );
    assert!(((r.t - stop_at) as f64) * 1e-6 < ts);
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.node.fault(), FaultCode::Underrun);
    assert_eq!(r.emergencies(), std::vec![FaultCode::Underrun as u8]);
    // At rest, on the path, inside what was buffered (3 segments).
    assert_eq!(r.node.scaling_phase(), Phase::Rest);
    assert_eq!(r.node.stats.reference.qd.amax(), 0.0);
    let end_of_buffer = segs[2].normalised_f64()[1].iter().sum::<f64>();
    let rest = r.node.stats.reference.q[1] as f64;
    let start = segs[0].normalised_f64()[1][0];
    assert!((rest - start).abs() < (end_of_buffer - start).abs());
    // The stop is jerk-limited: the measured joint jerk (q'''σ³ + 3q''σσ̇ + q'σ̈)
    // stays within the configured jerk limit.
    std::eprintln!(
        "plan jerk {j:.3}, stop time {ts:.3} s, max jerk during the stop {:.3} m/s³",
        r.max_stop_jerk
    );
    assert!(r.max_stop_jerk > 0.0);
    assert!(
        (r.max_stop_jerk as f64) <= limit * 1.001,
        "stop jerk {} > {limit}",
        r.max_stop_jerk
    );
}

/// A fault's stop runs the ramp its node vouches for, and a peer that
/// takes its Emergency runs the same one (the stop ends on the same tick)
/// and says so in its own; a ramp shorter than a segment the peer holds
/// needs gets the full ramp, and its Emergency carries none.
#[test]
fn a_peer_runs_the_ramp_a_fault_stop_carries_when_it_covers_what_it_holds() {
    let h = 0.8;
    let segs = segments(8, h);
    let rig = || {
        let mut r = Rig::with_stop_time(0.5);
        r.cfg.max_jerk = 5.0;
        r
    };
    // The node that faults (Underrun: it holds 3 segments).
    let mut a = Rig::loaded_with(rig(), &segs[..3]);
    a.start();
    let mut ticks = 0;
    while a.node.state() != State::Stopping {
        a.tick();
        ticks += 1;
        assert!(ticks < 6000, "underrun detected");
    }
    let carried = a.emergency_ramps_100us();
    assert_eq!(carried.len(), 1);
    assert!(carried[0] > 0 && carried[0] < 5000, "{carried:?}");
    let sent = a.emergency_frames()[0];
    let stop_ticks = |r: &mut Rig| {
        let mut n = 0u32;
        while r.node.state() == State::Stopping {
            r.tick();
            n += 1;
        }
        assert_eq!(r.node.state(), State::Fault);
        n
    };
    let a_stop = stop_ticks(&mut a);
    let a_rest = a.node.stats.reference.q;
    // Peers holding one segment more, told at the instant of the fault.
    for (ramp, runs) in [(carried[0], carried[0]), (carried[0] - 1, 0)] {
        let mut b = Rig::loaded_with(rig(), &segs[..4]);
        b.start();
        b.run(ticks - 1);
        assert_eq!(b.node.state(), State::Running);
        // A tick late, as a frame on the bus is: dated to the sender's instant.
        b.tick();
        b.rx(Emergency {
            ramp_100us: ramp,
            ..sent
        }
        .to_frame(3));
        b.tick();
        assert_eq!(b.node.state(), State::Stopping);
        assert_eq!(b.emergency_ramps_100us(), std::vec![runs]);
        let b_stop = stop_ticks(&mut b);
        let apart = (b.node.stats.reference.q - a_rest).amax();
        std::eprintln!(
            "carried {ramp}: stop {b_stop} ticks, the fault's node {a_stop}; rest {apart:e} m apart"
        );
        if runs > 0 {
            assert!(b_stop.abs_diff(a_stop) <= 1, "{b_stop} against {a_stop}");
            // The same σ(t) from the same plan time: the same rest pose.
            assert!(apart < 2e-7, "rest poses {apart:e} m apart");
        } else {
            assert!(b_stop > a_stop + 100, "{b_stop} against {a_stop}");
        }
    }
}

/// A host that configures a stop ramp far too short for the plan (50 ms)
/// cannot make the stop harder: the drive runs its own ramp for the
/// segments it holds, and the stop's joint jerk stays within its jerk
/// ceiling.
#[test]
fn a_too_short_configured_stop_ramp_cannot_make_the_stop_harder() {
    let h = 0.8;
    let segs = segments(8, h);
    let mut r = Rig::with_stop_time(0.05);
    let ceiling = 6.0f32;
    (r.cfg.max_jerk, r.cfg.ceiling_jerk) = (5.0, ceiling);
    let mut r = Rig::loaded_with(r, &segs[..3]);
    let (own, _) = r.node.drive.queue_ramps_ns();
    assert!(own > 200_000_000, "the drive's own ramp: {own} ns");
    r.start();
    for _ in 0..20_000 {
        r.tick();
        if r.node.state() == State::Fault {
            break;
        }
    }
    assert_eq!(r.node.fault(), FaultCode::Underrun);
    assert_eq!(r.node.scaling_phase(), Phase::Rest);
    std::eprintln!(
        "configured 50 ms, drive's own ramp {:.3} s, max jerk during the stop {:.3} m/s³ (ceiling {ceiling})",
        own as f64 * 1e-9,
        r.max_stop_jerk
    );
    assert!(r.max_stop_jerk > 0.0);
    assert!(
        r.max_stop_jerk <= ceiling * 1.001,
        "stop jerk {} > {ceiling}",
        r.max_stop_jerk
    );
}

/// A rig whose configured stop ramp (50 ms) is shorter than any segment's
/// own, jerk limit 5 m/s³ and ceiling 8 m/s³: the stops the dated-stop
/// tests time.
fn stop_rig() -> Rig {
    let mut r = Rig::with_stop_time(0.05);
    (r.cfg.max_jerk, r.cfg.ceiling_jerk) = (5.0, 8.0);
    r
}

/// The largest own controlled ramps (µs) of `segs` on a drive with
/// `cfg`: for every transition, and for a stop along the path from σ ≤ 1
/// (the largest over their pieces, in the 100 µs units the drive holds).
fn own_ramps_us(cfg: &DriveConfig, segs: &[WireSegment]) -> (u32, u32) {
    use crate::ceilings::Maxima;
    use crate::segment::Seg;
    segs.iter().fold((0, 0), |(full_us, unit_us), w| {
        let (full, units) = Maxima::of(&Seg::from_wire(w, 0))
            .ramps_and_units(cfg)
            .unwrap();
        let unit = units.largest[0] as u32 * 100;
        (full_us.max(full.0), unit_us.max(unit))
    })
}

/// The largest own controlled ramp (ns) of `segs` on a [`stop_rig`] for
/// a stop along the path from σ ≤ 1.
fn queue_ramp_ns(segs: &[WireSegment]) -> i64 {
    own_ramps_us(&stop_rig().cfg, segs).1 as i64 * 1000
}

/// A Stop dated with a ramp for the path ahead runs it when it covers the
/// own ramps of the segments the stop passes through, and the full ramp
/// when it does not (docs/protocol.md, "A ramp for the path ahead").
#[test]
fn a_dated_stop_ramp_is_run_only_when_it_covers_the_path_ahead() {
    // Two gentle segments, then two with the same jerk at 4× the speed.
    let segs = segments_of(&[0.4, 0.4, 0.8, 0.8]);
    let rig = stop_rig;
    let gentle = queue_ramp_ns(&segs[..2]);
    // The stop's length from Stop to Idle (ms) and its peak joint jerk.
    let stop_with = |dated_100us: u16| {
        let mut r = Rig::loaded_with(rig(), &segs);
        let full = r.node.drive.queue_ramps_ns().0;
        r.start();
        r.run(150);
        assert_eq!(r.node.state(), State::Running);
        let ms = r.dated_stop_ms(dated_100us);
        (ms, full, r.max_stop_jerk)
    };
    let covering = ((gentle + 99_999) / 100_000) as u16;
    let (ms, full, jerk) = stop_with(covering);
    std::eprintln!(
        "full ramp {:.3} s, the gentle segments' {:.3} s; a stop dated {covering} × 100 µs took {ms} ms, peak jerk {jerk:.3} m/s³",
        full as f64 * 1e-9,
        gentle as f64 * 1e-9
    );
    assert!(gentle * 10 < full * 6, "{gentle} against {full}");
    let dated_ms = covering as i64 / 10;
    assert!((ms - dated_ms).abs() <= 2, "{ms} ms against {dated_ms}");
    assert!(jerk <= 8.0, "{jerk}");
    // Too short for the segment it begins in, absent, or not shorter than
    // the full ramp: the full ramp.
    let full_ms = full / 1_000_000;
    for dated in [covering / 2, 0, (full / 100_000 + 1) as u16] {
        let (ms, _, _) = stop_with(dated);
        assert!(
            (ms - full_ms).abs() <= 2,
            "dated {dated}: {ms} ms against {full_ms}"
        );
    }
}

/// A Stop or FeedHold dated by the host but carrying no ramp (another
/// process's: `triquint stop`, `hold`, the web page) runs the ramp the
/// node vouches for at that instant, as a fault's stop does; on receipt
/// (not dated) it runs the full ramp.
#[test]
fn a_dated_stop_without_a_ramp_runs_the_one_the_node_vouches_for() {
    let segs = segments_of(&[0.4, 0.4, 0.8, 0.8]);
    let rig = stop_rig;
    let gentle = queue_ramp_ns(&segs[..2]);
    for c in [CommandCode::Stop, CommandCode::FeedHold] {
        let stop = |dated: bool| {
            let mut r = Rig::loaded_with(rig(), &segs);
            let full = r.node.drive.queue_ramps_ns().0;
            r.start();
            r.run(150);
            assert_eq!(r.node.state(), State::Running);
            // Dated a millisecond back, as `triquint stop` dates it.
            let arg = if dated { (r.t - 1_000) as u32 } else { 0 };
            let ms = r.stop_ms(c, arg, 0);
            (ms, full / 1_000_000, r.max_stop_jerk)
        };
        let (ms, full_ms, jerk) = stop(true);
        let gentle_ms = (gentle + 99_999) / 100_000 / 10;
        std::eprintln!(
            "{c:?} dated, no ramp: {ms} ms (the gentle segments' ramp {gentle_ms} ms, full {full_ms} ms), peak jerk {jerk:.3} m/s³"
        );
        assert!(
            gentle_ms * 10 < full_ms * 6,
            "{gentle_ms} against {full_ms}"
        );
        assert!((ms - gentle_ms).abs() <= 2, "{ms} ms against {gentle_ms}");
        // The rig measures the jerk of a stop (a hold stays Running).
        if c == CommandCode::Stop {
            assert!(jerk > 0.0 && jerk <= 8.0, "{jerk}");
        }
        let (ms, full_ms, _) = stop(false);
        assert!(
            (ms - full_ms).abs() <= 2,
            "on receipt: {ms} ms against {full_ms}"
        );
    }
    // A fast segment, then gentle ones. In the first gentle one, dated 1 ms
    // back: the ramps of the gentle pieces it passes. Dated 25 ms back,
    // into the fast one, which the node has dropped (its peers, ticking
    // elsewhere, may not have): that one's last piece's ramp all the same,
    // from that instant (25 ms of it behind), shorter than the fast
    // segment's own (its other pieces are behind the stop). Each is at
    // least the ramp of the piece it begins in and at most its segments'
    // largest.
    let segs = segments_of(&[0.8, 0.4, 0.4, 0.8]);
    let fast = queue_ramp_ns(&segs[..1]);
    let ms_of = |ns: i64| (ns + 99_999) / 100_000 / 10;
    let piece_ms = |w: &WireSegment, k: usize| {
        use crate::ceilings::Maxima;
        let (_, units) = Maxima::of(&crate::segment::Seg::from_wire(w, 0))
            .ramps_and_units(&rig().cfg)
            .unwrap();
        ms_of(units.pieces[k] as i64 * 100_000)
    };
    let cases = [
        (1_000, piece_ms(&segs[1], 0), ms_of(gentle)),
        (25_000, piece_ms(&segs[0], 3), ms_of(fast)),
    ];
    for (back_us, least_ms, most_ms) in cases {
        let mut r = Rig::loaded_with(rig(), &segs);
        r.start();
        r.run(830);
        let ms = r.stop_ms(CommandCode::Stop, (r.t - back_us) as u32, 0) + back_us as i64 / 1000;
        assert!(
            ms >= least_ms - 2 && ms <= most_ms + 2,
            "dated {back_us} µs back: {ms} ms of ramp, not within [{least_ms}, {most_ms}]"
        );
        if back_us == 25_000 {
            assert!(least_ms + 5 < most_ms, "{least_ms} against {most_ms}");
            assert!((ms - least_ms).abs() <= 2, "{ms} ms against {least_ms}");
        }
    }
    assert!(ms_of(gentle) * 10 < ms_of(fast) * 6);
    // Dated into a gentle segment before the last one dropped (a 5 ms
    // one): the full ramp (the fast segment's, queued later), though the
    // window reaches only gentle ones.
    let segs = segments_of(&[0.4, 0.005, 0.4, 0.8]);
    let mut r = Rig::loaded_with(rig(), &segs);
    let full_ms = r.node.drive.queue_ramps_ns().0 / 1_000_000;
    r.start();
    r.run(420);
    let ms = r.stop_ms(CommandCode::Stop, (r.t - 12_000) as u32, 0);
    assert!(
        (ms - (full_ms - 12)).abs() <= 2,
        "two segments back: {ms} ms against {}",
        full_ms - 12
    );
}

/// A piece whose stop along the path no ramp keeps within the
/// acceleration ceiling has no ramp of its own (`u16::MAX`): a stop that
/// passes it runs the full ramp, even one longer than the units reach
/// (6.5535 s), whether the node sizes the ramp or a stop carries that
/// value.
#[test]
fn a_piece_without_a_ramp_gets_the_full_one_however_long() {
    use crate::ceilings::Maxima;
    use crate::segment::Seg;
    let segs = segments_of(&[0.8; 4]);
    let rig = || {
        let mut r = Rig::with_stop_time(7.0);
        (r.cfg.max_jerk, r.cfg.ceiling_jerk) = (5.0, 8.0);
        // The ceiling at the plan's own peak acceleration: no room for a
        // stop along the path where it peaks.
        let peak = segs
            .iter()
            .map(|w| Maxima::of(&Seg::from_wire(w, 0)).a)
            .fold(0.0, f32::max);
        (r.cfg.max_acceleration, r.cfg.ceiling_acceleration) = (peak, peak);
        r
    };
    let (_, units) = Maxima::of(&Seg::from_wire(&segs[1], 0))
        .ramps_and_units(&rig().cfg)
        .unwrap();
    assert!(units.pieces.contains(&u16::MAX), "{units:?}");
    for dated_100us in [0, u16::MAX] {
        let mut r = Rig::loaded_with(rig(), &segs);
        // The configured ramp, above what the segments need.
        let full_ms = (r.cfg.stop_time * 1000.0) as i64;
        assert!(full_ms >= 7_000 && r.node.drive.queue_ramps_ns().0 < 1_000_000_000);
        r.start();
        r.run(150);
        let ms = r.stop_ms(CommandCode::Stop, (r.t - 1_000) as u32, dated_100us);
        assert!(
            ms >= full_ms - 3,
            "carried {dated_100us}: {ms} ms against {full_ms}"
        );
    }
}

/// With an override cap above 1, a dated stop from σ = 1 is held to the
/// segments' ramps for stops from σ ≤ 1, shorter than their ramps for
/// every transition up to the cap; from σ above 1 it runs the full ramp.
#[test]
fn a_dated_stop_is_held_to_the_ramps_of_stops_from_unit_sigma() {
    let segs = segments_of(&[0.4, 0.4, 0.8, 0.8]);
    let rig = || {
        let mut r = Rig::with_stop_time(0.05);
        (r.cfg.max_jerk, r.cfg.ceiling_jerk, r.cfg.override_cap) = (5.0, 8.0, 1.5);
        r
    };
    // The first two segments' own ramps: for every transition, for stops
    // from σ ≤ 1.
    let (cap_us, unit_us) = own_ramps_us(&rig().cfg, &segs[..2]);
    assert!(
        unit_us * 10 < cap_us * 9,
        "{unit_us} µs against {cap_us} µs"
    );
    let stop_with = |dated_100us: u16, override_permille: u16| {
        let mut r = Rig::loaded_with(rig(), &segs);
        let full = r.node.drive.queue_ramps_ns().0;
        r.start();
        r.run(50);
        if override_permille != 1000 {
            let a = r.command_with(CommandCode::Override, 0, override_permille, 0);
            assert_eq!(a.map(|a| a.0), Some(0));
        }
        // Past the override's ramp, still in the second segment.
        r.run(600);
        assert_eq!(r.node.state(), State::Running);
        assert!(!r.node.drive.scaling().in_transition());
        let ms = r.dated_stop_ms(dated_100us);
        (ms, full / 1_000_000, r.max_stop_jerk)
    };
    let unit = unit_us.div_ceil(100) as u16;
    let (ms, full_ms, jerk) = stop_with(unit, 1000);
    std::eprintln!(
        "ramps of the first segments: {cap_us} µs up to the cap, {unit_us} µs from σ ≤ 1; a stop dated {unit} × 100 µs took {ms} ms, peak jerk {jerk:.3} m/s³"
    );
    assert!((ms - unit as i64 / 10).abs() <= 2, "{ms} ms against {unit}");
    assert!(jerk <= 8.0, "{jerk}");
    // Shorter than that, or at σ = 1.05: the full ramp (at σ = 1.05 it
    // lasts T·1.05).
    let (ms, _, _) = stop_with(unit - 5, 1000);
    assert!((ms - full_ms).abs() <= 2, "{ms} ms against {full_ms}");
    let (ms, _, _) = stop_with(unit, 1050);
    assert!(
        (ms - full_ms * 105 / 100).abs() <= 2,
        "{ms} ms against {full_ms}·1.05"
    );
}

#[test]
fn commanded_stop_feed_hold_resume_and_emergencies() {
    let segs = segments(4, 0.3);
    // Stop → Stopping → Idle, queue flushed.
    let mut r = Rig::loaded(&segs);
    r.start();
    r.run(200);
    assert_eq!(r.node.state(), State::Running);
    assert_eq!(r.command(CommandCode::Stop, 0), 0);
    assert_eq!(r.node.state(), State::Stopping);
    r.run(450);
    assert_eq!(r.node.state(), State::Idle);
    assert_eq!(r.node.queue_depth(), 0);
    assert_eq!(r.node.fault(), FaultCode::None);
    // Feed hold then resume: completes.
    let mut r = Rig::loaded(&segs);
    r.start();
    r.run(200);
    assert_eq!(r.command(CommandCode::FeedHold, 0), 0);
    r.run(450);
    assert_eq!(r.node.scaling_phase(), Phase::Rest);
    assert_eq!(r.node.state(), State::Running);
    let held = r.node.stats.reference.q;
    r.run(300);
    assert_eq!(r.node.stats.reference.q, held);
    assert_eq!(r.command(CommandCode::Resume, 0), 0);
    r.run(1500);
    assert_eq!(r.node.state(), State::Idle);
    assert_eq!(r.node.fault(), FaultCode::None);
    // A peer's emergency while running: stop along the path, then Fault.
    let mut r = Rig::loaded(&segs);
    r.start();
    r.run(200);
    r.rx(Emergency {
        code: FaultCode::FollowingError as u8,
        state: State::Stopping as u8,
        ramp_100us: 0,
        plan_time_us: 0,
    }
    .to_frame(3));
    assert_eq!(r.node.state(), State::Stopping);
    r.run(450);
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.node.fault(), FaultCode::PeerEmergency);
}

#[test]
fn following_error_and_lost_sync_stop_with_their_codes() {
    let segs = segments(4, 0.3);
    let mut r = Rig::loaded(&segs);
    r.start();
    r.run(100);
    r.offset = 2e-3;
    r.run(2);
    assert_eq!(r.node.state(), State::Stopping);
    assert_eq!(r.node.fault(), FaultCode::FollowingError);
    r.run(500);
    assert_eq!(r.node.state(), State::Fault);

    let mut r = Rig::loaded(&segs);
    r.start();
    r.run(100);
    r.syncing = false;
    r.run(600);
    assert!(matches!(r.node.state(), State::Stopping | State::Fault));
    assert_eq!(r.node.fault(), FaultCode::LostSync);
}

/// Axis 1 (this node) over segment `s`: (start, end) position.
fn own_span(s: &WireSegment) -> (f32, f32) {
    let seg = crate::segment::Seg::from_wire(s, 0);
    (seg.start_q()[1], seg.end_q()[1])
}

#[test]
fn a_segment_beyond_the_soft_limits_is_rejected_never_queued() {
    let segs = segments(3, 0.3);
    let (a, b) = own_span(&segs[0]);
    let mut r = Rig::new();
    // The first segment fits exactly; the second moves on beyond.
    r.cfg.soft_limit_min = a.min(b) - 1e-6;
    r.cfg.soft_limit_max = a.max(b) + 1e-6;
    r.parked = a;
    r.configure();
    r.run(50);
    assert_eq!(
        r.send_segment(&segs[0]).map(|a| a.0),
        Some(Reject::Accepted)
    );
    assert_eq!(
        r.send_segment(&segs[1]).map(|a| a.0),
        Some(Reject::OutsideSoftLimits)
    );
    assert_eq!(r.node.queue_depth(), 1);
    assert_eq!(r.node.next_seq(), 1, "the rejected segment took no place");
    assert_eq!(
        r.node.stats.reason_counts[Reject::OutsideSoftLimits as usize],
        1
    );
}

#[test]
fn a_segment_above_a_configured_limit_by_its_exact_maxima_is_rejected() {
    use triquint_shared::protocol::contract::RELATIVE_LIMIT_MARGIN;
    let segs = segments(3, 0.3);
    let m = crate::ceilings::Maxima::of(&crate::segment::Seg::from_wire(&segs[0], 0));
    let k = 1.0 + RELATIVE_LIMIT_MARGIN;
    type Limit = fn(&mut DriveConfig) -> &mut f32;
    let limits: [(Limit, f32); 3] = [
        (|c| &mut c.max_velocity, m.v),
        (|c| &mut c.max_acceleration, m.a),
        (|c| &mut c.max_jerk, m.j),
    ];
    for (limit, peak) in limits {
        for (scale, want) in [(1.0001, Reject::Accepted), (0.99999, Reject::Invalid)] {
            let mut r = Rig::new();
            *limit(&mut r.cfg) = peak / k * scale;
            r.configure();
            r.run(50);
            assert_eq!(
                r.send_segment(&segs[0]).map(|a| a.0),
                Some(want),
                "peak {peak} at {scale} of the limit with its margin"
            );
            assert_eq!(r.node.queue_depth(), (want == Reject::Accepted) as usize);
        }
    }
}

#[test]
fn a_measured_position_beyond_the_soft_limits_stops_with_its_code() {
    let segs = segments(4, 0.3);
    let (a, b) = own_span(&segs[0]);
    let dir = (b - a).signum();
    let mut r = Rig::new();
    // The limit 0.5 mm behind the plan's start: the plan stays inside.
    if dir > 0.0 {
        r.cfg.soft_limit_min = a - 0.5e-3;
    } else {
        r.cfg.soft_limit_max = a + 0.5e-3;
    }
    let mut r = Rig::loaded_with(r, &segs);
    r.start();
    r.run(15);
    assert_eq!(r.node.state(), State::Running);
    // The axis drops 0.9 mm behind the reference (within the following
    // error bound): past the soft limit.
    r.offset = -0.9e-3 * dir;
    r.run(2);
    assert_eq!(r.node.state(), State::Stopping);
    assert_eq!(r.node.fault(), FaultCode::SoftLimit);
    assert!(r.emergencies().contains(&(FaultCode::SoftLimit as u8)));
    r.run(600);
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.node.fault(), FaultCode::SoftLimit);
    assert!(
        r.max_stop_jerk <= r.cfg.max_jerk * 1.5,
        "{}",
        r.max_stop_jerk
    );
}

/// A receive side that keeps finding the inbox full of
/// segments must still get Stop through, and the tick must run it.
#[test]
fn a_stop_behind_a_flood_of_segments_is_queued_and_runs() {
    use crate::inbox::{INBOX_SLOTS, Inbox, Item, RESERVED_SLOTS, offer};
    let segs = segments(16, 0.3);
    let mut r = Rig::loaded(&segs);
    r.start();
    r.run(20);
    assert_eq!(r.node.state(), State::Running);
    // The receive side runs apart from the tick, as on a board: every
    // finished item is offered to the inbox, which the tick does not drain.
    let mut inbox = Inbox::new();
    let (mut queued, mut refused) = (0, 0);
    for s in &segs[CAP..] {
        for f in s.frames(false) {
            if let Some(item) = r.receive(f) {
                assert!(matches!(item, Item::Segment(_)));
                match offer(&mut inbox, item) {
                    Ok(()) => queued += 1,
                    Err(_) => refused += 1,
                }
            }
        }
    }
    assert_eq!(queued, INBOX_SLOTS - 1 - RESERVED_SLOTS);
    assert!(refused > 0, "the flood did not fill the inbox");
    let stop = Command {
        command: CommandCode::Stop as u8,
        token: 77,
        arg: 0,
        arg2: 0,
    };
    let item = r.receive(stop.to_frame(2)).unwrap();
    assert!(item.is_urgent());
    assert!(
        offer(&mut inbox, item).is_ok(),
        "Stop refused behind segments"
    );
    // An Emergency and a ClearFault fit too; a further segment does not.
    let emergency = Item::Emergency {
        code: FaultCode::HostEmergency,
        node: 0,
        t_ns: 0,
        ramp_100us: 0,
        ready: None,
    };
    assert!(emergency.is_urgent());
    assert!(!inbox.is_full());
    // The tick takes its share each tick: the Stop runs within a few ticks.
    let mut m = Motor(0.0, false);
    for _ in 0..INBOX_SLOTS {
        r.node.drive.take_from(&mut inbox);
        let q = r.node.stats.reference.q[1];
        let counts = (q as f64 * r.cfg.counts_per_metre as f64).round() as i64;
        r.node.drive.tick(r.t, &mut Enc(counts), &mut m);
        r.t += TICK;
        while let Some(f) = r.node.pop_tx() {
            r.sent.push(f);
        }
    }
    assert!(inbox.is_empty());
    assert_eq!(r.node.state(), State::Stopping);
    let acked = r.sent.iter().any(
        |f| matches!(decode(f), Ok((Msg::CommandAck(a), 2)) if a.token == 77 && a.result == 0),
    );
    assert!(acked, "the Stop was not answered");
    r.run(1000);
    assert_eq!(r.node.state(), State::Idle);
}

#[test]
fn only_stop_quick_stop_clear_fault_and_emergency_are_urgent() {
    use crate::inbox::{CommandData, Item};
    let cmd = |c: CommandCode| Item::Command {
        command: Command {
            command: c as u8,
            token: 1,
            arg: 0,
            arg2: 0,
        },
        rx_us: 0,
        data: CommandData::None,
    };
    for c in [
        CommandCode::Stop,
        CommandCode::QuickStop,
        CommandCode::ClearFault,
    ] {
        assert!(cmd(c).is_urgent(), "{c:?}");
    }
    for c in [CommandCode::Arm, CommandCode::Start, CommandCode::Reset] {
        assert!(!cmd(c).is_urgent(), "{c:?}");
    }
    assert!(!Item::PartIgnored(Reject::Duplicate).is_urgent());
}

/// A resume, hold, override, stop or peer emergency in the middle of a
/// transition is sized by the receive side (the sampled search is over the
/// tick's budget); the drive takes that result, which is exactly what it
/// would have computed itself, and only when it was computed from its own
/// state: a stale one is computed again.
#[test]
fn mid_transition_changes_are_sized_by_the_receive_side() {
    use crate::inbox::{CommandData, Item};
    use crate::scaling::{Retarget, TimeScaling};
    let segs = segments(4, 0.3);
    let mut r = Rig::loaded(&segs);
    r.start();
    r.run(200);
    assert_eq!(r.command(CommandCode::FeedHold, 0), 0);
    // 100 ms into the 400 ms hold ramp.
    r.run(100);
    let cmd = |c: CommandCode, arg2: u16| Command {
        command: c as u8,
        token: 200 + c as u8,
        arg: 0,
        arg2,
    };
    let cases = [
        (cmd(CommandCode::Resume, 0), true),
        (cmd(CommandCode::Override, 500), false),
        (cmd(CommandCode::Stop, 0), false),
        (cmd(CommandCode::QuickStop, 0), false),
    ];
    for (c, resume_first) in cases {
        let mut r2 = Rig::loaded(&segs);
        r2.start();
        r2.run(200);
        assert_eq!(r2.command(CommandCode::FeedHold, 0), 0);
        r2.run(100);
        if !resume_first {
            // From the middle of the resume ramp instead.
            r2.run(400);
            assert_eq!(r2.command(CommandCode::Resume, 0), 0);
            r2.run(100);
        }
        let before = r2.node.drive.scaling();
        assert!(before.in_transition(), "{c:?}");
        let item = r2.receive(c.to_frame(0)).unwrap();
        let Item::Command {
            data: CommandData::Scaling(p),
            rx_us,
            ..
        } = item
        else {
            panic!("{c:?}: not sized by the receive side: {item:?}");
        };
        assert_eq!(p.from, before, "{c:?}");
        let mut own = before;
        own.retarget(p.t_ns, p.target_q16, p.full_ns);
        assert_eq!(p.to, own, "{c:?}: not what the tick computes");
        assert_ne!(p.to, before, "{c:?}: no change");
        // The drive takes it (a marked copy, to see it is the one taken).
        let mut marked = p;
        marked.to.s0_ns += 1;
        let mut d = r2.node.drive.clone();
        d.take(&Item::Command {
            command: c,
            rx_us,
            data: CommandData::Scaling(marked),
        });
        assert_eq!(
            d.scaling(),
            marked.to,
            "{c:?}: the prepared change not taken"
        );
        // Stale (the drive's state moved on): computed again, the same.
        let mut stale = marked;
        stale.from.t0_ns -= 1;
        let mut d = r2.node.drive.clone();
        d.take(&Item::Command {
            command: c,
            rx_us,
            data: CommandData::Scaling(stale),
        });
        assert_eq!(d.scaling(), own, "{c:?}: a stale preparation taken");
        assert_ne!(d.scaling(), marked.to);
    }
    // A peer's emergency in a resume ramp: the stop is prepared as well.
    r.run(400);
    assert_eq!(r.command(CommandCode::Resume, 0), 0);
    r.run(100);
    let before = r.node.drive.scaling();
    let peer = Emergency {
        code: FaultCode::FollowingError as u8,
        state: State::Stopping as u8,
        ramp_100us: 0,
        plan_time_us: 0,
    };
    let item = r.receive(peer.to_frame(3)).unwrap();
    let Item::Emergency { ready: Some(p), .. } = item else {
        panic!("emergency not sized: {item:?}");
    };
    assert_eq!(p.from, before);
    assert_eq!(
        Retarget::prepare(&TimeScaling::nominal(0, 0), 0, 0, 1),
        None
    );
    r.node.drive.take(&item);
    assert_eq!(r.node.state(), State::Stopping);
    assert_ne!(p.to, before);
    assert_eq!(r.node.drive.scaling(), p.to);
}

/// The loop is closed in every powered state: an axis pushed 2 mm off its
/// hold position (beyond `following_error_max`) at rest, Idle, Loaded or
/// Armed, ends in Fault with FollowingError and its Emergency, holding.
#[test]
fn a_following_error_at_rest_faults_in_every_powered_state() {
    let segs = segments(4, 0.3);
    for state in [State::Idle, State::Loaded, State::Armed] {
        let mut r = match state {
            State::Idle => {
                let mut r = Rig::new();
                r.parked = 0.3;
                r.configure();
                r
            }
            _ => Rig::loaded(&segs),
        };
        if state == State::Armed {
            assert_eq!(r.command(CommandCode::Arm, 0), 0);
        }
        assert_eq!(r.node.state(), state);
        r.run(50);
        assert_eq!(r.node.state(), state, "quiet at rest");
        assert!(r.emergencies().is_empty());
        r.offset = 2.0 * r.cfg.following_error_max;
        r.run(1);
        assert_eq!(r.node.state(), State::Fault, "{state:?}");
        assert_eq!(r.node.fault(), FaultCode::FollowingError);
        assert_eq!(r.emergencies(), [FaultCode::FollowingError as u8]);
    }
}

/// A following error while a commanded stop slows down: the stop goes on
/// along the path and ends in Fault with FollowingError, not in Idle.
#[test]
fn a_following_error_while_stopping_ends_in_fault() {
    let segs = segments(4, 0.3);
    let mut r = Rig::loaded(&segs);
    r.start();
    r.run(200);
    assert_eq!(r.command(CommandCode::Stop, 0), 0);
    r.run(20);
    assert_eq!(r.node.state(), State::Stopping);
    r.offset = 2.0 * r.cfg.following_error_max;
    r.run(1);
    assert_eq!(r.node.state(), State::Stopping);
    assert_eq!(r.node.fault(), FaultCode::FollowingError);
    assert!(r.emergencies().contains(&(FaultCode::FollowingError as u8)));
    r.run(500);
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.node.fault(), FaultCode::FollowingError);
}

/// Travel once homed, at rest: the measured position leaving the soft
/// limits (within the following-error bound) while the axis holds inside
/// them ends in Fault with SoftLimit; an axis that stands beyond a limit
/// because it was powered on there is not faulted for standing still.
#[test]
fn the_travel_is_supervised_at_rest() {
    let segs = segments(4, 0.3);
    let (a, b) = own_span(&segs[0]);
    let dir = (b - a).signum();
    let mut r = Rig::new();
    if dir > 0.0 {
        r.cfg.soft_limit_min = a - 0.5e-3;
    } else {
        r.cfg.soft_limit_max = a + 0.5e-3;
    }
    let mut r = Rig::loaded_with(r, &segs);
    assert!(r.node.is_homed());
    r.offset = -0.9e-3 * dir;
    assert!(0.9e-3 < r.cfg.following_error_max);
    r.run(1);
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.node.fault(), FaultCode::SoftLimit);
    assert_eq!(r.emergencies(), [FaultCode::SoftLimit as u8]);

    // Parked beyond the limit from the start: no fault at rest.
    let mut r = Rig::new();
    if dir > 0.0 {
        r.cfg.soft_limit_min = a + 0.5e-3;
    } else {
        r.cfg.soft_limit_max = a - 0.5e-3;
    }
    r.parked = a;
    r.configure();
    r.run(100);
    assert_eq!(r.node.state(), State::Idle);
    assert!(r.emergencies().is_empty());
}
