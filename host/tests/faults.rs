//! Fault injection on the in-process bus: one test per fault, each stating
//! the expected outcome and checking it. These are the evidence for the
//! "Guarantees" section of docs/protocol.md. Seeded: every run is reproducible.

use triquint_firmware::QUEUE_CAPACITY;
use triquint_host::inprocess::fault_run::{
    self, AboveCeiling, BURST_SEGMENTS, BadSegment, Scenario,
};
use triquint_shared::plan::Plan;
use triquint_shared::protocol::{FaultCode, Reject};
use triquint_sim::report::{Ending, FaultRunFigures, RunReport};
use triquint_sim::{Fault, FaultWindow, testplan};

const MS: u64 = 1_000_000;
const S: u64 = 1_000_000_000;
const FOREVER: u64 = u64::MAX;
const SYNC_ID: u16 = 0x020;
const SYNC_PERIOD_NS: u64 = 100 * MS;

fn case1() -> Plan {
    testplan::paper_case1().unwrap()
}

fn case2() -> Plan {
    testplan::paper_case2().unwrap()
}

fn spiral() -> Plan {
    testplan::spiral(
        testplan::SPIRAL_POINTS,
        testplan::SPIRAL_TURNS,
        testplan::SPIRAL_TIME,
    )
    .unwrap()
}

/// A plan that streams: three queues' worth of segments shaped as the
/// spiral's (the spiral itself when the queue holds 32), so a fault placed
/// after the first queue-full happens while the drives run and the host
/// streams.
fn beyond_the_queue() -> Plan {
    let n = 3 * QUEUE_CAPACITY;
    let per = |k: usize| k as f64 / (testplan::SPIRAL_POINTS - 1) as f64;
    // The spiral's intervals are 1, with 3 at each end (`testplan::spiral`).
    let time = testplan::SPIRAL_TIME * (n + 4) as f64 / (testplan::SPIRAL_POINTS + 3) as f64;
    let plan = testplan::spiral(n + 1, testplan::SPIRAL_TURNS * per(n), time).unwrap();
    assert_eq!(plan.segments.len(), n);
    plan
}

/// A fault run: its report, and the fault run's own figures in it.
struct Run {
    report: RunReport,
}

impl std::ops::Deref for Run {
    type Target = FaultRunFigures;
    fn deref(&self) -> &FaultRunFigures {
        self.report
            .fault_run
            .as_ref()
            .expect("a fault run's figures")
    }
}

impl std::fmt::Debug for Run {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        self.report.fmt(f)
    }
}

impl Run {
    /// The stop time (from the first fault to every running axis at rest) in ns.
    fn stop_time_ns(&self) -> Option<u64> {
        self.report.stop_s.map(|t| (t * 1e9).round() as u64)
    }

    /// The stop ramp T_s the drives were configured with, in whole ns.
    fn stop_ramp_ns(&self) -> u64 {
        (self.report.stop_ramp_s * 1e9) as u64
    }
}

fn run(plan: &Plan, sc: &Scenario) -> Run {
    Run {
        report: fault_run::run(plan, sc),
    }
}

fn report(what: &str, r: &Run) {
    eprintln!(
        "{what}: start {:?} ms, {:?}, codes {:?}, stop {:?} ms (ramp {} ms), jerk {:.3}/{:.3}, \
         emergency→stop {:?} ticks, retx {}, rejects {:?}, injected {:?}, host {:?}, track {:.2} µm",
        r.start_ns.map(|t| t as f64 * 1e-6),
        r.ending,
        r.codes,
        r.stop_time_ns().map(|t| t as f64 * 1e-6),
        r.stop_ramp_ns() / MS,
        r.report.worst_stop_jerk(),
        r.stop_jerk_bound,
        r.emergency_to_stop_ticks,
        r.retransmits,
        r.rejects,
        r.injected,
        r.host_error,
        r.report.worst_error_m() * 1e6,
    );
}

fn scenario(windows: Vec<FaultWindow>, seed: u64) -> Scenario {
    Scenario {
        windows,
        seed,
        ..Scenario::default()
    }
}

/// Recovered: every node executed every segment bit for bit in order and
/// ended Idle with no fault; tracking within `track_m` (measured from the
/// commanded start time, the fault-free Case I and II runs stay within
/// 1.6 and 2.3 µm).
fn assert_recovered_within(what: &str, r: &Run, track_m: f64) {
    report(what, r);
    assert_eq!(r.corrupted_executions, 0, "{what}");
    assert_eq!(r.ending, Ending::Completed, "{what}");
    assert!(r.report.completed, "{what}");
    assert!(r.executed_whole_plan, "{what}");
    let track = r.report.worst_error_m();
    assert!(track < track_m, "{what}: {track}");
}

fn assert_recovered(what: &str, r: &Run) {
    assert_recovered_within(what, r, 10e-6);
}

/// Stopped: every running axis at rest along the path, inside its buffer,
/// within the jerk budget, with a code from `codes` on every node, at least
/// one node with a code from `primary` (the detecting node), and the codes on
/// the bus in Emergency frames and heartbeats.
fn assert_stopped(what: &str, r: &Run, primary: &[FaultCode], codes: &[FaultCode]) {
    report(what, r);
    assert_eq!(r.corrupted_executions, 0, "{what}");
    assert_eq!(r.ending, Ending::Stopped, "{what}");
    assert!(!r.report.completed, "{what}");
    assert!(r.report.stopped_within_buffer, "{what}");
    let jerk = r.report.worst_stop_jerk();
    assert!(jerk > 0.0 && jerk <= r.stop_jerk_bound, "{what}");
    assert!(
        r.codes.iter().any(|c| primary.contains(c)),
        "{what}: {:?}",
        r.codes
    );
    for (i, c) in r.codes.iter().enumerate() {
        if *c != FaultCode::None {
            assert!(codes.contains(c), "{what}: node {} {c:?}", i + 1);
            let node = i as u8 + 1;
            assert!(
                r.heartbeat_codes.contains(&(node, *c)),
                "{what}: node {node} heartbeat {:?}",
                r.heartbeat_codes
            );
        }
    }
    assert!(
        r.emergency_codes.iter().any(|e| primary.contains(&e.1)),
        "{what}: emergencies {:?}",
        r.emergency_codes
    );
    if let Some(t) = r.emergency_to_stop_ticks {
        assert!(t <= 2.0, "{what}: emergency to stop {t} ticks");
    }
}

fn all(fault: Fault) -> Vec<FaultWindow> {
    vec![FaultWindow::new(fault, 0, FOREVER)]
}

#[test]
fn clean_run_completes() {
    assert_recovered("clean", &run(&case1(), &Scenario::default()));
}

#[test]
fn frame_loss_is_recovered_by_retransmission() {
    // From just after the start (lost set-up frames: see
    // `lost_set_up_frames_are_sent_again`). The spiral streams segments
    // for its whole duration.
    let w = vec![FaultWindow::new(
        Fault::Loss { rate: 0.01 },
        400 * MS,
        FOREVER,
    )];
    let r = run(&spiral(), &scenario(w, 12));
    assert_recovered("loss 1 %", &r);
    assert!(r.injected.lost > 10 && r.retransmits > 0, "{r:?}");
}

#[test]
fn lost_set_up_frames_are_sent_again() {
    // Configuration writes and command answers lost: a drive refuses a
    // commit whose writes did not all arrive, and Arm/commit answers go
    // missing; the host writes and commits again, re-sends Arm (same token:
    // a drive that did arm answers again), and the plan runs.
    let w = vec![
        FaultWindow::new(Fault::Loss { rate: 0.03 }, 0, FOREVER).on_ids(0x040..=0x043),
        FaultWindow::new(Fault::Loss { rate: 0.3 }, 0, FOREVER).on_ids(0x1A1..=0x1A3),
    ];
    let r = run(&case1(), &scenario(w, 21));
    assert_recovered("set-up frames lost", &r);
    assert!(r.injected.lost >= 3, "{r:?}");
}

#[test]
fn corrupted_segment_parts_fail_the_crc_and_are_retransmitted() {
    let r = run(&case2(), &scenario(all(Fault::Corrupt { rate: 0.01 }), 12));
    assert_recovered("corrupt 1 % of parts", &r);
    assert!(r.injected.corrupted > 5, "{r:?}");
    assert!(r.rejects[Reject::BadCrc as usize] > 0, "{r:?}");
    assert!(r.retransmits > 0);
}

#[test]
fn duplicated_frames_change_nothing() {
    let r = run(&case1(), &scenario(all(Fault::Duplicate { rate: 0.1 }), 13));
    assert_recovered("duplicate 10 %", &r);
    assert!(r.injected.duplicated > 50, "{r:?}");
    assert!(r.rejects[Reject::Duplicate as usize] > 0, "{r:?}");
}

#[test]
fn reordered_frames_are_retransmitted() {
    // Compact segments are few frames (75 for Case I): reorder those at
    // 3 % besides every frame at 0.5 %, so segment parts do get swapped.
    let w = vec![
        FaultWindow::new(Fault::Reorder { rate: 0.005 }, 0, FOREVER),
        FaultWindow::new(Fault::Reorder { rate: 0.03 }, 0, FOREVER).on_ids(0x100..=0x11F),
    ];
    let r = run(&case1(), &scenario(w, 14));
    assert_recovered("reorder 0.5 %, segment frames 3 %", &r);
    assert!(r.injected.reordered > 5, "{r:?}");
    assert!(r.rejects[Reject::OutOfOrder as usize] > 0, "{r:?}");
}

#[test]
fn reordered_frames_at_five_per_cent_are_retransmitted() {
    // A refused copy and one queued behind a missing segment use up no
    // try: only a copy lost to a node that needs it does. (Charging those
    // too, most of these seeds ended the upload after 6 transmissions.)
    for seed in 1..=4 {
        let w = vec![
            FaultWindow::new(Fault::Reorder { rate: 0.005 }, 0, FOREVER),
            FaultWindow::new(Fault::Reorder { rate: 0.05 }, 0, FOREVER).on_ids(0x100..=0x11F),
        ];
        for plan in [case1(), case2()] {
            let r = run(&plan, &scenario(w.clone(), seed));
            assert_recovered(
                &format!("reorder 0.5 %, segment frames 5 %, seed {seed}"),
                &r,
            );
            assert!(r.rejects[Reject::OutOfOrder as usize] > 0, "{r:?}");
        }
    }
}

#[test]
fn delay_and_jitter_change_nothing() {
    // Every frame handed to the software up to 2 ms late (hardware
    // timestamps), the sync's receive timestamps jittered by up to 20 µs.
    // (Timestamp jitter J moves a drive's time base by up to J: see the soak
    // table for larger J.)
    let w = vec![
        FaultWindow::new(Fault::Delay { max_ns: 2 * MS }, 0, FOREVER),
        FaultWindow::new(Fault::Jitter { max_ns: 20_000 }, 0, FOREVER).on_ids(SYNC_ID..=SYNC_ID),
    ];
    let r = run(&case2(), &scenario(w, 15));
    // The drives take the latest sync sample as their offset, so timestamp
    // jitter reaches the reference: the worst error depends on which syncs
    // the seeded jitter hits: 5.7-8.1 µm over seeds 1-6 and 15 (8.1 µm
    // here; 2.3 µm without faults), far inside the 1 mm following bound.
    // (Measured from the first Running tick, as before, these read 44-167 µm:
    // that tick lags the commanded start by up to a tick period.)
    assert_recovered_within("delay 0-2 ms, sync jitter 0-20 µs", &r, 25e-6);
    assert!(r.injected.delayed > 1000);
}

#[test]
fn a_burst_beyond_the_queue_is_refused_and_nothing_runs_twice() {
    // While the spiral streams, more segments at once than a queue holds.
    let plan = beyond_the_queue();
    let sc = Scenario {
        burst_ns: Some(1500 * MS),
        ..Scenario::default()
    };
    let r = run(&plan, &sc);
    assert_recovered(&format!("burst of {BURST_SEGMENTS} segments"), &r);
    let refused = r.rejects[Reject::QueueFull as usize] + r.rejects[Reject::Duplicate as usize];
    assert!(refused > 0, "{r:?}");
}

#[test]
fn a_short_babble_is_ridden_out() {
    let w = vec![FaultWindow::new(
        Fault::Babble { id: 0x001 },
        1500 * MS,
        1600 * MS,
    )];
    let r = run(&case1(), &scenario(w, 16));
    assert_recovered("babble 100 ms", &r);
    assert!(r.injected.babbled > 500);
}

#[test]
fn a_long_babble_stops_every_axis_on_lost_sync() {
    let w = vec![FaultWindow::new(
        Fault::Babble { id: 0x001 },
        1500 * MS,
        2500 * MS,
    )];
    let r = run(&case1(), &scenario(w, 17));
    // Nothing gets through: every node detects the silence itself.
    assert_stopped(
        "babble 1 s",
        &r,
        &[FaultCode::LostSync, FaultCode::PeerLost],
        &[
            FaultCode::LostSync,
            FaultCode::PeerLost,
            FaultCode::PeerEmergency,
        ],
    );
    // Detected within the sync timeout of the last sync; at rest one ramp later.
    assert!(r.stop_time_ns().unwrap() <= r.stop_ramp_ns() + 2 * r.tick_ns + SYNC_PERIOD_NS);
}

#[test]
fn a_short_bus_off_is_recovered() {
    let w = vec![FaultWindow::new(
        Fault::BusOff { station: 2 },
        1500 * MS,
        1560 * MS,
    )];
    let r = run(&case1(), &scenario(w, 18));
    assert_recovered("node 2 bus-off 60 ms", &r);
    assert!(r.injected.bus_off_dropped > 0);
}

#[test]
fn a_long_bus_off_stops_every_axis() {
    let w = vec![FaultWindow::new(
        Fault::BusOff { station: 2 },
        1500 * MS,
        2300 * MS,
    )];
    let r = run(&case1(), &scenario(w, 19));
    // Node 2 hears nobody (sync and peers silent); nodes 1 and 3 lose node
    // 2's heartbeat.
    assert_stopped(
        "node 2 bus-off 800 ms",
        &r,
        &[FaultCode::PeerLost],
        &[
            FaultCode::LostSync,
            FaultCode::PeerLost,
            FaultCode::PeerEmergency,
        ],
    );
    assert!(matches!(
        r.codes[1],
        FaultCode::LostSync | FaultCode::PeerLost
    ));
}

#[test]
fn a_host_killed_mid_upload_ends_in_the_along_path_stop() {
    let sc = Scenario {
        host_killed_ns: Some(500 * MS),
        ..Scenario::default()
    };
    let r = run(&case1(), &sc);
    assert_stopped(
        "host killed at 0.5 s",
        &r,
        &[FaultCode::LostSync, FaultCode::Underrun],
        &[
            FaultCode::LostSync,
            FaultCode::Underrun,
            FaultCode::PeerEmergency,
        ],
    );
    // Every axis came to rest inside what it had buffered (checked above),
    // one ramp after the detection.
    assert!(r.stop_time_ns().unwrap() <= r.stop_ramp_ns() + 2 * r.tick_ns);
}

#[test]
fn a_node_reset_mid_trajectory_stops_the_others() {
    let sc = Scenario {
        node_reset: Some((2, 2 * S)),
        ..Scenario::default()
    };
    let r = run(&case2(), &sc);
    assert_stopped(
        "node 3 reset at 2 s",
        &r,
        &[FaultCode::PeerLost],
        &[FaultCode::PeerLost, FaultCode::PeerEmergency],
    );
    assert_eq!(r.codes[2], FaultCode::None, "the reset node starts afresh");
    // The reset node's first heartbeat arrives within a tick or two.
    let first = r.first_fault_ns.unwrap();
    assert!(first - 2 * S <= 3 * r.tick_ns, "{}", first - 2 * S);
    assert!(r.stop_time_ns().unwrap() <= r.stop_ramp_ns() + 2 * r.tick_ns);
}

#[test]
fn lost_time_sync_is_detected_within_three_sync_periods() {
    let w =
        vec![FaultWindow::new(Fault::Loss { rate: 1.0 }, 2 * S, FOREVER).on_ids(SYNC_ID..=SYNC_ID)];
    let r = run(&case2(), &scenario(w, 20));
    assert_stopped(
        "time sync lost from 2 s",
        &r,
        &[FaultCode::LostSync],
        &[FaultCode::LostSync, FaultCode::PeerEmergency],
    );
    let detect = r.lost_sync_ns.unwrap() - r.last_sync_ns.unwrap();
    eprintln!(
        "lost sync detected {:.1} ms after the last sync",
        detect as f64 * 1e-6
    );
    assert!(detect <= 3 * SYNC_PERIOD_NS, "{detect}");
    assert!(r.stop_time_ns().unwrap() <= r.stop_ramp_ns() + 2 * r.tick_ns);
}

#[test]
fn a_late_time_sync_is_discarded() {
    // One sync reaches every node 40 ms late: without the outlier gate the
    // drives' time base would jump by 40 ms.
    let w = vec![
        FaultWindow::new(Fault::Late { ns: 40 * MS }, 2 * S, 2 * S + SYNC_PERIOD_NS)
            .on_ids(SYNC_ID..=SYNC_ID),
    ];
    let r = run(&case2(), &scenario(w, 21));
    assert_recovered("one sync 40 ms late", &r);
    assert_eq!(r.injected.delayed, 3);
}

/// The nodes refuse the segment; the host gives up and falls silent (as the
/// CLI exits): the drives stop along the buffered path (lost sync, or
/// underrun, whichever comes first) and the bad segment never runs.
#[test]
fn a_segment_beyond_the_limits_is_never_executed() {
    // After the first queue-full: the drives run when it arrives.
    let k = QUEUE_CAPACITY + 2;
    let sc = Scenario {
        bad_segment: Some(BadSegment::Limits(k)),
        ..Scenario::default()
    };
    let r = run(&beyond_the_queue(), &sc);
    assert!(r.start_ns.is_some(), "{r:?}");
    assert_stopped(
        &format!("segment {k} beyond the jerk limit"),
        &r,
        &[FaultCode::LostSync, FaultCode::Underrun],
        &[
            FaultCode::LostSync,
            FaultCode::Underrun,
            FaultCode::PeerEmergency,
        ],
    );
    assert!(r.rejects[Reject::Invalid as usize] >= 3, "{r:?}");
    assert!(r.host_error.as_deref().unwrap_or("").contains("Invalid"));
}

#[test]
fn a_segment_not_c3_continuous_is_never_executed() {
    // After the first queue-full: the drives run when it arrives.
    let k = QUEUE_CAPACITY + 2;
    let sc = Scenario {
        bad_segment: Some(BadSegment::Kink(k)),
        ..Scenario::default()
    };
    let r = run(&beyond_the_queue(), &sc);
    assert!(r.start_ns.is_some(), "{r:?}");
    assert_stopped(
        &format!("segment {k} with a velocity step"),
        &r,
        &[FaultCode::LostSync, FaultCode::Underrun],
        &[
            FaultCode::LostSync,
            FaultCode::Underrun,
            FaultCode::PeerEmergency,
        ],
    );
    assert!(r.rejects[Reject::Discontinuous as usize] >= 3, "{r:?}");
}

#[test]
fn a_peer_emergency_stops_every_node_within_two_ticks() {
    // Node 1 bus-off long enough to lose the sync: its Emergency goes out
    // on recovery, and the others (running) stop on it.
    let w = vec![FaultWindow::new(
        Fault::BusOff { station: 1 },
        1500 * MS,
        1500 * MS + 260 * MS,
    )];
    let r = run(&case2(), &scenario(w, 22));
    report("node 1 bus-off 260 ms", &r);
    assert_eq!(r.corrupted_executions, 0);
    assert_eq!(r.ending, Ending::Stopped);
    let t = r
        .emergency_to_stop_ticks
        .expect("a running node received an Emergency");
    assert!(t <= 2.0, "{t}");
}

/// Drives commissioned with a velocity ceiling under Case II's peak; the
/// host then configures them with the top ceilings, as from a machine file
/// raised without maintenance: the ceiling lock refuses the commit and
/// nothing moves. In the maintenance window the same commit is taken and
/// the plan runs whole.
#[test]
fn a_host_cannot_widen_the_commissioned_ceilings_outside_maintenance() {
    let locked = Scenario {
        above_ceiling: Some(AboveCeiling::Locked(0, 0.8)),
        ..Scenario::default()
    };
    let r = run(&case2(), &locked);
    report("ceilings widened, locked", &r);
    assert_eq!(r.ending, Ending::NotStarted, "{r:?}");
    assert!(r.start_ns.is_none() && !r.executed_whole_plan, "{r:?}");
    let e = r.host_error.as_deref().unwrap_or("");
    assert!(
        e.contains("CeilingsLocked") && e.contains("`ceiling_velocity`"),
        "{e}"
    );
    let unlocked = Scenario {
        unlock_ceilings: true,
        ..locked
    };
    let r = run(&case2(), &unlocked);
    report("ceilings widened in maintenance", &r);
    assert_recovered("ceilings widened in maintenance", &r);
}
