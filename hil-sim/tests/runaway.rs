//! Axis 1 wired or described wrongly on the in-process virtual machine:
//! from the brakes' release on, the supervision at rest and the enable
//! check must end it in Fault, naming the axis (node 1) and what is wrong,
//! within a bounded time and distance, with the reaction the fault table
//! gives (docs/protocol.md, "Fault reactions"). The machine has no brakes.

use nalgebra::Vector3;
use triquint_link::{DriveConfigs, Session, SessionOptions};
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{FaultCode, State};
use triquint_shared::{Limits, Robot};
use triquint_sim::host_port::SimPort;
use triquint_sim::{Sim, SimConfig};

/// Bounds from the brakes' release to the Fault when the loop is
/// positive feedback or its gain 32× too high (following error at rest).
const RUNAWAY_S: f64 = 0.050;
const RUNAWAY_M: f64 = 2.0e-3;
/// Bounds when the loop is sound but wrong (the enable check's window).
const CHECK_S: f64 = 0.100;
const CHECK_M: f64 = 1.0e-3;

/// What is wrong with axis 1: the machine (the simulated wiring) or its
/// description (the machine file the drives are configured from).
#[derive(Clone, Copy, Debug)]
struct Case {
    name: &'static str,
    /// The motor's torque on the slider, and the encoder's counts per
    /// metre, times these on the machine.
    motor: f64,
    encoder: f64,
    /// The machine file's `direction` flipped, its counts per metre times this.
    file_flipped: bool,
    file_scale: f64,
    want: FaultCode,
    max_s: f64,
    max_m: f64,
}

const fn case(name: &'static str, want: FaultCode, max_s: f64, max_m: f64) -> Case {
    Case {
        name,
        motor: 1.0,
        encoder: 1.0,
        file_flipped: false,
        file_scale: 1.0,
        want,
        max_s,
        max_m,
    }
}

fn machine(c: &Case) -> Sim {
    let robot = Robot::default();
    let r = Vector3::new(-0.09, 0.09, 0.68);
    let q0 = Pose::from_cartesian(&robot.model::<f64>(), r).unwrap().q;
    let mut cfg = SimConfig {
        record_every: 1000,
        ..SimConfig::default()
    };
    cfg.motor_direction[0] *= c.motor;
    cfg.counts_per_metre[0] *= c.encoder;
    Sim::new(&robot, q0, cfg)
}

fn settings(c: &Case) -> DriveSettings {
    let mut s = DriveSettings::default();
    if c.file_flipped {
        // As the machine file derives them: the encoder's sign follows the direction.
        s.direction[0] = -s.direction[0];
        s.counts_per_metre[0] = -s.counts_per_metre[0];
    }
    s.counts_per_metre[0] *= c.file_scale;
    s
}

/// Configures the drives over the bus, 1 ms steps; from the brakes'
/// release on, returns (seconds, joint travel of axis 1) at node 1's
/// first Fault, or None within `s` seconds.
fn configure_and_watch(sim: &mut Sim, settings: &DriveSettings, s: f64) -> Option<(f64, f64)> {
    let configs = DriveConfigs::for_limits(&Robot::default(), &Limits::default(), settings).nodes;
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
fn a_correct_machine_passes_the_enable_check_and_rests() {
    let c = case("correct", FaultCode::None, 0.0, 0.0);
    let mut sim = machine(&c);
    assert_eq!(configure_and_watch(&mut sim, &settings(&c), 2.0), None);
    assert!(sim.faults().is_empty(), "{:?}", sim.faults());
    for n in &sim.nodes {
        let d = &n.node.drive;
        assert_eq!(n.node.state(), State::Idle);
        assert!(d.is_verified(), "node {}", d.node_id());
        let (g, b) = (d.stats.check_gain_ratio, d.stats.check_load_ratio);
        println!(
            "node {}: gain {g:.3}, load {b:.3} of the model's",
            d.node_id()
        );
        assert!((0.25..4.0).contains(&g) && b > 0.25, "{g} {b}");
    }
}

/// Every case: the right code from node 1 within its bounds, the other
/// nodes stopped by its Emergency only if they had to, and the reaction
/// the fault table gives (no brakes: torque off where the loop's sign is
/// unknown or wrong, an open-loop hold where only its gain is).
#[test]
fn a_wrong_axis_ends_in_fault_within_bounds() {
    let wrong = |c: Case, f: &dyn Fn(&mut Case)| {
        let mut c = c;
        f(&mut c);
        c
    };
    use FaultCode::{FollowingError, WrongDirection, WrongScale};
    let cases = [
        wrong(
            case("motor reversed", FollowingError, RUNAWAY_S, RUNAWAY_M),
            &|c| c.motor = -1.0,
        ),
        wrong(
            case("encoder reversed", FollowingError, RUNAWAY_S, RUNAWAY_M),
            &|c| c.encoder = -1.0,
        ),
        wrong(
            case("file: direction flipped", WrongDirection, CHECK_S, CHECK_M),
            &|c| c.file_flipped = true,
        ),
        wrong(
            case("encoder ×32", FollowingError, RUNAWAY_S, RUNAWAY_M),
            &|c| c.encoder = 32.0,
        ),
        wrong(case("encoder ×1/32", WrongScale, CHECK_S, CHECK_M), &|c| {
            c.encoder = 1.0 / 32.0
        }),
        wrong(
            case("file: scale ×1/32", FollowingError, RUNAWAY_S, RUNAWAY_M),
            &|c| c.file_scale = 1.0 / 32.0,
        ),
        wrong(
            case("file: scale ×32", WrongScale, CHECK_S, CHECK_M),
            &|c| c.file_scale = 32.0,
        ),
    ];
    for c in cases {
        let mut sim = machine(&c);
        let (t, d) = configure_and_watch(&mut sim, &settings(&c), 2.0)
            .unwrap_or_else(|| panic!("{}: no fault within 2 s", c.name));
        let first = sim.faults()[0];
        // The power stage goes off at the tick after the fault's.
        let t_next = sim.now_ns() + 2_000_000;
        sim.run_until(t_next).unwrap();
        let drive = &sim.nodes[0].node.drive;
        println!(
            "{}: {:?} after {:.1} ms, {:.3} mm; gain {:.3}, load {:.3} of the model's",
            c.name,
            first.code,
            t * 1e3,
            d * 1e3,
            drive.stats.check_gain_ratio,
            drive.stats.check_load_ratio,
        );
        assert_eq!((first.node, first.code), (1, c.want), "{}", c.name);
        assert!(t < c.max_s, "{}: {t} s", c.name);
        assert!(d < c.max_m, "{}: {d} m", c.name);
        let open_loop = c.want == WrongScale;
        assert_eq!(drive.is_torque_off(), !open_loop, "{}", c.name);
        assert!(!sim.nodes[0].enabled() || open_loop, "{}", c.name);
    }
}

/// A wrong encoder scale with the right sign and no brake: the open-loop
/// hold on the load the check measured lets the axis sink far slower than
/// torque off does (a reversed encoder's reaction, on the same machine).
#[test]
fn a_wrong_scale_without_a_brake_holds_open_loop() {
    let sink_in_1s = |c: Case| {
        let mut sim = machine(&c);
        configure_and_watch(&mut sim, &settings(&c), 1.0).expect("a fault");
        let q0 = sim.plant.q()[0];
        let t = sim.now_ns() + 1_000_000_000;
        sim.run_until(t).unwrap();
        (
            q0 - sim.plant.q()[0],
            sim.nodes[0].node.drive.is_torque_off(),
        )
    };
    let base = case("", FaultCode::None, 0.0, 0.0);
    let (held, off) = sink_in_1s(Case {
        encoder: 1.0 / 32.0,
        ..base
    });
    assert!(!off);
    let (fell, off) = sink_in_1s(Case {
        encoder: -1.0,
        ..base
    });
    assert!(off);
    println!(
        "1 s after the fault: open-loop hold sank {:.2} mm, torque off {:.2} mm",
        held * 1e3,
        fell * 1e3
    );
    assert!(held.abs() < 0.25 * fell, "{held} m, {fell} m");
}
