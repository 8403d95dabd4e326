//! Homing on the in-process virtual machine: drives powered on unhomed
//! (seeded encoder offsets), switches on the guideways at the `[homing]`
//! heights, the host's link session and Home commands over the bus.

use std::time::Instant;

use nalgebra::Vector3;
use triquint_link::session::AXES;
use triquint_link::{DriveConfigs, Listener, Session, SessionOptions, UploadError};
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::config::{DriveSettings, HomingSettings};
use triquint_shared::protocol::{Command, CommandCode, FaultCode, State};
use triquint_shared::{Limits, Robot};
use triquint_sim::host_port::SimPort;
use triquint_sim::sim::SwitchMode;
use triquint_sim::{Sim, SimConfig, testplan};

const CPM: f64 = 131_072.0 / 0.010;

fn machine(modes: [SwitchMode; 3]) -> Sim {
    machine_at(Vector3::new(-0.09, 0.09, 0.68), modes)
}

fn machine_at(r: Vector3<f64>, modes: [SwitchMode; 3]) -> Sim {
    let robot = Robot::default();
    let q0 = Pose::from_cartesian(&robot.model::<f64>(), r).unwrap().q;
    let cfg = SimConfig {
        record_every: 1000,
        ..SimConfig::default()
    };
    let mut sim = Sim::new(&robot, q0, cfg);
    sim.power_on_unhomed(42, &HomingSettings::default(), modes);
    sim
}

fn settings() -> DriveSettings {
    DriveSettings::default()
}

/// Runs a session to its end in simulated time (1 ms steps, at most `s` seconds).
fn drive(sim: &mut Sim, session: &mut Session, s: f64) -> Result<(), UploadError> {
    let end = sim.now_ns() + (s * 1e9) as u64;
    while sim.now_ns() < end {
        let r = session.poll(&mut SimPort { sim, tx_queue: 32 })?;
        if r.is_some() {
            return Ok(());
        }
        let t = sim.now_ns() + 1_000_000;
        sim.run_until(t).unwrap();
    }
    panic!("session did not end within {s} s");
}

fn configure(sim: &mut Sim) {
    let configs =
        DriveConfigs::for_limits(&Robot::default(), &Limits::default(), &settings()).nodes;
    let mut s = Session::configure(configs, SessionOptions::default());
    drive(sim, &mut s, 10.0).unwrap();
}

fn home_all(sim: &mut Sim) {
    for id in 1..=AXES as u8 {
        sim.host_send(
            Command {
                command: CommandCode::Home as u8,
                token: 0x40 + id,
                arg: 0,
                arg2: 0,
            }
            .to_frame(id),
        );
    }
}

/// Runs until no node is Homing (at most `s` seconds); returns the time taken.
fn until_homed(sim: &mut Sim, s: f64) -> f64 {
    let t0 = sim.now_ns();
    let t = sim.now_ns() + 5_000_000;
    sim.run_until(t).unwrap();
    while sim.nodes.iter().any(|n| n.node.state() == State::Homing) {
        assert!(
            sim.now_ns() - t0 < (s * 1e9) as u64,
            "still homing after {s} s"
        );
        let t = sim.now_ns() + 10_000_000;
        sim.run_until(t).unwrap();
    }
    (sim.now_ns() - t0) as f64 * 1e-9
}

fn status(sim: &mut Sim) -> triquint_link::MachineStatus {
    let mut l = Listener::new([1, 2, 3]);
    let t = sim.now_ns() + 300_000_000;
    sim.run_until(t).unwrap();
    while let Some(d) = sim.host_receive() {
        l.take(&triquint_link::Received {
            frame: d.frame,
            t_us: d.t_ns / 1000,
            own: d.own,
        });
    }
    l.status(&Robot::default())
}

#[test]
fn an_unhomed_machine_refuses_motion_homes_and_knows_its_position() {
    let wall = Instant::now();
    let mut sim = machine([SwitchMode::Working; 3]);
    configure(&mut sim);
    let s = status(&mut sim);
    assert!(s.all_heard);
    assert!(s.nodes.iter().all(|n| !n.homed && n.homing == "not homed"));
    assert!(s.nodes.iter().all(|n| n.joint_position_mm.is_none()));
    assert_eq!(s.platform_mm, None);

    // Upload refused with NotHomed; the nodes stay Idle without a fault.
    let plan = testplan::paper_case1().unwrap();
    let configs = DriveConfigs::for_plan(&plan, &settings()).unwrap().nodes;
    let mut up = Session::new(&plan, configs, SessionOptions::default()).unwrap();
    match drive(&mut sim, &mut up, 10.0) {
        Err(UploadError::NotHomed {
            node: triquint_link::Drive { axis: 1, node: 1 },
        }) => {}
        other => panic!("{other:?}"),
    }
    let t = sim.now_ns() + 200_000_000;
    sim.run_until(t).unwrap();
    for n in &sim.nodes {
        assert_eq!(
            (n.node.state(), n.node.fault()),
            (State::Idle, FaultCode::None)
        );
    }

    // Home: all three together.
    home_all(&mut sim);
    let took = until_homed(&mut sim, 35.0);
    eprintln!(
        "homed in {took:.2} s of machine time ({:.1} s wall)",
        wall.elapsed().as_secs_f64()
    );
    assert!(took < 30.0, "{took}");
    for (i, n) in sim.nodes.iter().enumerate() {
        assert_eq!(n.node.state(), State::Idle, "axis {}", i + 1);
        assert!(n.node.is_homed());
        // The homed zero (the encoder count at joint position 0) against
        // the simulator's unknown offset, and the position it reports
        // (f32 metres) against the true one.
        let zero = n.node.home_offset() - n.enc_offset;
        let err = (f64::from(n.node.stats.q) - sim.plant.q()[i]) * CPM;
        eprintln!(
            "axis {}: homed zero off by {zero} counts, position {err:+.3} counts",
            i + 1
        );
        assert!(zero.abs() <= 1, "axis {}: zero {zero} counts", i + 1);
        assert!(err.abs() <= 2.0, "axis {}: {err} counts", i + 1);
        // Backed off below the switch.
        let below = HomingSettings::default().switch_height[i] - sim.plant.q()[i];
        assert!(below > 0.0 && below < 0.012, "axis {}: {below}", i + 1);
    }
    let s = status(&mut sim);
    assert!(s.nodes.iter().all(|n| n.homed && n.homing == "homed"));
    let p = s.platform_mm.expect("platform position once homed");
    assert!(p[2] > 700.0, "{p:?}");

    // Now an upload is refused for distance, with each axis's distance.
    let mut up = Session::new(&plan, configs, SessionOptions::default()).unwrap();
    match drive(&mut sim, &mut up, 20.0) {
        Err(e @ UploadError::ArmTooFar { .. }) => {
            let UploadError::ArmTooFar {
                distances_mm,
                start_mm,
                ..
            } = e
            else {
                unreachable!()
            };
            assert!(
                distances_mm
                    .iter()
                    .all(|d| d.is_some_and(|d| d.abs() > 1.0)),
                "{distances_mm:?}"
            );
            assert!((start_mm[0] + 90.0).abs() < 1e-6);
            assert!(e.to_string().contains("axis 1"), "{e}");
        }
        other => panic!("{other:?}"),
    }
    let t = sim.now_ns() + 200_000_000;
    sim.run_until(t).unwrap();
    for n in &sim.nodes {
        assert_eq!(
            (n.node.state(), n.node.fault()),
            (State::Idle, FaultCode::None)
        );
    }
}

#[test]
fn stuck_and_dead_switches_end_in_their_faults() {
    for (modes, axis, code) in [
        (
            [SwitchMode::Working, SwitchMode::Stuck, SwitchMode::Working],
            1,
            FaultCode::HomeSwitchActive,
        ),
        (
            [SwitchMode::Working, SwitchMode::Working, SwitchMode::Dead],
            2,
            FaultCode::HomeSwitchNeverTriggered,
        ),
    ] {
        let mut sim = machine(modes);
        configure(&mut sim);
        home_all(&mut sim);
        until_homed(&mut sim, 40.0);
        let n = &sim.nodes[axis];
        assert_eq!((n.node.state(), n.node.fault()), (State::Fault, code));
        let s = status(&mut sim);
        assert_eq!(s.nodes[axis].fault.name, code.name());
        assert_eq!(s.nodes[axis].homing, "failed");
    }
}

#[test]
fn homing_from_the_lowest_corner_of_the_workspace_takes_under_30_s() {
    // Slider 3 at 104 mm, the lowest of the paper workspace's corners
    // (x, y ±90 mm, z 540 mm): 316 mm to its switch.
    let mut sim = machine_at(Vector3::new(-0.09, -0.09, 0.54), [SwitchMode::Working; 3]);
    configure(&mut sim);
    home_all(&mut sim);
    let took = until_homed(&mut sim, 35.0);
    eprintln!("homed from the lowest corner in {took:.2} s of machine time");
    assert!(
        sim.nodes
            .iter()
            .all(|n| n.node.is_homed() && n.node.state() == State::Idle)
    );
    assert!(took < 30.0, "{took}");
}
