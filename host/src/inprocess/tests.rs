//! End-to-end tests: the host session uploads plans over the in-process bus
//! to three firmware nodes driving the Lagrangian plant.

use triquint_firmware::QUEUE_CAPACITY;
use triquint_shared::Robot;
use triquint_shared::plan::Plan;
use triquint_shared::protocol::compact::compact_parts;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{Command, CommandCode, FaultCode, config_write_frame};
use triquint_sim::{Sim, SimConfig, testplan};

use triquint_link::{DriveConfigs, Session, SessionOptions, UploadError};
use triquint_sim::host_port::SimPort;

use super::simulate::{SimReport, SimulateError, SimulateOptions, simulate, start_skew_ns};

fn run(plan: &Plan, f: impl FnOnce(&mut SimulateOptions)) -> Result<SimReport, SimulateError> {
    let mut o = SimulateOptions::default();
    f(&mut o);
    simulate(plan, &o)
}

fn assert_clean(r: &SimReport, what: &str) {
    assert!(
        r.run.completed,
        "{what}: not completed, faults {:?}",
        r.faults_on_nodes
    );
    assert!(
        r.faults.is_empty() && r.faults_on_nodes.is_empty(),
        "{what}: {:?}",
        r.faults
    );
    assert!(
        r.start_skew_ns.is_some_and(|s| s <= r.tick_ns),
        "{what}: axes started {:?} ns apart (tick {} ns)",
        r.start_skew_ns,
        r.tick_ns
    );
}

#[test]
fn paper_cases_complete_on_classic_and_fd() {
    for (name, plan) in [
        ("case I", testplan::paper_case1().unwrap()),
        ("case II", testplan::paper_case2().unwrap()),
    ] {
        for fd in [false, true] {
            let r = run(&plan, |o| o.fd = fd).unwrap();
            let what = format!("{name} fd={fd}");
            assert_clean(&r, &what);
            // The first segment in full, most others compact
            // continuations (one after a much shorter segment goes in
            // full: Case II has several).
            let full = if fd { 2 } else { 20 };
            let compact = compact_parts(0, fd) as u64;
            assert_eq!(r.retransmits, 0, "{what}");
            assert_eq!(r.segments_sent, plan.segments.len() as u64, "{what}");
            assert!(
                2 * r.compact_sent >= r.segments_sent,
                "{what}: {} compact",
                r.compact_sent
            );
            assert_eq!(
                r.run.segment_frames,
                full * (r.segments_sent - r.compact_sent) + compact * r.compact_sent,
                "{what}"
            );
            for j in 0..3 {
                assert!(
                    r.run.rms_error_m[j] < 5e-6,
                    "{what}: {:?}",
                    r.run.tracking()
                );
                assert!(
                    r.run.max_error_m[j] < 50e-6,
                    "{what}: {:?}",
                    r.run.tracking()
                );
            }
            assert!(
                r.run.bus_load > 0.0 && r.run.bus_load < 0.2,
                "{what}: load {}",
                r.run.bus_load
            );
        }
    }
}

#[test]
fn feedforward_cuts_case2_tracking_error_at_least_threefold() {
    let plan = testplan::paper_case2().unwrap();
    let ff = run(&plan, |_| {}).unwrap();
    let fb = run(&plan, |o| o.feedforward = false).unwrap();
    assert_clean(&ff, "ff");
    assert_clean(&fb, "no ff");
    for j in 0..3 {
        let ratio = fb.run.rms_error_m[j] / ff.run.rms_error_m[j];
        eprintln!(
            "axis {}: RMS {:.3} µm with FF, {:.3} µm without, ratio {ratio:.1}",
            j + 1,
            ff.run.rms_error_m[j] * 1e6,
            fb.run.rms_error_m[j] * 1e6
        );
        assert!(ratio >= 3.0, "axis {}: ratio {ratio}", j + 1);
    }
}

#[test]
fn stress_spiral_completes_on_classic_can_with_flow_control() {
    let plan = testplan::spiral(
        testplan::SPIRAL_POINTS,
        testplan::SPIRAL_TURNS,
        testplan::SPIRAL_TIME,
    )
    .unwrap();
    assert!(plan.segments.len() >= 3 * QUEUE_CAPACITY);
    let r = run(&plan, |_| {}).unwrap();
    assert_clean(&r, "spiral");
    eprintln!(
        "spiral: {} segments, bus load {:.4} (segments {:.4}), {} frames, {} retransmissions",
        plan.segments.len(),
        r.run.bus_load,
        r.run.segment_bus_load,
        r.run.frames,
        r.retransmits
    );
}

#[test]
fn lost_frames_are_retransmitted() {
    let plan = testplan::paper_case1().unwrap();
    let r = run(&plan, |o| {
        o.sim.bus.rx_drop = 0.01;
        o.sim.bus.seed = 5;
    })
    .unwrap();
    assert_clean(&r, "lossy bus");
    assert!(r.retransmits > 0, "no retransmission on a lossy bus");
}

#[test]
fn stalled_host_underruns_and_every_node_stops_on_the_path() {
    let plan = testplan::paper_case2().unwrap();
    let r = run(&plan, |o| o.session.stall_after = Some(4)).unwrap();
    assert!(!r.run.completed);
    let first = r.faults_on_nodes.first().expect("a fault");
    assert_eq!(first.code, FaultCode::Underrun);
    // Every node detected the underrun itself (same buffered path).
    let underruns = r
        .faults_on_nodes
        .iter()
        .filter(|f| f.code == FaultCode::Underrun)
        .count();
    assert!(underruns >= 1);
    // The stop is jerk-limited: within the limit, or within the plan's own
    // jerk plus half the limit when the plan already uses more than half.
    let plan_jerk = testplan::sampled_max_abs(&plan)
        .unwrap()
        .jerk
        .iter()
        .fold(0.0f64, |a, b| a.max(*b));
    let lim = plan.limits.jerk;
    let stop_jerk = r.run.max_stop_jerk.iter().copied().fold(0.0, f64::max);
    eprintln!(
        "underrun stop: plan jerk {plan_jerk:.3}, stop time {:.3} s, max jerk while stopping {stop_jerk:.3} m/s³",
        r.run.stop_ramp_s
    );
    assert!(stop_jerk > 0.0);
    assert!(stop_jerk <= lim.max(plan_jerk + 0.5 * lim) * 1.001);
    // At the end the machine is at rest, close to the path: the reference
    // held over the last 5 ms (the stop ended), the axes still within
    // 1 µm over them. (The stop's last 20 ms still move a few µm: σ ends
    // at rest as (1 − u)², not the quintic's (1 − u)³.)
    let last = r.samples.last().unwrap();
    let prev = &r.samples[r.samples.len() - 5];
    for j in 0..3 {
        assert_eq!(last.reference[j], prev.reference[j], "axis {j}'s reference");
        assert!(
            (last.q[j] - prev.q[j]).abs() < 1e-6,
            "axis {j} still moving"
        );
        assert!((last.q[j] - last.reference[j] as f64).abs() < 20e-6);
    }
}

#[test]
fn arm_is_refused_away_from_the_plan_start() {
    let plan = testplan::paper_case1().unwrap();
    for strict in [true, false] {
        let e = run(&plan, |o| {
            o.start_offset_m = [0.0, 1e-3, 0.0];
            o.strict = strict;
        })
        .unwrap_err();
        // A refusal: how far each axis is, and the move that fixes it.
        match e {
            SimulateError::Upload(
                ref u @ UploadError::ArmTooFar {
                    node: triquint_link::Drive { axis: 2, node: 2 },
                    distances_mm,
                    start_mm,
                },
            ) => {
                assert!(u.is_refusal());
                // As the drive measures it, still settling against gravity
                // when Arm comes (compact segments fill the queues sooner).
                assert!(u.to_string().contains("axis 2 +1.00"), "{u}");
                let d = distances_mm.map(|d| d.unwrap());
                assert!(
                    d[0].abs() < 0.01 && (d[1] - 1.0).abs() < 0.01 && d[2].abs() < 0.01,
                    "{d:?}"
                );
                assert!((start_mm[0] + 90.0).abs() < 1e-9 && (start_mm[2] - 680.0).abs() < 1e-9);
            }
            other => panic!("{other}"),
        }
    }
}

#[test]
fn a_node_with_another_configuration_is_named() {
    let plan = testplan::paper_case1().unwrap();
    let settings = DriveSettings::default();
    let configs = DriveConfigs::for_plan(&plan, &settings).unwrap().nodes;
    let q0 = plan.segments[0].quintic().eval(0.0).q;
    let mut sim = Sim::new(&Robot::default(), q0, SimConfig::default());
    // Node 3 was configured elsewhere with a different gain.
    for (i, c) in configs.iter().enumerate() {
        let node = i as u8 + 1;
        let mut c = *c;
        if node == 3 {
            c.kp *= 1.5;
        }
        for (k, v) in c.to_values().iter().enumerate() {
            sim.host_send(config_write_frame(node, k as u8, *v));
        }
        sim.host_send(
            Command {
                command: CommandCode::ConfigCommit as u8,
                token: 1,
                arg: c.crc(),
                arg2: 0,
            }
            .to_frame(node),
        );
    }
    sim.run_until(50_000_000).unwrap();
    while sim.host_receive().is_some() {}
    let opts = SessionOptions {
        configure: false,
        ..SessionOptions::default()
    };
    let mut s = Session::new(&plan, configs, opts).unwrap();
    let err = loop {
        let mut port = SimPort {
            sim: &mut sim,
            tx_queue: 32,
        };
        match s.poll(&mut port) {
            Ok(None) => {}
            Ok(Some(_)) => panic!("uploaded to a node with another configuration"),
            Err(e) => break e,
        }
        let t = sim.now_ns() + 100_000;
        sim.run_until(t).unwrap();
    };
    assert!(err.is_config(), "{err}");
    match err {
        UploadError::ConfigMismatch { node, param, .. } => {
            assert_eq!(node, triquint_link::Drive { axis: 3, node: 3 });
            assert_eq!(param, "kp");
        }
        other => panic!("{other}"),
    }
}

#[test]
fn case2_at_10_khz_tracks_as_well_as_at_1_khz() {
    let plan = testplan::paper_case2().unwrap();
    let fast = run(&plan, |o| o.rate_hz = 10_000.0).unwrap();
    assert_clean(&fast, "10 kHz");
    assert!(fast.start_skew_ns.is_some_and(|s| s <= 100_000));
    for j in 0..3 {
        assert!(fast.run.max_error_m[j] < 10e-6, "{:?}", fast.run.tracking());
    }
}

#[test]
fn start_skew_is_none_unless_every_drive_started() {
    assert_eq!(start_skew_ns([Some(30), Some(10), Some(25)]), Some(20));
    assert_eq!(start_skew_ns([Some(7), Some(7), Some(7)]), Some(0));
    // One drive never started: no figure, not a wrapped one.
    assert_eq!(start_skew_ns([Some(10), None, Some(25)]), None);
    assert_eq!(start_skew_ns([None, None, None]), None);
    assert_eq!(
        start_skew_ns([Some(u64::MAX), Some(0), Some(1)]),
        Some(u64::MAX)
    );
}

/// Largest |q′|, |q″|, |q‴| of `plan`'s segments over the three joints.
fn exact_maxima(plan: &Plan) -> [f64; 3] {
    let m = triquint_shared::plan::figures::kinematics(&plan.segments);
    let top = |x: [f64; 3]| x.into_iter().fold(0.0, f64::max);
    [top(m.velocity), top(m.acceleration), top(m.jerk)]
}

/// A host that skips its own check (`simulate` here does not run `check`):
/// a plan above the machine's ceilings is refused by the drives, naming
/// the ceiling, before anything starts.
#[test]
fn the_drives_refuse_a_plan_above_their_ceilings_whatever_the_host_sends() {
    use triquint_shared::machine::Ceilings;
    use triquint_shared::protocol::Reject;
    let mut plan = testplan::paper_case1().unwrap();
    let [v, a, j] = exact_maxima(&plan);
    // Limits at the plan's own maxima: override cap 1, so the first
    // segment refused is refused for its own maxima.
    let tight = plan.clone();
    plan.limits.velocity = v * 1.001;
    plan.limits.acceleration = a * 1.001;
    plan.limits.jerk = j * 1.001;
    let free = Ceilings::default();
    let cases = [
        (
            Ceilings {
                velocity: 0.9 * v,
                ..free.clone()
            },
            Reject::AboveVelocityCeiling,
        ),
        (
            Ceilings {
                acceleration: 0.9 * a,
                ..free.clone()
            },
            Reject::AboveAccelerationCeiling,
        ),
        (
            Ceilings {
                jerk: 0.9 * j,
                ..free.clone()
            },
            Reject::AboveJerkCeiling,
        ),
        // Above the segments' maxima, below them at the cap the host
        // sized from the plan's own limits. (With the jerk ceiling at
        // 1.05 j too, the host lowers the cap to 1 for the stop's room,
        // and the drives' ramps by pieces accept every segment there: the
        // plan runs, as it should.)
        (
            Ceilings {
                velocity: 1.05 * v,
                acceleration: 1.05 * a,
                ..free.clone()
            },
            Reject::OverrideAboveCeiling,
        ),
    ];
    for (ceilings, want) in cases {
        let plan = if want == Reject::OverrideAboveCeiling {
            &tight
        } else {
            &plan
        };
        let r = run(plan, |o| o.settings.ceilings = ceilings.clone());
        match r {
            Err(SimulateError::Upload(UploadError::Rejected { reason, .. })) => {
                assert_eq!(reason, Some(want), "{ceilings:?}")
            }
            Err(e) => panic!("{want:?}: {e}"),
            Ok(r) => panic!("{want:?}: ran, completed {}", r.run.completed),
        }
    }
    // Every ceiling 5 % above the segments' maxima: the host sizes the
    // cap to 1 and every drive accepts the plan.
    let close = Ceilings {
        velocity: 1.05 * v,
        acceleration: 1.05 * a,
        jerk: 1.05 * j,
        ..free.clone()
    };
    match run(&tight, |o| o.settings.ceilings = close.clone()) {
        Ok(r) => assert!(
            r.run.completed && r.run.faults.is_empty(),
            "{:?}",
            r.run.faults
        ),
        Err(e) => panic!("ceilings 5 % above the plan: {e}"),
    }
}

/// The project's own plans pass the drives' ceiling checks on a machine
/// whose ceilings are the plans' limits (the tightest a planner allows),
/// and on the B-G431B-ESC1 example's; Case I runs clean on the former.
#[test]
fn the_projects_plans_pass_the_ceilings_they_were_made_within() {
    use triquint_firmware::ceilings::Maxima;
    use triquint_firmware::segment::Seg;
    use triquint_shared::machine::Ceilings;
    let esc1 = Ceilings {
        velocity: 0.5,
        acceleration: 2.0,
        jerk: 10.0,
        torque: 0.75,
    };
    for name in ["case1-spline", "case2-spline", "spiral-spline"] {
        let text = std::fs::read_to_string(format!(
            "{}/../testdata/protocol/plans/{name}.json",
            env!("CARGO_MANIFEST_DIR")
        ))
        .expect("a test plan");
        let plan: Plan = serde_json::from_str(&text).expect("a plan");
        let l = &plan.limits;
        let tight = Ceilings {
            velocity: l.velocity,
            acceleration: l.acceleration,
            jerk: l.jerk,
            torque: l.torque,
        };
        for ceilings in [tight, esc1.clone()] {
            let settings = DriveSettings {
                ceilings: ceilings.clone(),
                ..DriveSettings::default()
            };
            let configs = DriveConfigs::for_plan(&plan, &settings).unwrap();
            for cfg in &configs.nodes {
                cfg.validate().unwrap();
                for (k, w) in plan.wire_segments().unwrap().iter().enumerate() {
                    let m = Maxima::of(&Seg::from_wire(w, 0));
                    let got = m.check(cfg).and_then(|()| m.ramps_us(cfg));
                    assert!(got.is_ok(), "{name} segment {k} {ceilings:?}: {got:?}");
                }
            }
        }
    }
    let plan = testplan::paper_case1().unwrap();
    let l = plan.limits.clone();
    let r = run(&plan, |o| {
        o.settings.ceilings = Ceilings {
            velocity: l.velocity,
            acceleration: l.acceleration,
            jerk: l.jerk,
            torque: l.torque,
        }
    })
    .unwrap();
    assert_clean(&r, "case I within tight ceilings");
}
