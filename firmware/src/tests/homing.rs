//! Homing and the refusals of an unhomed node, on a node driven by frames
//! and ticks: an axis that follows its reference exactly, an encoder with
//! an unknown offset, and a limit switch with an exact-crossing latch.

extern crate std;
use std::vec::Vec;

use triquint_shared::protocol::config::{DriveConfig, DriveSettings};
use triquint_shared::protocol::{
    Command, CommandCode, Emergency, FaultCode, Frame, HeartbeatExt, Msg, Reject, State, TimeSync,
    config_write_frame, decode, flags,
};
use triquint_shared::{Limits, Robot};

use crate::hal::{Encoder, LimitSwitch, MotorOutput, RxFrame};
use crate::inbox::Item;
use crate::node::Node;

const TICK: u64 = 1000;
/// Encoder counts per metre of the default configuration.
const CPM: f64 = 131_072.0 / 0.010;

struct Enc(i64);
impl Encoder for Enc {
    fn read_counts(&mut self) -> i64 {
        self.0
    }
}
struct Motor;
impl MotorOutput for Motor {
    fn set_torque(&mut self, _: f32) {}
    fn enable(&mut self, _: bool) {}
}

/// A switch at true height `at` (m): active at and above it; the edge
/// latches the count at the exact crossing.
struct Switch {
    active: bool,
    edge: Option<i64>,
}
impl LimitSwitch for Switch {
    fn active(&mut self) -> bool {
        self.active
    }
    fn take_edge(&mut self) -> Option<i64> {
        self.edge.take()
    }
}

/// Node `id` driving axis 1 (index 0) of a robot with drives `ids`.
struct Rig {
    node: Node,
    cfg: DriveConfig,
    t: u64,
    /// True joint position (m).
    q: f64,
    /// Encoder count at true position 0 (unknown to the node).
    enc_offset: i64,
    /// True switch height (m); `None`: dead switch.
    switch_at: Option<f64>,
    stuck: bool,
    sw: Switch,
    sent: Vec<Frame>,
    token: u8,
    seq: u8,
}

impl Rig {
    fn new(id: u8, ids: [u8; 3]) -> Self {
        let s = DriveSettings {
            node_ids: ids,
            ..DriveSettings::default()
        };
        let cfg = DriveConfig::new(&Robot::default(), &Limits::default(), 0, &s, 0.4, 0.2);
        Self {
            node: Node::new_unhomed(id),
            cfg,
            t: 1_000_000,
            q: 0.2,
            enc_offset: 987_654_321,
            switch_at: Some(f64::from(cfg.switch_height)),
            stuck: false,
            sw: Switch {
                active: false,
                edge: None,
            },
            sent: Vec::new(),
            token: 0,
            seq: 0,
        }
    }

    fn counts(&self, q: f64) -> i64 {
        (q * CPM).floor() as i64 + self.enc_offset
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
        let id = self.node.node_id();
        for (k, v) in self.cfg.to_values().iter().enumerate() {
            self.rx(config_write_frame(id, k as u8, *v));
        }
        let crc = self.cfg.crc();
        assert_eq!(self.command(CommandCode::ConfigCommit, crc), 0);
        assert_eq!(self.node.config_crc(), crc);
        self.run(5);
    }

    fn command(&mut self, c: CommandCode, arg: u32) -> u8 {
        let n = self.sent.len();
        self.token = self.token.wrapping_add(1);
        let id = self.node.node_id();
        self.rx(Command {
            command: c as u8,
            token: self.token,
            arg,
            arg2: 0,
        }
        .to_frame(id));
        self.sent[n..]
            .iter()
            .filter_map(|f| match decode(f) {
                Ok((Msg::CommandAck(a), _)) => Some(a.result),
                _ => None,
            })
            .next_back()
            .unwrap_or(255)
    }

    /// One tick: the axis moves to the reference the node commanded (a
    /// perfect axis), the switch latches where it was crossed.
    fn tick(&mut self) {
        if self.t % 20_000 == 0 {
            self.seq = self.seq.wrapping_add(1);
            let prev = self.t.saturating_sub(20_000) as u32;
            self.rx(TimeSync {
                seq: self.seq,
                prev_tx_us: prev,
            }
            .to_frame(0));
        }
        let before = self.q;
        if let Some(h) = self.node.homing() {
            // The homing reference is in the encoder's frame.
            let counts = f64::from(h.q) * CPM + (self.node.home_offset() as f64);
            self.q = (counts - self.enc_offset as f64) / CPM;
        }
        let now_on = self.stuck || self.switch_at.is_some_and(|s| self.q >= s);
        let was_on = self.stuck || self.switch_at.is_some_and(|s| before >= s);
        if now_on && !was_on {
            let s = self.switch_at.unwrap_or(self.q);
            self.sw.edge = Some(self.counts(s));
        }
        self.sw.active = now_on;
        let mut enc = Enc(self.counts(self.q));
        self.node
            .drive
            .tick_with_switch(self.t, &mut enc, &mut Motor, &mut self.sw);
        while let Some(f) = self.node.pop_tx() {
            self.sent.push(f);
        }
        self.t += TICK;
    }

    fn run(&mut self, n: usize) {
        for _ in 0..n {
            self.tick();
        }
    }

    /// Ticks until the node leaves Homing (at most `max` ticks).
    fn home(&mut self, max: usize) -> usize {
        for k in 0..max {
            if self.node.state() != State::Homing {
                return k;
            }
            self.tick();
        }
        max
    }

    fn emergencies(&self) -> Vec<u8> {
        self.sent
            .iter()
            .filter_map(|f| match decode(f) {
                Ok((Msg::Emergency(e), _)) => Some(e.code),
                _ => None,
            })
            .collect()
    }

    fn last_flags(&self) -> u8 {
        self.sent
            .iter()
            .rev()
            .find_map(|f| match decode(f) {
                Ok((Msg::HeartbeatExt(HeartbeatExt { flags, .. }), _)) => Some(flags),
                _ => None,
            })
            .unwrap_or(0)
    }

    /// The node's position (m, its own frame) from its measurement.
    fn measured(&self) -> f32 {
        self.node.stats.q
    }
}

fn a_segment() -> triquint_shared::protocol::WireSegment {
    use triquint_shared::protocol::segment::{FLAG_FIRST, FLAG_LAST};
    use triquint_shared::quintic::Quintic;
    let mut coeffs = [[0.0; 6]; 3];
    for (j, c) in coeffs.iter_mut().enumerate() {
        c[0] = 0.3 + 0.01 * j as f64;
    }
    let q = Quintic {
        coeffs,
        duration: 0.2,
    };
    triquint_shared::protocol::WireSegment::from_quintic(0, &q, FLAG_FIRST | FLAG_LAST).unwrap()
}

#[test]
fn an_unhomed_node_refuses_segments_and_arm_and_stays_idle() {
    let mut r = Rig::new(1, [1, 2, 3]);
    r.configure();
    assert_eq!(r.last_flags() & flags::HOMED, 0);
    assert_ne!(r.last_flags() & flags::CONFIGURED, 0);
    let n = r.sent.len();
    for f in a_segment().frames(false) {
        r.rx(f);
    }
    let acks: Vec<u8> = r.sent[n..]
        .iter()
        .filter_map(|f| match decode(f) {
            Ok((Msg::SegmentAck(a), _)) => Some(a.result),
            _ => None,
        })
        .collect();
    assert_eq!(acks, std::vec![Reject::NotHomed as u8]);
    assert_eq!(r.node.queue_depth(), 0);
    assert_eq!(r.command(CommandCode::Arm, 0), FaultCode::NotHomed as u8);
    r.run(3);
    assert_eq!(r.node.state(), State::Idle);
    assert_eq!(r.node.fault(), FaultCode::None);
    assert!(r.emergencies().is_empty());
}

#[test]
fn home_needs_idle_and_a_configuration() {
    let mut r = Rig::new(1, [1, 2, 3]);
    r.run(3);
    assert_eq!(r.command(CommandCode::Home, 0), FaultCode::NoConfig as u8);
    assert_eq!(r.node.state(), State::Idle);
    r.configure();
    assert_eq!(r.command(CommandCode::Home, 0), 0);
    assert_eq!(r.node.state(), State::Homing);
    // Home again while homing: wrong state, homing goes on.
    assert_eq!(r.command(CommandCode::Home, 0), FaultCode::WrongState as u8);
    assert_eq!(r.node.state(), State::Homing);
}

#[test]
fn homing_finds_the_zero_within_one_count_and_unlocks_motion() {
    let mut r = Rig::new(1, [1, 2, 3]);
    r.configure();
    assert_eq!(r.command(CommandCode::Home, 0), 0);
    let ticks = r.home(40_000);
    assert_eq!(r.node.state(), State::Idle, "after {ticks} ticks");
    assert!(r.node.is_homed());
    // 0.22 m at 25 mm/s plus ramps and back-off: about 10 s at 1 kHz.
    assert!((8_000..14_000).contains(&ticks), "{ticks}");
    r.run(3);
    let err_counts = (f64::from(r.measured()) - r.q) * CPM;
    assert!(err_counts.abs() <= 1.0, "{err_counts} counts");
    // Backed off below the switch, within back-off + braking.
    let below = f64::from(r.cfg.switch_height) - r.q;
    assert!(below > 0.0 && below < 0.012, "{below}");
    r.run(200);
    assert_ne!(r.last_flags() & flags::HOMED, 0);
    assert!(r.emergencies().is_empty());
    // Segments are accepted now.
    let n = r.sent.len();
    for f in a_segment().frames(false) {
        r.rx(f);
    }
    assert!(r.sent[n..].iter().any(|f| matches!(
        decode(f),
        Ok((Msg::SegmentAck(a), _)) if a.result == Reject::Accepted as u8
    )));
    assert_eq!(r.node.state(), State::Loaded);
}

#[test]
fn homing_survives_reset_clear_fault_and_configuration() {
    let mut r = Rig::new(1, [1, 2, 3]);
    r.configure();
    r.command(CommandCode::Home, 0);
    r.home(40_000);
    assert!(r.node.is_homed());
    let offset = r.node.home_offset();
    assert_eq!(r.command(CommandCode::Reset, 0), 0);
    r.configure();
    r.rx(Emergency::default().to_frame(0));
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.command(CommandCode::ClearFault, 0), 0);
    r.run(3);
    assert_eq!(r.node.state(), State::Idle);
    assert!(r.node.is_homed());
    assert_eq!(r.node.home_offset(), offset);
    // Power-on loses it.
    r.node = Node::new_unhomed(1);
    assert!(!r.node.is_homed());
}

#[test]
fn a_switch_active_at_start_is_a_fault() {
    let mut r = Rig::new(1, [1, 2, 3]);
    r.stuck = true;
    r.configure();
    assert_eq!(
        r.command(CommandCode::Home, 0),
        FaultCode::HomeSwitchActive as u8
    );
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(
        r.emergencies(),
        std::vec![FaultCode::HomeSwitchActive as u8]
    );
    assert_ne!(r.last_flags() & flags::SWITCH, 0);
}

#[test]
fn a_dead_switch_ends_at_the_maximum_travel() {
    let mut r = Rig::new(1, [1, 2, 3]);
    r.switch_at = None;
    r.configure();
    let q0 = r.q;
    r.command(CommandCode::Home, 0);
    r.home(40_000);
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.node.fault(), FaultCode::HomeSwitchNeverTriggered);
    assert!(!r.node.is_homed());
    let travel = r.q - q0;
    assert!(
        (travel - f64::from(r.cfg.homing_max_travel)).abs() < 1e-3,
        "{travel}"
    );
    assert_eq!(
        r.emergencies(),
        std::vec![FaultCode::HomeSwitchNeverTriggered as u8]
    );
}

#[test]
fn homing_times_out() {
    let mut r = Rig::new(1, [1, 2, 3]);
    r.cfg.homing_timeout = 2.0;
    r.configure();
    r.command(CommandCode::Home, 0);
    let ticks = r.home(40_000);
    assert_eq!(r.node.fault(), FaultCode::HomingTimeout);
    assert!((2_000..2_010).contains(&ticks), "{ticks}");
}

#[test]
fn stop_while_homing_comes_to_rest_unhomed() {
    let mut r = Rig::new(1, [1, 2, 3]);
    r.configure();
    r.command(CommandCode::Home, 0);
    r.run(2_000);
    assert_eq!(r.command(CommandCode::Stop, 0), 0);
    let ticks = r.home(2_000);
    assert!(ticks < 500, "{ticks}");
    assert_eq!(r.node.state(), State::Idle);
    assert!(!r.node.is_homed());
    assert_eq!(r.node.fault(), FaultCode::None);
}

#[test]
fn home_is_urgent_and_peers_are_the_configured_drives() {
    let home = Item::Command {
        command: Command {
            command: CommandCode::Home as u8,
            ..Command::default()
        },
        rx_us: 0,
        data: crate::inbox::CommandData::None,
    };
    assert!(home.is_urgent());
    // Node 12 drives axis 1 of a robot on nodes 12, 13, 14.
    let mut r = Rig::new(12, [12, 13, 14]);
    r.configure();
    r.command(CommandCode::Home, 0);
    r.run(100);
    // An Emergency of node 2 (another device) does not concern it...
    r.rx(Emergency::default().to_frame(2));
    assert_eq!(r.node.state(), State::Homing);
    // ...one of its peer 13 does: its own Emergency at once, then it slows
    // to rest with the homing ramp (Stopping) and faults.
    r.rx(Emergency::default().to_frame(13));
    assert_eq!(r.node.state(), State::Stopping);
    assert_eq!(r.node.fault(), FaultCode::PeerEmergency);
    assert_eq!(r.emergencies(), std::vec![FaultCode::PeerEmergency as u8]);
    r.run(2_000);
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.node.fault(), FaultCode::PeerEmergency);
    assert!(!r.node.is_homed());
    // Its frames carry its own id.
    assert!(r.sent.iter().any(|f| f.id == 0x700 + 12));
}

/// An Emergency mid-homing, at full homing speed: the reference slows to
/// rest with bounded acceleration (no step in velocity), then Fault, not
/// homed; a later Home starts again from there.
#[test]
fn an_emergency_while_homing_ramps_to_rest_then_faults() {
    let mut r = Rig::new(1, [1, 2, 3]);
    r.configure();
    r.command(CommandCode::Home, 0);
    r.run(2_000);
    let v0 = r.node.homing().map(|h| h.v).unwrap_or_default();
    assert!(v0.abs() > 0.02, "at homing speed: {v0}");
    r.rx(Emergency::default().to_frame(0));
    assert_eq!(r.node.state(), State::Stopping);
    assert_eq!(r.node.fault(), FaultCode::HostEmergency);
    let dt = TICK as f32 * 1e-6;
    let (mut v, mut ticks) = (v0, 0);
    while let Some(h) = r.node.homing() {
        // The homing ramp's acceleration limit (0.25 m/s²) per tick, and margin.
        assert!((h.v - v).abs() <= 0.3 * dt, "velocity step {} → {}", v, h.v);
        v = h.v;
        r.tick();
        ticks += 1;
        assert!(ticks < 2_000, "still stopping");
    }
    assert_eq!(r.node.state(), State::Fault);
    assert_eq!(r.node.fault(), FaultCode::HostEmergency);
    assert!(!r.node.is_homed());
    // About v0 / a_max (0.1 s) plus the jerk-limited corners, not at once.
    assert!(ticks as f32 * dt > 0.05, "{ticks} ticks");
}
