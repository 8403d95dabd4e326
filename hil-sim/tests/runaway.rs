//! A reversed motor on the in-process virtual machine: axis 1's torque
//! acts against the sign its drive is configured with, so once the brakes
//! release the loop holding the axis at rest is positive feedback. The
//! following-error supervision at rest must end it in Fault within a
//! bounded time and distance.

use nalgebra::Vector3;
use triquint_link::{DriveConfigs, Session, SessionOptions};
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{FaultCode, State};
use triquint_shared::{Limits, Robot};
use triquint_sim::host_port::SimPort;
use triquint_sim::{Sim, SimConfig};

/// Bounds from the brakes' release to the Fault.
const MAX_FAULT_S: f64 = 0.050;
const MAX_TRAVEL_M: f64 = 2.0e-3;

fn machine(direction: f64) -> Sim {
    let robot = Robot::default();
    let r = Vector3::new(-0.09, 0.09, 0.68);
    let q0 = Pose::from_cartesian(&robot.model::<f64>(), r).unwrap().q;
    let mut cfg = SimConfig {
        record_every: 1000,
        ..SimConfig::default()
    };
    cfg.motor_direction[0] = direction;
    Sim::new(&robot, q0, cfg)
}

/// Configures the drives (direction +1) over the bus, 1 ms steps; from
/// the brakes' release on, returns (seconds, joint travel of axis 1) at
/// node 1's first Fault, or None within `s` seconds.
fn configure_and_watch(sim: &mut Sim, s: f64) -> Option<(f64, f64)> {
    let configs = DriveConfigs::for_limits(
        &Robot::default(),
        &Limits::default(),
        &DriveSettings::default(),
    )
    .nodes;
    let mut session = Session::configure(configs, SessionOptions::default());
    let mut done = false;
    let mut released: Option<(u64, f64)> = None;
    let end = sim.now_ns() + (s * 1e9) as u64;
    while sim.now_ns() < end {
        if !done {
            done = session
                .poll(&mut SimPort { sim, tx_queue: 32 })
                .unwrap()
                .is_some();
        }
        let t = sim.now_ns() + 1_000_000;
        sim.run_until(t).unwrap();
        let q = sim.plant.q()[0];
        if released.is_none() && sim.nodes.iter().all(|n| n.enabled()) {
            released = Some((sim.now_ns(), q));
        }
        if sim.nodes[0].node.state() == State::Fault {
            let (t0, q0) = released.expect("a fault before the brakes released");
            return Some(((sim.now_ns() - t0) as f64 * 1e-9, (q - q0).abs()));
        }
    }
    None
}

#[test]
fn a_reversed_motor_ends_in_following_error_within_bounds() {
    let mut sim = machine(-1.0);
    let (t, d) = configure_and_watch(&mut sim, 2.0).expect("no fault within 2 s");
    let first = sim.faults()[0];
    assert_eq!((first.node, first.code), (1, FaultCode::FollowingError));
    println!(
        "reversed motor: Fault after {:.1} ms, {:.3} mm",
        t * 1e3,
        d * 1e3
    );
    assert!(t < MAX_FAULT_S, "{t} s");
    assert!(d < MAX_TRAVEL_M, "{d} m");
}

#[test]
fn a_correctly_wired_machine_rests_without_a_fault() {
    let mut sim = machine(1.0);
    assert_eq!(configure_and_watch(&mut sim, 2.0), None);
    assert!(sim.faults().is_empty(), "{:?}", sim.faults());
    assert!(sim.nodes.iter().all(|n| n.node.state() == State::Idle));
}

/// Axis 1's encoder scale 32× off from its drive's `counts_per_metre`.
/// Too many counts per metre: the drive sees its motion 32× magnified, a
/// 32× loop gain, and faults within the runaway bounds. Too few: the drive
/// sees 1/32 of it, so its 1 mm bound is 32 mm of real sag under gravity
/// before the Fault; only a check at enable (the axis moves as told) would
/// catch it sooner.
#[test]
fn a_wrong_encoder_scale_ends_in_following_error() {
    for (k, max_s, max_m) in [(32.0, MAX_FAULT_S, MAX_TRAVEL_M), (1.0 / 32.0, 2.0, 0.035)] {
        let robot = Robot::default();
        let r = Vector3::new(-0.09, 0.09, 0.68);
        let q0 = Pose::from_cartesian(&robot.model::<f64>(), r).unwrap().q;
        let mut cfg = SimConfig {
            record_every: 1000,
            ..SimConfig::default()
        };
        cfg.counts_per_metre[0] *= k;
        let mut sim = Sim::new(&robot, q0, cfg);
        let (t, d) = configure_and_watch(&mut sim, 3.0).expect("no fault within 3 s");
        let first = sim.faults()[0];
        assert_eq!((first.node, first.code), (1, FaultCode::FollowingError));
        println!(
            "encoder scale ×{k}: Fault after {:.1} ms, {:.3} mm",
            t * 1e3,
            d * 1e3
        );
        assert!(t < max_s, "×{k}: {t} s");
        assert!(d < max_m, "×{k}: {d} m");
    }
}
