//! Sessions one after another, each on its own host clock, as processes
//! are (`upload --approach` configures, then runs the approach, then the
//! plan, each on a port of its own): the drives must follow each new host
//! time base before the session arms them, or a Start dated on the new
//! clock reads as past on the old one (`StartInPast`).

use triquint_link::{CanPort, DriveConfigs, PortError, Received, Session, SessionOptions};
use triquint_shared::Robot;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{Frame, State};
use triquint_sim::host_port::SimPort;
use triquint_sim::{Sim, SimConfig, testplan};

/// The host's station with its clock counted from `epoch_us` of the
/// simulation's time, as a new process's clock is from its port's opening.
struct EpochPort<'a> {
    inner: SimPort<'a>,
    epoch_us: u64,
}

impl CanPort for EpochPort<'_> {
    fn now_us(&mut self) -> u64 {
        self.inner.now_us() - self.epoch_us
    }
    fn send(&mut self, frame: &Frame) -> Result<bool, PortError> {
        self.inner.send(frame)
    }
    fn recv(&mut self) -> Result<Option<Received>, PortError> {
        Ok(self.inner.recv()?.map(|mut r| {
            r.t_us = r.t_us.saturating_sub(self.epoch_us);
            r
        }))
    }
}

/// Runs a session from now on a clock of its own to its end; the outcome's
/// completion and the faults it saw.
fn run_session(sim: &mut Sim, session: &mut Session, what: &str) -> (bool, String) {
    // A new port hears nothing sent before it opened.
    while sim.host_receive().is_some() {}
    let epoch_us = sim.now_ns() / 1000;
    let limit_ns = sim.now_ns() + 20_000_000_000;
    loop {
        let mut port = EpochPort {
            inner: SimPort {
                sim: &mut *sim,
                tx_queue: 32,
            },
            epoch_us,
        };
        match session.poll(&mut port) {
            Ok(Some(o)) => return (o.completed, format!("{what}: faults {:?}", o.faults)),
            Ok(None) => {}
            Err(e) => return (false, format!("{what}: {e}")),
        }
        let t = sim.now_ns() + 1_000_000;
        assert!(t < limit_ns, "{what}: no end within 20 s");
        sim.run_until(t).unwrap();
    }
}

#[test]
fn back_to_back_sessions_on_new_host_clocks_start_whatever_the_gap() {
    let plan = testplan::point_to_point(15, 0.9, 0.03).unwrap();
    let q0 = plan.segments[0].quintic().eval(0.0).q;
    let configs = DriveConfigs::for_plan(&plan, &DriveSettings::default())
        .unwrap()
        .nodes;
    // Gaps within the drives' sync timeout (0.25 s), where the old time
    // base is still valid when the next session begins, in steps finer
    // than the heartbeats' period: some put a heartbeat of the old base
    // just after the configuration, which a session must not take as a
    // sync to its own.
    for gap_ms in (0..240).step_by(5) {
        let mut sim = Sim::new(&Robot::default(), q0, SimConfig::default());
        // What `upload --approach` does first: configure, read positions.
        let mut configure = Session::new(
            &plan,
            configs,
            SessionOptions {
                configure_only: true,
                ..SessionOptions::default()
            },
        )
        .unwrap();
        let what = format!("configure, gap {gap_ms} ms");
        let (done, faults) = run_session(&mut sim, &mut configure, &what);
        assert!(done, "{faults}");
        let t = sim.now_ns() + gap_ms * 1_000_000;
        sim.run_until(t).unwrap();
        let mut upload = Session::new(&plan, configs, SessionOptions::default()).unwrap();
        let what = format!("upload after {gap_ms} ms");
        let (done, faults) = run_session(&mut sim, &mut upload, &what);
        assert!(done, "{faults}");
    }
}

#[test]
fn a_session_after_one_that_left_the_drives_loaded_starts() {
    let plan = testplan::point_to_point(15, 0.9, 0.03).unwrap();
    let q0 = plan.segments[0].quintic().eval(0.0).q;
    let configs = DriveConfigs::for_plan(&plan, &DriveSettings::default())
        .unwrap()
        .nodes;
    for gap_ms in (0..240).step_by(5) {
        let mut sim = Sim::new(&Robot::default(), q0, SimConfig::default());
        // A host that loaded the drives and went before Arm: they keep
        // its time base until Reset.
        let mut first = Session::new(&plan, configs, SessionOptions::default()).unwrap();
        while sim.host_receive().is_some() {}
        let epoch_us = sim.now_ns() / 1000;
        while !sim.nodes.iter().all(|n| n.node.state() == State::Loaded) {
            let mut port = EpochPort {
                inner: SimPort {
                    sim: &mut sim,
                    tx_queue: 32,
                },
                epoch_us,
            };
            assert!(first.poll(&mut port).unwrap().is_none());
            let t = sim.now_ns() + 1_000_000;
            assert!(t < 10_000_000_000, "never loaded");
            sim.run_until(t).unwrap();
        }
        let t = sim.now_ns() + gap_ms * 1_000_000;
        sim.run_until(t).unwrap();
        let mut upload = Session::new(&plan, configs, SessionOptions::default()).unwrap();
        let what = format!("upload {gap_ms} ms after a session left them loaded");
        let (done, faults) = run_session(&mut sim, &mut upload, &what);
        assert!(done, "{faults}");
    }
}
