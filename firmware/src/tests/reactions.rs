//! The fault reaction table (`reaction`), row by row on one node driven by
//! frames and ticks: stop along the path, hold, open-loop hold and torque
//! off, by fault class, motion, brake and gravity load; the enable check's
//! verdicts on a one-axis plant; and the supervision of the Fault state.

extern crate std;

use triquint_shared::Robot;
use triquint_shared::protocol::{CommandCode, Emergency, FaultCode, State};

use super::{Plant, Rig, segments};
use crate::enable_check::Expected;
use crate::reaction::{self, Axis, Class, Reaction, TABLE};

/// A rig configured (brake, gravity as given), parked at rest.
fn idle(brake: bool, gravity: bool, trusted: bool) -> Rig {
    let mut r = Rig::new();
    r.cfg.brake = if brake { 1.0 } else { 0.0 };
    if !gravity {
        r.cfg.gravity = 0.0;
    }
    r.trusted = trusted;
    r.parked = 0.3;
    r.configure();
    r.run(50);
    r
}

/// The table itself: every class has one row, and the function reads it.
#[test]
fn the_table_has_a_row_per_class_and_is_what_reaction_returns() {
    for c in [Class::Path, Class::Tracking, Class::Scale, Class::Untrusted] {
        assert_eq!(TABLE.iter().filter(|r| r.0 == c).count(), 1, "{c:?}");
    }
    let code = |c: Class| match c {
        Class::Path => (FaultCode::HostEmergency, true),
        Class::Tracking => (FaultCode::FollowingError, true),
        Class::Scale => (FaultCode::WrongScale, true),
        Class::Untrusted => (FaultCode::FollowingError, false),
    };
    for (c, moving, off_safe, held) in TABLE {
        let (f, verified) = code(c);
        assert_eq!(reaction::class(f, verified), c);
        let ax = |brake, gravity_loaded| Axis {
            brake,
            gravity_loaded,
            verified,
        };
        assert_eq!(
            reaction::reaction(f, true, ax(false, true)),
            moving,
            "{c:?}"
        );
        assert_eq!(reaction::reaction(f, false, ax(true, true)), off_safe);
        assert_eq!(reaction::reaction(f, false, ax(false, false)), off_safe);
        assert_eq!(reaction::reaction(f, false, ax(false, true)), held);
    }
    // A reversed loop is never held, whatever the machine.
    for brake in [false, true] {
        let ax = Axis {
            brake,
            gravity_loaded: true,
            verified: true,
        };
        for moving in [false, true] {
            assert_eq!(
                reaction::reaction(FaultCode::WrongDirection, moving, ax),
                Reaction::TorqueOff
            );
        }
    }
}

/// Path, at rest: hold without a brake on a gravity-loaded axis; torque
/// off with a brake, or without gravity load.
#[test]
fn path_faults_at_rest_hold_or_take_the_torque_off() {
    for (brake, gravity, held) in [
        (false, true, true),
        (true, true, false),
        (false, false, false),
    ] {
        let mut r = idle(brake, gravity, true);
        assert!(r.powered);
        r.rx(Emergency::host_stop());
        r.run(2);
        assert_eq!(r.node.state(), State::Fault);
        assert_eq!(r.node.fault(), FaultCode::HostEmergency);
        assert_eq!(r.powered, held, "brake {brake} gravity {gravity}");
        assert_eq!(r.node.drive.is_torque_off(), !held);
    }
}

/// Path, moving: a stop along the path; at rest the brake's row (torque
/// off), or the hold.
#[test]
fn path_faults_moving_stop_on_the_path_then_react_at_rest() {
    let segs = segments(4, 0.3);
    for brake in [false, true] {
        let mut r = Rig::new();
        r.cfg.brake = if brake { 1.0 } else { 0.0 };
        let mut r = Rig::loaded_with(r, &segs);
        r.start();
        r.run(200);
        r.rx(Emergency::host_stop());
        r.run(2);
        assert_eq!(r.node.state(), State::Stopping);
        assert!(r.powered);
        r.run(600);
        assert_eq!(r.node.state(), State::Fault);
        assert_eq!(r.powered, !brake, "brake {brake}");
    }
}

/// Tracking (a following error on a verified axis): moving, a stop along
/// the path; at rest, hold without a brake, torque off with one.
#[test]
fn tracking_faults_stop_on_the_path_then_hold_or_brake() {
    let segs = segments(4, 0.3);
    for brake in [false, true] {
        let mut r = Rig::new();
        r.cfg.brake = if brake { 1.0 } else { 0.0 };
        let mut r = Rig::loaded_with(r, &segs);
        r.start();
        r.run(100);
        r.offset = 2e-3;
        r.run(2);
        assert_eq!(r.node.state(), State::Stopping, "brake {brake}");
        assert!(r.powered);
        r.run(600);
        assert_eq!(r.node.state(), State::Fault);
        assert_eq!(r.node.fault(), FaultCode::FollowingError);
        assert_eq!(r.powered, !brake, "brake {brake}");

        let mut r = idle(brake, true, true);
        r.offset = 2.0 * r.cfg.following_error_max;
        r.run(2);
        assert_eq!(r.node.fault(), FaultCode::FollowingError);
        assert_eq!(r.powered, !brake, "at rest, brake {brake}");
    }
}

/// Untrusted (a following error before the enable check passed): torque
/// off at once, moving or not, brake or not.
#[test]
fn untrusted_faults_take_the_torque_off_at_once() {
    let segs = segments(4, 0.3);
    for brake in [false, true] {
        let mut r = idle(brake, true, false);
        assert!(!r.node.drive.is_verified());
        r.offset = 2.0 * r.cfg.following_error_max;
        r.run(2);
        assert_eq!(r.node.fault(), FaultCode::FollowingError);
        assert!(!r.powered, "at rest, brake {brake}");

        // The ideal encoder gives the check no verdict: unverified.
        let mut r = Rig::new();
        r.trusted = false;
        r.cfg.brake = if brake { 1.0 } else { 0.0 };
        let mut r = Rig::loaded_with(r, &segs);
        r.start();
        r.run(100);
        assert_eq!(r.node.state(), State::Running);
        assert!(!r.node.drive.is_verified());
        r.offset = 2e-3;
        r.run(2);
        assert_eq!(r.node.state(), State::Fault, "moving, brake {brake}");
        assert!(!r.powered);
        assert_eq!(r.emergencies(), [FaultCode::FollowingError as u8]);
        // ClearFault: the power stage comes back with a new enable check.
        r.offset = 0.0;
        assert_eq!(r.command(CommandCode::ClearFault, 0), 0);
        r.run(1);
        assert!(r.powered);
        assert!(r.node.drive.is_checking());
    }
}

/// The Fault state is supervised: a held axis whose following error
/// exceeds its bound is torque off where its loop is not trusted, held
/// where it is (a push on a verified axis).
#[test]
fn a_held_fault_that_cannot_hold_takes_the_torque_off_unless_verified() {
    for trusted in [true, false] {
        let mut r = idle(false, true, trusted);
        r.rx(Emergency::host_stop());
        r.run(2);
        assert_eq!(r.node.state(), State::Fault);
        assert!(r.powered);
        r.offset = 2.0 * r.cfg.following_error_max;
        r.run(3);
        assert_eq!(r.powered, trusted, "trusted {trusted}");
        assert_eq!(
            r.node.fault(),
            FaultCode::HostEmergency,
            "the first cause stays"
        );
        let fe = r.emergencies().contains(&(FaultCode::FollowingError as u8));
        assert_eq!(fe, !trusted);
    }
}

fn plant(encoder: f64) -> Plant {
    let e = Expected::of(&Robot::default().model::<f32>());
    Plant {
        q: 0.3,
        v: 0.0,
        gain: e.gain as f64,
        load: e.load as f64,
        encoder,
        pending: 0.0,
    }
}

/// The enable check on a one-axis plant under gravity: passes on the
/// model's axis; a reversed encoder, or one 32× off either way, ends in
/// Fault naming what (or, for the runaway of a reversed loop, the
/// following error first), with the table's reaction; an axis that does
/// not move gets no verdict.
#[test]
fn the_enable_check_names_a_wrong_direction_or_scale() {
    for (encoder, want) in [
        (1.0, FaultCode::None),
        (-1.0, FaultCode::FollowingError),
        (32.0, FaultCode::FollowingError),
        (1.0 / 32.0, FaultCode::WrongScale),
    ] {
        let mut r = Rig::new();
        r.trusted = false;
        r.plant = Some(plant(encoder));
        r.configure();
        r.run(200);
        assert_eq!(r.node.fault(), want, "encoder ×{encoder}");
        assert_eq!(r.node.drive.is_verified(), want == FaultCode::None);
        let g = r.node.drive.stats.check_gain_ratio;
        if want == FaultCode::None {
            assert!((0.9..1.1).contains(&g), "{g}");
        }
        if want == FaultCode::WrongScale {
            // Right sign, wrong gain: held open loop on the measured load.
            assert!((0.02..0.05).contains(&g), "{g}");
            assert!(r.powered);
            let p0 = r.plant.unwrap();
            r.run(500);
            let drift = (r.plant.unwrap().q - p0.q).abs();
            // Torque off, it would fall 0.5·g_axis·t² (no friction here).
            let fall = 0.5 * p0.load * p0.gain * 0.5 * 0.5;
            assert!(drift < 0.5 * fall, "{drift} m of {fall} m");
        } else if want != FaultCode::None {
            assert!(!r.powered, "encoder ×{encoder}");
        }
    }
    // The encoder and the motor both reversed (the machine file's direction
    // flipped): a sound loop holding with a lowering torque.
    let mut r = Rig::new();
    r.trusted = false;
    r.cfg.direction = -r.cfg.direction;
    r.cfg.counts_per_metre = -r.cfg.counts_per_metre;
    // The rig counts with the configured scale: −1 is the true encoder.
    r.plant = Some(plant(-1.0));
    r.configure();
    r.run(200);
    assert_eq!(r.node.fault(), FaultCode::WrongDirection);
    assert!(!r.powered);
    // A plant that does not move (no gravity, no torque): no verdict once
    // the wait for its first motion is over.
    let mut r = Rig::new();
    r.trusted = false;
    r.cfg.gravity = 0.0;
    r.parked = 0.3;
    r.configure();
    r.run(200);
    assert!(r.node.drive.is_checking(), "waiting for the first motion");
    r.run(400);
    assert_eq!(r.node.state(), State::Idle);
    assert!(!r.node.drive.is_verified() && !r.node.drive.is_checking());
}
