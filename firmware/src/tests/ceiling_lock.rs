//! The ceiling lock on one node driven by frames: after a commit, a host's
//! configuration may tighten the ceilings and the travel but not widen
//! them, except in the maintenance window `UnlockCeilings` opens; a
//! board's own kept configuration is taken as it is.

extern crate std;

use triquint_shared::protocol::contract::MAINTENANCE_WINDOW_US;
use triquint_shared::protocol::{
    Command, CommandCode, DriveConfig, FaultCode, PARAMS, State, config_write_frame,
};

use super::{Rig, segments};
use crate::hal::RxFrame;

/// A rig configured with ceilings well above its limits.
fn configured() -> Rig {
    let mut r = Rig::new();
    (r.cfg.ceiling_velocity, r.cfg.ceiling_acceleration) = (10.0, 100.0);
    (r.cfg.ceiling_jerk, r.cfg.ceiling_torque) = (500.0, 10.0);
    r.configure();
    r.run(10);
    r
}

/// The answer (result, value) to a command.
fn ack(r: &mut Rig, c: CommandCode, arg: u32) -> (u8, u32) {
    r.command_to(c, arg, 2).expect("an answer")
}

/// A host writes `cfg` and commits it: the answer (result, value).
fn commit(r: &mut Rig, cfg: &DriveConfig) -> (u8, u32) {
    for (k, v) in cfg.to_values().iter().enumerate() {
        r.rx(config_write_frame(2, k as u8, *v));
    }
    ack(r, CommandCode::ConfigCommit, cfg.crc())
}

/// The board replays `cfg` from its store (`Receiver::on_kept_frame`).
fn replay_kept(r: &mut Rig, cfg: &DriveConfig) {
    let commit = Command {
        command: CommandCode::ConfigCommit as u8,
        token: 0,
        arg: cfg.crc(),
        arg2: 0,
    }
    .to_frame(0);
    let frames = cfg
        .to_values()
        .into_iter()
        .enumerate()
        .map(|(k, v)| config_write_frame(2, k as u8, v))
        .chain([commit]);
    for frame in frames {
        let rx = RxFrame {
            frame,
            timestamp_us: r.t,
        };
        let snapshot = r.node.drive.snapshot();
        if let Some(item) = r.node.receiver.on_kept_frame(&rx, snapshot) {
            r.node.drive.take(&item);
        }
    }
}

fn locked(index: u32) -> (u8, u32) {
    (FaultCode::CeilingsLocked as u8, index)
}

/// A change to a configuration.
type Change = fn(&mut DriveConfig);

/// Each locked bound, widened a little.
fn widened() -> [(Change, &'static str); 6] {
    [
        (|c| c.ceiling_velocity *= 1.5, "ceiling_velocity"),
        (|c| c.ceiling_acceleration *= 1.01, "ceiling_acceleration"),
        (|c| c.ceiling_jerk += 1.0, "ceiling_jerk"),
        (|c| c.ceiling_torque *= 2.0, "ceiling_torque"),
        (|c| c.soft_limit_min -= 0.01, "soft_limit_min"),
        (|c| c.soft_limit_max += 0.01, "soft_limit_max"),
    ]
}

fn index(name: &str) -> u32 {
    PARAMS.iter().position(|p| p.name == name).unwrap() as u32
}

#[test]
fn a_host_cannot_widen_a_ceiling_or_the_travel_after_a_commit() {
    for (widen, name) in widened() {
        let mut r = configured();
        let before = r.node.config_crc();
        let mut wide = r.cfg;
        widen(&mut wide);
        wide.validate().unwrap();
        assert_eq!(commit(&mut r, &wide), locked(index(name)), "{name}");
        // The drive runs on with what it held, and says so again on a resend.
        assert_eq!(r.node.config_crc(), before, "{name}");
        assert_eq!(r.node.config().unwrap(), r.cfg);
        assert_eq!(commit(&mut r, &wide), locked(index(name)), "{name}");
        assert_eq!(r.node.state(), State::Idle);
    }
}

#[test]
fn a_host_may_tighten_them_and_not_widen_them_back() {
    let mut r = configured();
    let mut tight = r.cfg;
    tight.ceiling_velocity = 2.0;
    tight.ceiling_torque = tight.max_torque;
    tight.soft_limit_min += 0.02;
    tight.soft_limit_max -= 0.02;
    // Not locked: a gain, the stop time.
    tight.kp *= 1.5;
    tight.stop_time *= 2.0;
    assert_eq!(commit(&mut r, &tight), (0, tight.crc()));
    assert_eq!(r.node.config_crc(), tight.crc());
    // The same again, and another that changes nothing locked: taken.
    assert_eq!(commit(&mut r, &tight), (0, tight.crc()));
    let mut gains = tight;
    gains.kd *= 1.1;
    assert_eq!(commit(&mut r, &gains), (0, gains.crc()));
    // Back to the first configuration: a widening now.
    let first = r.cfg;
    assert_eq!(commit(&mut r, &first), locked(index("soft_limit_min")));
    assert_eq!(r.node.config_crc(), gains.crc());
}

#[test]
fn the_maintenance_window_lets_one_commit_widen_them() {
    let mut r = configured();
    let crc = r.node.config_crc();
    let mut wide = r.cfg;
    wide.ceiling_velocity *= 2.0;
    wide.soft_limit_max += 0.05;
    // The key is the running configuration's CRC.
    let mismatch = (FaultCode::ConfigMismatch as u8, 0);
    assert_eq!(ack(&mut r, CommandCode::UnlockCeilings, crc ^ 1), mismatch);
    assert_eq!(commit(&mut r, &wide), locked(index("soft_limit_max")));
    let window_ms = (MAINTENANCE_WINDOW_US / 1000) as u32;
    assert_eq!(
        ack(&mut r, CommandCode::UnlockCeilings, crc),
        (0, window_ms)
    );
    // ReadConfig inside the window leaves it open.
    assert_eq!(ack(&mut r, CommandCode::ReadConfig, 0).0, 0);
    assert_eq!(commit(&mut r, &wide), (0, wide.crc()));
    assert_eq!(r.node.config().unwrap(), wide);
    // The window closed with that commit.
    let mut wider = wide;
    wider.ceiling_jerk *= 2.0;
    assert_eq!(commit(&mut r, &wider), locked(index("ceiling_jerk")));
}

#[test]
fn the_window_closes_on_time_and_on_any_other_command() {
    let mut r = configured();
    let crc = r.node.config_crc();
    let mut wide = r.cfg;
    wide.ceiling_torque *= 2.0;
    let torque = locked(index("ceiling_torque"));
    // Timed out.
    assert_eq!(ack(&mut r, CommandCode::UnlockCeilings, crc).0, 0);
    r.t += MAINTENANCE_WINDOW_US;
    assert_eq!(commit(&mut r, &wide), torque);
    // Closed by a command that could lead to motion, or any other.
    for other in [CommandCode::Reset, CommandCode::Resume, CommandCode::Arm] {
        assert_eq!(ack(&mut r, CommandCode::UnlockCeilings, crc).0, 0);
        ack(&mut r, other, 0);
        assert_eq!(commit(&mut r, &wide), torque, "{other:?}");
    }
    // Not opened outside Idle (Loaded: a segment queued).
    let segs = segments(2, 0.3);
    r.parked = segs[0].normalised_f32()[1][0];
    r.send_segment(&segs[0]);
    assert_eq!(r.node.state(), State::Loaded);
    let wrong = (FaultCode::WrongState as u8, 0);
    assert_eq!(ack(&mut r, CommandCode::UnlockCeilings, crc), wrong);
}

#[test]
fn the_boards_kept_configuration_is_not_a_host_widening() {
    // At start the board replays what it kept, ceilings and all.
    let mut r = Rig::new();
    r.cfg.ceiling_velocity = 10.0;
    let kept = r.cfg;
    replay_kept(&mut r, &kept);
    assert_eq!(r.node.config_crc(), kept.crc());
    // A host then widens: refused.
    let mut wide = kept;
    wide.ceiling_velocity = 20.0;
    assert_eq!(commit(&mut r, &wide), locked(index("ceiling_velocity")));
    // A host tightens; the board replaying its kept (wider) one is taken.
    let mut tight = kept;
    tight.ceiling_velocity = 5.0;
    assert_eq!(commit(&mut r, &tight).0, 0);
    replay_kept(&mut r, &kept);
    assert_eq!(r.node.config_crc(), kept.crc());
    // A host's commit of the same values is not.
    assert_eq!(commit(&mut r, &tight).0, 0);
    assert_eq!(commit(&mut r, &kept), locked(index("ceiling_velocity")));
}

#[test]
fn refused_commits_never_push_the_running_configuration_out_of_the_receive_side() {
    let mut r = configured();
    let crc = r.node.config_crc();
    // Two different widened configurations refused in a row.
    for f in [2.0, 3.0] {
        let mut wide = r.cfg;
        wide.ceiling_velocity *= f;
        assert_eq!(commit(&mut r, &wide).0, FaultCode::CeilingsLocked as u8);
    }
    assert_eq!(r.node.config_crc(), crc);
    // Segments are still checked against the running one and accepted.
    let segs = segments(2, 0.3);
    r.parked = segs[0].normalised_f32()[1][0];
    assert_eq!(
        r.send_segment(&segs[0]).map(|a| a.0),
        Some(triquint_shared::protocol::Reject::Accepted)
    );
}

/// ReadConfig answers with every written value, in order, over as many
/// ticks as the outbox needs, and a command sent meanwhile is answered.
#[test]
fn a_read_config_answer_goes_out_whole_over_ticks() {
    use triquint_shared::protocol::{Msg, PARAM_COUNT, decode};
    let mut r = configured();
    let n = r.sent.len();
    assert_eq!(ack(&mut r, CommandCode::ReadConfig, 0).0, 0);
    r.run(2);
    // A command in the middle of the answer still gets its own.
    assert_eq!(ack(&mut r, CommandCode::Reset, 0).0, 0);
    r.run(20);
    let values: std::vec::Vec<(u8, f32)> = r.sent[n..]
        .iter()
        .filter_map(|f| match decode(f) {
            Ok((Msg::ConfigValue { index, value }, 2)) => Some((index, value)),
            _ => None,
        })
        .collect();
    let want = r.cfg.to_values();
    assert_eq!(values.len(), PARAM_COUNT, "one frame a parameter");
    for (k, (index, value)) in values.iter().enumerate() {
        assert_eq!((*index as usize, value.to_bits()), (k, want[k].to_bits()));
    }
    assert_eq!(r.node.drive.dropped_tx(), 0);
}
