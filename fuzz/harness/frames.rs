// Shared by the `frames` fuzz target and firmware/tests/fuzz_corpus.rs (via
// include!): the input is a stream of frames, each [id low, id high (3 bits)
// | fd << 3, length, payload…]. Identifier 0x7FF (not in the protocol) is a
// pause instead: payload byte 0 = milliseconds of ticks without a frame.
//
// Every input runs twice through a drive node (node 2, axis 1), once as it
// comes and once on a node the harness configured first, so arbitrary frames
// reach Armed → Running → stop. Between frames the node ticks at the
// configured 1 kHz (time advances FRAME_US per frame), the harness sends a
// TimeSync every 100 ms and the encoder follows the reference (a perfect
// axis, parked at the start of the last accepted first segment; from the
// start at `parked_start()`, so a plan from there is not a jump the drive's
// following-error supervision at rest would fault on). Checked:
// nothing panics; a completed segment is exactly what its body encodes; a
// segment that failed the receive side's checks is never accepted; and the
// segment the node executes is always one it accepted, bit for bit (seq, CRC).

/// Harness time per frame (µs): about one classic frame on a 1 Mbit/s bus.
#[allow(dead_code)]
pub const FRAME_US: u64 = 137;
/// Harness tick period (µs): the default control rate, 1 kHz.
#[allow(dead_code)]
pub const TICK_US: u64 = 1000;
/// Where the harness's axis stands before a first segment is accepted (m):
/// axis 1 at the platform pose (0, 0, 0.62 m), where the corpus's plan starts.
#[allow(dead_code)]
pub fn parked_start() -> f32 {
    let m = triquint_shared::Robot::default().model::<f64>();
    let pose = nalgebra::Vector3::new(0.0, 0.0, 0.62);
    triquint_shared::kinematics::Pose::from_cartesian(&m, pose).map_or(0.0, |p| p.q[1] as f32)
}

/// The pause pseudo-identifier.
#[allow(dead_code)]
pub const PAUSE_ID: u16 = 0x7FF;
/// Harness time at which the input's first frame arrives (µs): after the
/// harness's own set-up (configuration and two syncs).
#[allow(dead_code)]
pub const FIRST_FRAME_US: u64 = 300_000;

/// What one pass did, for the corpus tests.
#[allow(dead_code)]
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Outcome {
    pub ticks: u64,
    pub running_ticks: u64,
    pub accepted: usize,
    pub refused_checked: usize,
}

/// The configuration the second pass starts with (the firmware tests' limits).
#[allow(dead_code)]
pub fn fuzz_config() -> triquint_shared::protocol::DriveConfig {
    use triquint_shared::protocol::config::{DriveConfig, DriveSettings};
    let limits = triquint_shared::Limits {
        velocity: 1.0,
        acceleration: 10.0,
        jerk: 50.0,
        ..triquint_shared::Limits::default()
    };
    let robot = triquint_shared::Robot::default();
    DriveConfig::new(&robot, &limits, 1, &DriveSettings::default(), 0.2, 0.1)
}

/// Frames in the input format (the inverse of the parser).
#[allow(dead_code)]
pub fn encode_frames(frames: &[triquint_shared::protocol::Frame]) -> Vec<u8> {
    let mut out = Vec::new();
    for f in frames {
        out.push(f.id as u8);
        out.push((f.id >> 8) as u8 & 0x07 | if f.fd { 0x08 } else { 0 });
        out.push(f.len);
        out.extend_from_slice(f.payload());
    }
    out
}

/// A pause of `ms` milliseconds in the input format.
#[allow(dead_code)]
pub fn pause(ms: u8) -> triquint_shared::protocol::Frame {
    triquint_shared::protocol::Frame::with_payload(PAUSE_ID, &[ms], false)
}

/// Runs one fuzz input (both passes).
pub fn fuzz_frames(data: &[u8]) -> [Outcome; 2] {
    [fuzz_pass(data, false), fuzz_pass(data, true)]
}

/// One pass of an input, on a fresh node (`configured`: set up first).
pub fn fuzz_pass(data: &[u8], configured: bool) -> Outcome {
    use triquint_firmware::inbox::Item;
    use triquint_shared::protocol::{
        CommandCode, Frame, Msg, Reject, SegmentEvent, SegmentRx, State, TimeSync, WireSegment,
        config_write_frame, decode,
    };

    struct Axis(i64);
    impl triquint_firmware::Encoder for Axis {
        fn read_counts(&mut self) -> i64 {
            self.0
        }
    }
    struct Motor;
    impl triquint_firmware::MotorOutput for Motor {
        fn set_torque(&mut self, t: f32) {
            assert!(t.is_finite(), "torque {t}");
        }
        fn enable(&mut self, _on: bool) {}
    }

    struct Harness {
        node: triquint_firmware::Node,
        t: u64,
        next_tick: u64,
        next_sync: u64,
        sync_seq: u8,
        /// Start position of our axis of the last accepted first segment.
        parked: f32,
        /// (seq, CRC) of every segment the node accepted.
        accepted: std::collections::HashSet<(u16, u32)>,
        out: Outcome,
    }

    impl Harness {
        fn frame(&mut self, frame: Frame) {
            let rx = triquint_firmware::RxFrame {
                frame,
                timestamp_us: self.t,
            };
            let snapshot = self.node.drive.snapshot();
            let Some(item) = self.node.receiver.on_frame(&rx, snapshot) else {
                return;
            };
            self.node.drive.take(&item);
            let Item::Segment(c) = item else {
                self.drain(None);
                return;
            };
            let verdict = self.drain(Some(c.seg.seq));
            let accepted = verdict == Some(Reject::Accepted as u8);
            assert!(
                !(accepted && c.verdict.is_err()),
                "segment {} accepted although its checks failed: {:?}",
                c.seg.seq,
                c.verdict
            );
            if accepted {
                self.accepted.insert((c.seg.seq, c.seg.crc));
                self.out.accepted += 1;
                if c.seg.first {
                    self.parked = c.begin.q[1];
                }
            } else if c.verdict.is_err() {
                self.out.refused_checked += 1;
            }
        }

        /// Empties the outbox; returns the result of the SegmentAck for `seq`.
        fn drain(&mut self, seq: Option<u16>) -> Option<u8> {
            let mut result = None;
            while let Some(f) = self.node.drive.pop_tx() {
                if let Ok((Msg::SegmentAck(a), _)) = decode(&f)
                    && Some(a.seq) == seq
                {
                    result = Some(a.result);
                }
            }
            result
        }

        /// Ticks (and syncs) due up to time `until`.
        fn run_to(&mut self, until: u64) {
            while self.next_tick <= until {
                self.t = self.t.max(self.next_tick);
                if self.next_sync <= self.t {
                    self.sync_seq = self.sync_seq.wrapping_add(1);
                    let prev = self.next_sync.saturating_sub(100_000) as u32;
                    let f = TimeSync {
                        seq: self.sync_seq,
                        prev_tx_us: prev,
                    }
                    .to_frame(0);
                    self.frame(f);
                    self.next_sync += 100_000;
                }
                self.tick();
                self.next_tick += TICK_US;
            }
            self.t = self.t.max(until);
        }

        fn tick(&mut self) {
            let d = &self.node.drive;
            let cpm = d.config().map_or(1e9, |c| c.counts_per_metre) as f64;
            let q = match d.state() {
                State::Idle | State::Loaded => self.parked,
                _ => d.stats.reference.q[1],
            };
            let q = if q.is_finite() { q as f64 } else { 0.0 };
            let counts = (q * cpm).round() as i64;
            self.node.drive.tick(self.t, &mut Axis(counts), &mut Motor);
            self.drain(None);
            self.out.ticks += 1;
            if let Some(running) = self.node.drive.executing() {
                self.out.running_ticks += 1;
                assert!(
                    self.accepted.contains(&running),
                    "executing segment {running:?}, never accepted"
                );
            }
        }
    }

    let mut h = Harness {
        node: triquint_firmware::Node::new(2),
        t: 0,
        next_tick: 0,
        next_sync: 0,
        sync_seq: 0,
        parked: parked_start(),
        accepted: std::collections::HashSet::new(),
        out: Outcome::default(),
    };
    if configured {
        let cfg = fuzz_config();
        for (k, v) in cfg.to_values().iter().enumerate() {
            h.frame(config_write_frame(2, k as u8, *v));
        }
        let commit = triquint_shared::protocol::Command {
            command: CommandCode::ConfigCommit as u8,
            token: 0,
            arg: cfg.crc(),
            arg2: 0,
        };
        h.frame(commit.to_frame(2));
        assert_eq!(h.node.drive.config_crc(), cfg.crc(), "harness set-up");
    }
    h.run_to(FIRST_FRAME_US);

    let mut asm = SegmentRx::default();
    let mut rest = data;
    while rest.len() >= 3 {
        let id = u16::from_le_bytes([rest[0], rest[1] & 0x07]);
        let fd = rest[1] & 0x08 != 0;
        let n = (rest[2] as usize).min(64).min(rest.len() - 3);
        let frame = Frame::with_payload(id, &rest[3..3 + n], fd);
        rest = &rest[3 + n..];
        if id == PAUSE_ID {
            let ms = frame.payload().first().copied().unwrap_or(0) as u64;
            h.run_to(h.t + ms * 1000);
            continue;
        }
        if let Ok((msg, _)) = decode(&frame)
            && let Some(SegmentEvent::Complete { segment, crc, .. }) =
                asm.push(msg.kind(), frame.payload())
        {
            assert_eq!(crc, segment.body_crc());
            assert_eq!(WireSegment::decode_body(&segment.encode_body()), Ok(segment));
        }
        h.frame(frame);
        h.run_to(h.t + FRAME_US);
    }
    // Let whatever was started run out (a stop or the plan's end).
    h.run_to(h.t + 100_000);
    h.out
}
