//! Golden vectors for the on-target test (`firmware/boards/qemu-mps2-an386`):
//! the host runs the firmware core on recorded inputs and stores every f32
//! result bit for bit in `testdata/firmware/golden.bin`; the Cortex-M4F image
//! replays the same inputs and must reproduce the same bits. The f64 side
//! (within 1 µm of the plan) is checked here, on the host.
//!
//! `TRIQUINT_BLESS=1 cargo test -p triquint-firmware --test golden` rewrites the file;
//! otherwise the test fails when the stored vectors are stale.
//!
//! Record format (little endian; one tag byte per record), read by the
//! image's `golden.rs`:
//! - `M` 18 × f32: `Model<f32>` (rho_u[0..3] xyz, l, l2, platform, strut,
//!   slider masses, rotor inertia, ratio, inv_ratio, gravity)
//! - `S` seq u16, flags u16, duration_us u32, start_ns i64, 18 × i64: a segment
//! - `E` s_ns i64, σ, σ̇, σ̈ f32 → 12 × f32 (q, q̇, q̈, q⃛ after scaling),
//!   ok u8, 3 × f32 torque: evaluation of the last segment
//! - `N` node id u8: a fresh node (receive side, inbox and drive)
//! - `F` timestamp_us u32, id u16, len u8, fd u8, payload: a frame through
//!   the receive side into the inbox, as the board's CAN task does (it
//!   transmits nothing)
//! - `T` now_us u32, counts i32 → torque f32, enabled | state << 1 u8,
//!   tx count u8, tx hash u32 (only when the count is not 0): a tick as the
//!   board runs it, items taken from the inbox first
//! - `Z` end

use std::path::PathBuf;

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_firmware::inbox::Inbox;
use triquint_firmware::scaling::Phase;
use triquint_firmware::{Drive, Encoder, MotorOutput, QUEUE_CAPACITY, Receiver, RxFrame};
use triquint_shared::dynamics;
use triquint_shared::plan::{Plan, Segment};
use triquint_shared::protocol::compact::Chain;
use triquint_shared::protocol::config::{DriveConfig, DriveSettings};
use triquint_shared::protocol::{
    Command, CommandCode, FaultCode, Frame, Msg, State, TimeSync, WireSegment, config_write_frame,
    decode,
};
use triquint_shared::quintic::JointMotion;
use triquint_shared::{Limits, Model, Robot};

use triquint_firmware::segment::{Seg, scale};

const PLANS: [&str; 3] = ["case1-spline", "case2-spline", "spiral-spline"];
/// The drive under test: node 2, axis 1.
const NODE: u8 = 2;
/// Control period (µs): 10 kHz, the rate of the real board.
const TICK_US: u64 = 100;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

fn load_plan(name: &str) -> Plan {
    let p = root().join(format!("testdata/protocol/plans/{name}.json"));
    let text = std::fs::read_to_string(&p).unwrap_or_else(|e| panic!("{}: {e}", p.display()));
    serde_json::from_str(&text).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

fn wire_segments(plan: &Plan) -> Vec<WireSegment> {
    plan.wire_segments()
        .unwrap_or_else(|e| panic!("plan {e} on the wire"))
}

/// FNV-1a over the frames a node queued for transmission.
fn tx_hash(frames: &[Frame]) -> u32 {
    let mut h: u32 = 0x811C_9DC5;
    let mut eat = |b: u8| {
        h ^= b as u32;
        h = h.wrapping_mul(0x0100_0193);
    };
    for f in frames {
        for b in f.id.to_le_bytes() {
            eat(b);
        }
        eat(f.len);
        eat(f.fd as u8);
        for &b in f.payload() {
            eat(b);
        }
    }
    h
}

#[derive(Default)]
struct Out(Vec<u8>);
impl Out {
    fn u8(&mut self, x: u8) {
        self.0.push(x);
    }
    fn u16(&mut self, x: u16) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn u32(&mut self, x: u32) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn u64(&mut self, x: u64) {
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn f32(&mut self, x: f32) {
        self.u32(x.to_bits());
    }
    fn v3(&mut self, v: &Vector3<f32>) {
        for k in 0..3 {
            self.f32(v[k]);
        }
    }
    fn motion(&mut self, m: &JointMotion<f32>) {
        for v in [&m.q, &m.qd, &m.qdd, &m.qddd] {
            self.v3(v);
        }
    }
}

fn model_record(out: &mut Out, m: &Model<f32>) {
    out.u8(b'M');
    for r in &m.rho_u {
        out.v3(r);
    }
    for x in [
        m.l,
        m.l2,
        m.platform_mass,
        m.strut_mass,
        m.slider_mass,
        m.rotor_inertia,
        m.ratio,
        m.inv_ratio,
        m.gravity,
    ] {
        out.f32(x);
    }
}

/// Golden plans: every segment of the three test plans, sampled and scaled,
/// with the feedforward. Returns the worst f32-vs-f64 position error (m).
fn golden_plans(out: &mut Out) -> f64 {
    let m32 = Robot::default().model::<f32>();
    model_record(out, &m32);
    let mut worst: f64 = 0.0;
    // Time-scalings: nominal, and a few ramp states (σ, σ̇, σ̈).
    let scalings = [
        (1.0f32, 0.0f32, 0.0f32),
        (0.5, -3.75, 0.0),
        (0.1, 1.2, -20.0),
    ];
    for name in PLANS {
        let plan = load_plan(name);
        assert!(
            plan.robot == Robot::default(),
            "{name}: golden plans assume the default robot"
        );
        let mut start = 0i64;
        for (w, seg64) in wire_segments(&plan).iter().zip(&plan.segments) {
            let seg = Seg::from_wire(w, start);
            out.u8(b'S');
            out.u16(w.seq);
            out.u16(w.flags);
            out.u32(w.duration_us);
            out.u64(start as u64);
            for row in &w.coeffs {
                for &c in row {
                    out.u64(c as u64);
                }
            }
            let q64 = seg64.quintic();
            for i in 0..=16i64 {
                // Include points just outside the segment (clamped).
                let d = (seg.duration_ns() * i) / 16 + if i == 16 { 1000 } else { 0 };
                let s_ns = start + d - if i == 0 { 1000 } else { 0 };
                let (sg, sd, sdd) = scalings[i as usize % scalings.len()];
                let m = scale(&seg.eval(s_ns), sg, sd, sdd);
                out.u8(b'E');
                out.u64(s_ns as u64);
                for x in [sg, sd, sdd] {
                    out.f32(x);
                }
                out.motion(&m);
                match dynamics::torque(&m32, &m.q, &m.qd, &m.qdd) {
                    Ok(t) => {
                        out.u8(1);
                        out.v3(&t);
                    }
                    Err(_) => {
                        out.u8(0);
                        out.v3(&Vector3::zeros());
                    }
                }
                // f64 side: the drive's f32 position against the plan.
                let t_s = (s_ns - start).clamp(0, seg.duration_ns()) as f64 * 1e-9;
                let p = q64.eval(t_s);
                for j in 0..3 {
                    worst = worst.max((p.q[j] - m.q[j] as f64).abs());
                }
            }
            start += seg.duration_ns();
        }
    }
    worst
}

struct Enc(i64);
impl Encoder for Enc {
    fn read_counts(&mut self) -> i64 {
        self.0
    }
}
#[derive(Default)]
struct Motor {
    torque: f32,
    enabled: bool,
}
impl MotorOutput for Motor {
    fn set_torque(&mut self, t: f32) {
        self.torque = t;
    }
    fn enable(&mut self, on: bool) {
        self.enabled = on;
    }
}

/// Replays inputs into one node and records its outputs.
struct Recorder {
    node: Drive,
    receiver: Receiver,
    inbox: Inbox,
    motor: Motor,
    out: Out,
    now: u64,
    sync_seq: u8,
    next_sync: u64,
    /// Token of the last command (each command its own: a repeat of the
    /// last one within the repeat window is answered, not executed).
    token: u8,
    /// Seeded encoder noise.
    noise: ChaCha8Rng,
    cpm: f64,
    ticks: u64,
    /// States visited, in order.
    states: Vec<State>,
    /// Segments as the host sends them: compact after the first.
    chain: Chain,
    /// Segments sent compact.
    compact: usize,
    /// The ramps its Emergency frames carried (100 µs units).
    emergency_ramps: Vec<u16>,
}

impl Recorder {
    fn drain(&mut self) -> (u8, u32) {
        let mut sent = Vec::new();
        while let Some(f) = self.node.pop_tx() {
            if let Ok((Msg::Emergency(e), _)) = decode(&f) {
                self.emergency_ramps.push(e.ramp_100us);
            }
            sent.push(f);
        }
        (sent.len() as u8, tx_hash(&sent))
    }

    fn rx(&mut self, f: Frame) {
        let rx = RxFrame {
            frame: f,
            timestamp_us: self.now,
        };
        if let Some(item) = self.receiver.on_frame(&rx, self.node.snapshot()) {
            // A full inbox drops the item, as on the board.
            let _ = self.inbox.enqueue(item);
        }
        let o = &mut self.out;
        o.u8(b'F');
        o.u32(self.now as u32);
        o.u16(f.id);
        o.u8(f.len);
        o.u8(f.fd as u8);
        o.0.extend_from_slice(f.payload());
    }

    fn command(&mut self, c: CommandCode, arg: u32) {
        self.command2(c, arg, 0);
    }

    fn command2(&mut self, c: CommandCode, arg: u32, arg2: u16) {
        self.token = self.token.wrapping_add(1);
        self.rx(Command {
            command: c as u8,
            token: self.token,
            arg,
            arg2,
        }
        .to_frame(0));
    }

    fn tick(&mut self) {
        // Host time = local time + 3 s; syncs every 20 ms.
        if self.now >= self.next_sync {
            self.sync_seq = self.sync_seq.wrapping_add(1);
            let prev = (self.next_sync + 3_000_000).saturating_sub(20_000) as u32;
            self.rx(TimeSync {
                seq: self.sync_seq,
                prev_tx_us: prev,
            }
            .to_frame(0));
            self.next_sync = self.now + 20_000;
        }
        // The axis follows last tick's reference, with ±3 counts of noise.
        let jitter: i64 = self.noise.random_range(-3..=3);
        let q = self.node.stats.reference.q[1] as f64;
        let counts = (q * self.cpm).round() as i64 + jitter;
        self.node.take_from(&mut self.inbox);
        self.node.tick(self.now, &mut Enc(counts), &mut self.motor);
        let (n, h) = self.drain();
        let o = &mut self.out;
        o.u8(b'T');
        o.u32(self.now as u32);
        o.u32(counts as i32 as u32);
        o.f32(self.motor.torque);
        o.u8(self.motor.enabled as u8 | (self.node.state() as u8) << 1);
        o.u8(n);
        if n > 0 {
            o.u32(h);
        }
        self.now += TICK_US;
        self.ticks += 1;
        if self.states.last() != Some(&self.node.state()) {
            self.states.push(self.node.state());
        }
    }

    /// Hands segment `next` over when the queue runs low or when the next
    /// tick switches segments (its front ends within one tick).
    fn top_up(&mut self, segs: &[WireSegment], next: &mut usize) {
        let switch = self.node.executing().is_some_and(|(seq, _)| {
            let end: i64 = segs[..=seq as usize]
                .iter()
                .map(|w| w.duration_us as i64 * 1000)
                .sum();
            self.node.plan_ns() + (TICK_US * 1000) as i64 >= end
        });
        let room = self.node.queue_depth() < QUEUE_CAPACITY;
        if (self.node.queue_depth() < 3 || switch && room) && *next < segs.len() {
            let out = self.chain.next(&segs[*next], segs.get(*next + 1));
            self.compact += out.is_compact() as usize;
            for f in out.frames(true) {
                self.rx(f);
            }
            *next += 1;
        }
    }

    /// Parks the axis at `start`'s first pose, unconfigured (motor off),
    /// for `idle_us`, then writes and commits `cfg`.
    fn park_and_configure(&mut self, start: &WireSegment, cfg: &DriveConfig, idle_us: u64) {
        self.node.stats.reference.q = Seg::from_wire(start, 0).start_q();
        self.run_us(idle_us);
        for (k, v) in cfg.to_values().iter().enumerate() {
            self.rx(config_write_frame(NODE, k as u8, *v));
        }
        self.command(CommandCode::ConfigCommit, cfg.crc());
        self.tick();
        assert_eq!(self.node.config_crc(), cfg.crc(), "configuration committed");
    }

    fn run_us(&mut self, us: u64) {
        for _ in 0..us / TICK_US {
            self.tick();
        }
    }
}

/// Golden frames: node 2 configured over CAN at 10 kHz, the first part of
/// Case I uploaded (classic frames before the start, CAN-FD while running),
/// armed, started, held, resumed, held, resumed and overridden in the
/// middle of ramps, and stopped in one. Returns the states visited.
fn golden_frames(out: Out) -> (Out, Vec<State>, u64) {
    let plan = load_plan("case1-spline");
    let settings = DriveSettings {
        control_rate: 1e6 / TICK_US as f64,
        ..DriveSettings::default()
    };
    let cfg = DriveConfig::new(&plan.robot, &Limits::default(), 1, &settings, 0.2, 0.1);
    let mut r = Recorder {
        node: Drive::new(NODE),
        receiver: Receiver::new(NODE),
        inbox: Inbox::new(),
        motor: Motor::default(),
        out,
        now: 1_000_000,
        sync_seq: 0,
        next_sync: 1_000_000,
        token: 0,
        noise: ChaCha8Rng::seed_from_u64(12345),
        cpm: cfg.counts_per_metre as f64,
        ticks: 0,
        states: Vec::new(),
        chain: Chain::default(),
        compact: 0,
        emergency_ramps: Vec::new(),
    };
    r.out.u8(b'N');
    r.out.u8(NODE);
    let segs = wire_segments(&plan);
    r.park_and_configure(&segs[0], &cfg, 60_000);
    r.run_us(20_000);
    let mut next = 0;
    for (i, w) in segs.iter().enumerate().take(3) {
        let out = r.chain.next(w, segs.get(i + 1));
        r.compact += out.is_compact() as usize;
        for f in out.frames(false) {
            r.rx(f);
        }
        next += 1;
    }
    r.run_us(5_000);
    r.command(CommandCode::Arm, 0);
    let host_now = (r.now + 3_000_000) as u32;
    r.command(CommandCode::Start, host_now + 20_000);
    // Run 1.1 s (two segment switches), topping the queue up over CAN-FD
    // right before ticks; at every segment switch the tick also takes a
    // new segment (the worst case of the hand-off).
    for _ in 0..11_000 {
        r.top_up(&segs, &mut next);
        r.tick();
    }
    // A hold dated with a ramp for the path ahead (the tick scans the
    // queue for it): 150 ms, covering these gentle segments.
    r.command2(CommandCode::FeedHold, 0, 1_500);
    r.run_us(250_000);
    // Commands in the middle of a transition (200 ms ramps): a hold at 20 %
    // of the resume ramp, a resume at 30 % of that hold's ramp, an override
    // to 50 % in that resume ramp, back to 100 % and a stop in that change.
    let run = |r: &mut Recorder, next: &mut usize, us: u64| {
        for _ in 0..us / TICK_US {
            r.top_up(&segs, next);
            r.tick();
        }
    };
    r.command(CommandCode::Resume, 0);
    run(&mut r, &mut next, 40_000);
    assert!(r.node.scaling().in_transition(), "not mid-transition");
    r.command(CommandCode::FeedHold, 0);
    run(&mut r, &mut next, 60_000);
    assert!(r.node.scaling().in_transition(), "not mid-transition");
    r.command(CommandCode::Resume, 0);
    run(&mut r, &mut next, 100_000);
    assert!(r.node.scaling().in_transition(), "not mid-transition");
    r.command2(CommandCode::Override, 0, 500);
    run(&mut r, &mut next, 400_000);
    r.command2(CommandCode::Override, 0, 1000);
    run(&mut r, &mut next, 50_000);
    assert!(r.node.scaling().in_transition(), "not mid-transition");
    r.command(CommandCode::FeedHold, 0);
    run(&mut r, &mut next, 50_000);
    assert!(r.node.scaling().in_transition(), "not mid-transition");
    r.command(CommandCode::Resume, 0);
    run(&mut r, &mut next, 300_000);
    assert!(!r.node.scaling().in_transition(), "still in a transition");
    // A hold dated a millisecond back carrying no ramp, as another process
    // sends it: the tick sizes the ramp from its queue (here the own ramp
    // of the segment it begins in, as long as the full one).
    let host_us = (r.now + 3_000_000 - 1_000) as u32;
    r.command(CommandCode::FeedHold, host_us);
    let mut held_us = 0;
    while r.node.scaling_phase() != Phase::Rest && held_us < 1_000_000 {
        run(&mut r, &mut next, TICK_US);
        held_us += TICK_US;
    }
    eprintln!("golden frames: a dated hold without a ramp at rest in {held_us} µs");
    r.command(CommandCode::Resume, 0);
    // The host goes silent at σ = 1: the node faults with Underrun, its
    // tick scans the queue for the ramp it vouches for (Emergency
    // `ramp_100us`), and it comes to rest in Fault.
    assert!(next < segs.len(), "the plan's end was sent");
    r.run_us(1_500_000);
    assert_eq!(r.node.state(), State::Fault, "no underrun");
    assert_eq!(r.node.fault(), FaultCode::Underrun);
    assert!(
        matches!(r.emergency_ramps[..], [x] if x > 0),
        "the ramp it vouched for: {:?}",
        r.emergency_ramps
    );
    // Every segment after the first went compact, and the node took them all.
    assert_eq!(r.compact + 1, next, "segments sent compact");
    assert_eq!(r.node.stats.rejects, 0, "segments or parts rejected");
    short_queue(&mut r, &plan);
    r.out.u8(b'Z');
    let ticks = r.ticks;
    (r.out, r.states, ticks)
}

/// `plan`'s segments cut into pieces of at most `h` (s), exactly (each
/// piece the same quintic from its own start), up to `until` (s).
fn cut(plan: &Plan, h: f64, until: f64) -> Plan {
    let shifted = |c: &[f64; 6], t0: f64| {
        let mut out = [0.0f64; 6];
        for (k, o) in out.iter_mut().enumerate() {
            let mut binom = 1.0;
            for (m, cm) in c.iter().enumerate().skip(k) {
                *o += cm * binom * t0.powi((m - k) as i32);
                binom = binom * (m + 1) as f64 / (m + 1 - k) as f64;
            }
        }
        out
    };
    let mut p = plan.clone();
    p.segments.clear();
    for q in &plan.segments {
        if q.t0_s >= until {
            break;
        }
        // Whole microseconds, as the wire carries them.
        let us = (q.duration_s * 1e6).round() as u64;
        let n = (q.duration_s / h).ceil() as u64;
        for i in 0..n {
            let (a, b) = (us * i / n, us * (i + 1) / n);
            let t0 = a as f64 * 1e-6;
            p.segments.push(Segment {
                t0_s: q.t0_s + t0,
                duration_s: (b - a) as f64 * 1e-6,
                coeffs: q.coeffs.map(|c| shifted(&c, t0)),
            });
        }
    }
    p
}

/// A fresh node with a full queue of short segments (Case I cut into 20 ms
/// pieces: 16 of them hold 0.32 s of plan, about as little as the look-ahead
/// for the configured 0.5 s stop allows) and holds dated with ramps for the
/// path ahead whose windows overlap 13–14 and 9–10 of them: the tick that takes
/// each checks the queue up to the window's end.
fn short_queue(r: &mut Recorder, plan: &Plan) {
    let short = cut(plan, 0.02, 3.5);
    let segs = wire_segments(&short);
    let settings = DriveSettings {
        control_rate: 1e6 / TICK_US as f64,
        underrun_margin: 0.005,
        ..DriveSettings::default()
    };
    let cfg = DriveConfig::new(&plan.robot, &Limits::default(), 1, &settings, 0.5, 0.25);
    r.node = Drive::new(NODE);
    r.receiver = Receiver::new(NODE);
    r.inbox = Inbox::new();
    r.chain = Chain::default();
    r.motor = Motor::default();
    r.out.u8(b'N');
    r.out.u8(NODE);
    // Time syncs every 20 ms, as before: the node needs a few to arm.
    r.park_and_configure(&segs[0], &cfg, 100_000);
    let mut next = 0;
    while next < QUEUE_CAPACITY {
        let out = r.chain.next(&segs[next], segs.get(next + 1));
        for f in out.frames(true) {
            r.rx(f);
        }
        next += 1;
        r.tick();
    }
    assert_eq!(r.node.queue_depth(), QUEUE_CAPACITY, "the queue is full");
    assert_eq!(r.node.queue_ramps_ns().0.max(500_000_000), 500_000_000);
    r.command(CommandCode::Arm, 0);
    r.tick();
    let host_now = (r.now + 3_000_000) as u32;
    r.command(CommandCode::Start, host_now + 5_000);
    let rejects = r.node.stats.rejects;
    // 0.49 s: its window (0.245 s) overlaps 13–14 of the 20 ms segments;
    // 0.33 s (above every piece's own, 0.325 s at most): 0.165 s, 9–10. Both
    // run their own.
    for (ramp_100us, run_us) in [(4_900, 300_000), (3_300, 600_000)] {
        for _ in 0..run_us / TICK_US {
            r.top_up(&segs, &mut next);
            r.tick();
        }
        assert_eq!(r.node.state(), State::Running, "running on short segments");
        r.command2(CommandCode::FeedHold, 0, ramp_100us);
        let mut held_us = 0;
        while r.node.scaling_phase() != Phase::Rest && held_us < 1_000_000 {
            r.top_up(&segs, &mut next);
            r.tick();
            held_us += TICK_US;
        }
        eprintln!(
            "golden frames: a hold carrying {ramp_100us} × 100 µs over 20 ms segments at rest in {held_us} µs"
        );
        assert!(
            held_us <= ramp_100us as u64 * 100 + 200,
            "{ramp_100us}: {held_us} µs"
        );
        r.command(CommandCode::Resume, 0);
    }
    assert_eq!(r.node.stats.rejects, rejects, "short segments rejected");
    // The host goes silent with the queue full of short segments: the node
    // faults with Underrun, and the tick that takes the fault scans the
    // queue for the ramp it vouches for over a window of about 8 of them.
    for _ in 0..600_000 / TICK_US {
        r.top_up(&segs, &mut next);
        r.tick();
    }
    assert_eq!(r.node.scaling_phase(), Phase::Nominal, "back at σ = 1");
    let before = r.emergency_ramps.len();
    let mut waited_us = 0;
    while r.node.state() != State::Fault && waited_us < 2_000_000 {
        r.tick();
        waited_us += TICK_US;
    }
    assert_eq!(r.node.state(), State::Fault, "no underrun");
    assert_eq!(r.node.fault(), FaultCode::Underrun);
    let vouched = &r.emergency_ramps[before..];
    eprintln!(
        "golden frames: an underrun over 20 ms segments vouches for {vouched:?} × 100 µs, in Fault at rest after {waited_us} µs"
    );
    assert!(
        matches!(vouched, [x] if *x > 0 && *x < 5_000),
        "the ramp it vouched for: {vouched:?}"
    );
}

#[test]
fn golden_vectors_are_current_and_within_a_micrometre() {
    let mut out = Out::default();
    out.0.extend_from_slice(b"TQG1");
    let worst = golden_plans(&mut out);
    eprintln!("golden plans: f32 drive position vs f64 plan, worst {worst:e} m");
    assert!(worst < 1e-6, "f32 position {worst:e} m from the plan");
    let (out, states, ticks) = golden_frames(out);
    eprintln!("golden frames: {ticks} ticks, states {states:?}");
    for s in [
        State::Loaded,
        State::Armed,
        State::Running,
        State::Stopping,
        State::Idle,
    ] {
        assert!(
            states.contains(&s),
            "the scenario never reached {s:?}: {states:?}"
        );
    }
    let path = root().join("testdata/firmware/golden.bin");
    if std::env::var_os("TRIQUINT_BLESS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, &out.0).unwrap();
        eprintln!("wrote {} ({} bytes)", path.display(), out.0.len());
    } else {
        let stored = std::fs::read(&path).unwrap_or_default();
        assert!(
            stored == out.0,
            "{} is stale: rerun with TRIQUINT_BLESS=1 and the QEMU test",
            path.display()
        );
    }
}
