//! Feed hold, resume, override and stop in every state, applied at the host
//! time the command carries, on one node driven by frames and ticks.

extern crate std;
use std::format;
use std::vec::Vec;

use triquint_shared::protocol::{Command, CommandCode, FaultCode, Msg, State, decode};

use super::{Rig, segments};
use crate::scaling::Phase;

impl Rig {
    /// Sends a command with both arguments: (result, acknowledged value).
    fn command2(&mut self, c: CommandCode, arg: u32, arg2: u16) -> (u8, u32) {
        let n = self.sent.len();
        self.token = self.token.wrapping_add(1);
        self.rx(Command {
            command: c as u8,
            token: self.token,
            arg,
            arg2,
        }
        .to_frame(0));
        self.sent[n..]
            .iter()
            .filter_map(|f| match decode(f) {
                Ok((Msg::CommandAck(a), _)) => Some((a.result, a.value)),
                _ => None,
            })
            .next_back()
            .unwrap_or((255, 0))
    }

    /// Host time now (µs; the rig's host time is its local time).
    fn host_us(&self) -> u32 {
        self.t as u32
    }

    /// Runs until Idle or `ms`; returns (ms run, largest change of the own
    /// axis's reference velocity in one tick, m/s).
    fn run_to_idle(&mut self, ms: u64) -> (u64, f32) {
        let mut step = 0.0f32;
        let mut last = self.node.stats.reference.qd[1];
        for k in 0..ms {
            self.tick();
            let v = self.node.stats.reference.qd[1];
            step = step.max((v - last).abs());
            last = v;
            if self.node.state() == State::Idle {
                return (k + 1, step);
            }
        }
        (ms, step)
    }
}

const HOLD: CommandCode = CommandCode::FeedHold;
const RESUME: CommandCode = CommandCode::Resume;
const OVERRIDE: CommandCode = CommandCode::Override;
const STOP: CommandCode = CommandCode::Stop;
const OK: u8 = FaultCode::None as u8;
const WRONG: u8 = FaultCode::WrongState as u8;
const CAPPED: u8 = FaultCode::OverrideAboveCap as u8;

/// A node in the named state: idle, loaded, armed, running, held (at rest),
/// holding (in the hold ramp), faulted.
fn in_state(name: &str) -> Rig {
    let segs = segments(4, 0.3);
    let mut r = match name {
        "idle" => {
            let mut r = Rig::new();
            r.parked = segs[0].normalised_f32()[1][0];
            r.configure();
            r.run(50);
            return r;
        }
        _ => Rig::loaded(&segs),
    };
    match name {
        "loaded" => {}
        "armed" => {
            assert_eq!(r.command(CommandCode::Arm, 0), OK);
        }
        "running" | "held" | "holding" | "faulted" => {
            r.start();
            r.run(200);
            assert_eq!(r.node.state(), State::Running);
            if name == "held" || name == "holding" {
                assert_eq!(r.command(HOLD, 0), OK);
                r.run(if name == "held" { 450 } else { 100 });
            }
            if name == "faulted" {
                // Encoder 5 mm off: following error, stop, Fault.
                r.offset = 0.005;
                r.run(600);
                assert_eq!(r.node.state(), State::Fault);
                r.offset = 0.0;
            }
        }
        _ => panic!("no state {name}"),
    }
    r
}

/// Every command in every state: the result, the state after, and (for a
/// motion) whether the plan still completes.
#[test]
fn each_command_in_each_state() {
    // (state, command, override per mille, result, state after)
    let table: &[(&str, CommandCode, u16, u8, State)] = &[
        ("idle", HOLD, 0, OK, State::Idle),
        ("idle", RESUME, 0, OK, State::Idle),
        ("idle", OVERRIDE, 500, OK, State::Idle),
        ("idle", OVERRIDE, 1001, CAPPED, State::Idle),
        ("idle", STOP, 0, OK, State::Idle),
        ("loaded", HOLD, 0, OK, State::Loaded),
        ("loaded", RESUME, 0, OK, State::Loaded),
        ("loaded", OVERRIDE, 500, OK, State::Loaded),
        ("loaded", STOP, 0, OK, State::Loaded),
        ("armed", HOLD, 0, OK, State::Armed),
        ("armed", OVERRIDE, 800, OK, State::Armed),
        ("armed", STOP, 0, OK, State::Loaded),
        ("running", HOLD, 0, OK, State::Running),
        ("running", RESUME, 0, OK, State::Running),
        ("running", OVERRIDE, 500, OK, State::Running),
        ("running", OVERRIDE, 0, CAPPED, State::Running),
        ("running", OVERRIDE, 1200, CAPPED, State::Running),
        ("running", STOP, 0, OK, State::Stopping),
        ("held", HOLD, 0, OK, State::Running),
        ("held", RESUME, 0, OK, State::Running),
        ("held", OVERRIDE, 500, OK, State::Running),
        ("held", STOP, 0, OK, State::Stopping),
        ("holding", HOLD, 0, OK, State::Running),
        ("holding", RESUME, 0, OK, State::Running),
        ("holding", OVERRIDE, 700, OK, State::Running),
        ("holding", STOP, 0, OK, State::Stopping),
        ("faulted", HOLD, 0, WRONG, State::Fault),
        ("faulted", RESUME, 0, WRONG, State::Fault),
        ("faulted", OVERRIDE, 500, OK, State::Fault),
        ("faulted", STOP, 0, OK, State::Fault),
    ];
    for &(name, c, pm, want, after) in table {
        let mut r = in_state(name);
        let ctx = format!("{c:?} {pm} when {name}");
        let (res, value) = r.command2(c, 0, pm);
        assert_eq!(res, want, "{ctx}: result");
        if c == OVERRIDE {
            assert_eq!(value, 1000, "{ctx}: the cap in the acknowledgement");
            let expect = if want == OK { pm as u32 } else { 1000 };
            assert_eq!(r.node.override_permille(), expect, "{ctx}");
        }
        assert_eq!(r.node.state(), after, "{ctx}: state");
        // What follows: a motion completes once resumed (unless stopped or faulted).
        match (name, c) {
            ("running" | "held" | "holding", HOLD) => {
                r.run(450);
                assert_eq!(r.node.scaling_phase(), Phase::Rest, "{ctx}");
                assert!(r.node.is_held(), "{ctx}");
                assert_eq!(r.command(RESUME, 0), OK, "{ctx}");
                let (_, step) = r.run_to_idle(4000);
                assert_eq!(r.node.state(), State::Idle, "{ctx}: completes");
                assert!(step < 2e-3, "{ctx}: velocity step {step}");
            }
            ("running" | "held" | "holding", RESUME | OVERRIDE) => {
                if name != "running" && !(c == RESUME) {
                    assert_eq!(r.command(RESUME, 0), OK, "{ctx}");
                }
                let (_, step) = r.run_to_idle(4000);
                assert_eq!(r.node.state(), State::Idle, "{ctx}: completes");
                assert_eq!(r.node.fault(), FaultCode::None, "{ctx}");
                assert!(step < 2e-3, "{ctx}: velocity step {step}");
            }
            (_, STOP) if after == State::Stopping => {
                r.run(450);
                assert_eq!(r.node.state(), State::Idle, "{ctx}: stopped");
                assert_eq!(r.node.queue_depth(), 0, "{ctx}");
            }
            ("faulted", _) => {
                assert_eq!(r.node.fault(), FaultCode::FollowingError, "{ctx}");
            }
            _ => {}
        }
    }
}

#[test]
fn hold_before_start_is_latched_and_resume_runs_the_plan() {
    let mut r = in_state("loaded");
    assert_eq!(r.command(HOLD, 0), OK);
    assert!(r.node.is_held());
    r.start();
    r.run(100);
    assert_eq!(r.node.state(), State::Running);
    assert_eq!(r.node.scaling_phase(), Phase::Rest);
    let q = r.node.stats.reference.q;
    r.run(300);
    assert_eq!(r.node.stats.reference.q, q, "held at the start");
    assert_eq!(r.node.plan_ns(), 0);
    assert_eq!(r.command(RESUME, 0), OK);
    let (ms, _) = r.run_to_idle(4000);
    assert_eq!(r.node.state(), State::Idle);
    assert_eq!(r.node.fault(), FaultCode::None);
    // 1.2 s of plan + the resume ramp's lost 0.2 s.
    assert!((1350..1500).contains(&ms), "{ms} ms");
    assert!(!r.node.is_held());
}

#[test]
fn override_before_start_applies_at_start_and_persists() {
    let mut r = in_state("loaded");
    assert_eq!(r.command2(OVERRIDE, 0, 500).0, OK);
    r.start();
    r.run(20);
    let s0 = r.node.plan_ns();
    r.run(400);
    let ds = r.node.plan_ns() - s0;
    assert!(
        (ds - 200_000_000).abs() < 1_000_000,
        "plan time {ds} ns in 400 ms"
    );
    let (ms, _) = r.run_to_idle(4000);
    assert_eq!(r.node.state(), State::Idle);
    // 1.2 s of plan at half speed: 2.4 s from the start.
    assert!((2380..2450).contains(&(ms + 420)), "{ms}");
    assert_eq!(r.node.override_permille(), 500, "persists after the plan");
}

#[test]
fn override_above_the_cap_is_refused_with_the_cap() {
    let segs = segments(4, 0.3);
    let mut r = Rig::new();
    r.cfg.override_cap = 1.5;
    let mut r = Rig::loaded_with(r, &segs);
    assert_eq!(r.command2(OVERRIDE, 0, 1501), (CAPPED, 1500));
    assert_eq!(r.node.override_permille(), 1000);
    assert_eq!(r.command2(OVERRIDE, 0, 1500), (OK, 1500));
    r.start();
    let (ms, _) = r.run_to_idle(4000);
    assert_eq!(r.node.state(), State::Idle);
    assert!(ms < 900, "1.2 s of plan at 150 %: {ms} ms");
}

/// A resume during the hold ramp must not be dropped, and a hold during the
/// resume ramp must continue from the current σ, not restart from σ = 1 (a
/// velocity step).
#[test]
fn resume_during_hold_and_hold_during_resume_ramps() {
    let mut r = in_state("holding");
    assert_eq!(r.command(RESUME, 0), OK);
    r.run(300);
    assert!(!r.node.is_held());
    // A hold at 20 % of the resume ramp: σ continues from where it is.
    let mut r = in_state("held");
    assert_eq!(r.command(RESUME, 0), OK);
    r.run(80);
    let before = r.node.scaling().at(r.t as i64 * 1000);
    assert!(before.sigma > 0.0 && before.sigma < 0.2, "{before:?}");
    assert_eq!(r.command(HOLD, 0), OK);
    let mut sig = Vec::new();
    for _ in 0..500 {
        r.tick();
        sig.push(r.node.scaling().at(r.t as i64 * 1000 - 1_000_000).sigma);
    }
    let max_step = sig
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(0.0, f32::max);
    assert!(max_step < 0.02, "σ step {max_step} per ms");
    assert!(
        sig.iter().all(|s| *s < 0.5),
        "σ rose to {:?}",
        sig.iter().fold(0.0f32, |a, b| a.max(*b))
    );
    assert_eq!(r.node.scaling_phase(), Phase::Rest);
    assert_eq!(r.command(RESUME, 0), OK);
    r.run_to_idle(4000);
    assert_eq!(r.node.state(), State::Idle);
    assert_eq!(r.node.fault(), FaultCode::None);
}

/// Two nodes, one getting the hold 3 ms later than the other, with the same
/// host time in it: the same plan time from then on.
#[test]
fn commands_apply_at_the_host_time_they_carry() {
    let mut a = in_state("running");
    let mut b = in_state("running");
    assert_eq!(a.t, b.t);
    let at = a.host_us();
    for (c, pm) in [(HOLD, 0u16), (RESUME, 0), (OVERRIDE, 600), (STOP, 0)] {
        let at = if c == HOLD { at } else { a.host_us() };
        assert_eq!(a.command2(c, at, pm).0, OK);
        b.run(3);
        a.run(3);
        assert_eq!(b.command2(c, at, pm).0, OK);
        for _ in 0..150 {
            a.tick();
            b.tick();
            assert!(
                (a.node.plan_ns() - b.node.plan_ns()).abs() < 2_000,
                "{c:?}: plan time {} vs {}",
                a.node.plan_ns(),
                b.node.plan_ns()
            );
        }
    }
}
