//! Sessions one after another, each on its own host clock, as processes
//! are (`upload --approach` configures, then runs the approach, then the
//! plan, each on a port of its own): the drives must follow each new host
//! time base before the session arms them, or a Start dated on the new
//! clock reads as past on the old one (`StartInPast`).

use triquint_link::{CanPort, DriveConfigs, PortError, Received, Session, SessionOptions};
use triquint_shared::Robot;
use triquint_shared::plan::Plan;
use triquint_shared::protocol::DriveConfig;
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

/// Runs a session from now on a clock of its own until it ends (its
/// completion and the faults it saw) or `until` holds (`None`).
fn run_session(
    sim: &mut Sim,
    session: &mut Session,
    what: &str,
    until: impl Fn(&Sim) -> bool,
) -> Option<(bool, String)> {
    // A new port hears nothing sent before it opened.
    while sim.host_receive().is_some() {}
    let epoch_us = sim.now_ns() / 1000;
    let limit_ns = sim.now_ns() + 20_000_000_000;
    while !until(sim) {
        let mut port = EpochPort {
            inner: SimPort {
                sim: &mut *sim,
                tx_queue: 32,
            },
            epoch_us,
        };
        match session.poll(&mut port) {
            Ok(Some(o)) => return Some((o.completed, format!("{what}: faults {:?}", o.faults))),
            Ok(None) => {}
            Err(e) => return Some((false, format!("{what}: {e}"))),
        }
        let t = sim.now_ns() + 1_000_000;
        assert!(t < limit_ns, "{what}: no end within 20 s");
        sim.run_until(t).unwrap();
    }
    None
}

/// For gaps up to 4 × the drives' sync timeout (1 s), within which a
/// drive that hears syncs reports itself synced on the old time base, in
/// steps finer than the heartbeats' period (some put a heartbeat of the
/// old base just before the next session's Sync phase): `first` on a
/// fresh machine, the gap, then an upload, which must complete.
fn upload_after(what: &str, first: impl Fn(&mut Sim, &Plan, [DriveConfig; 3])) {
    let plan = testplan::point_to_point(15, 0.9, 0.03).unwrap();
    let q0 = plan.segments[0].quintic().eval(0.0).q;
    let configs = DriveConfigs::for_plan(&plan, &DriveSettings::default())
        .unwrap()
        .nodes;
    for gap_ms in (0..1000).step_by(5) {
        let mut sim = Sim::new(&Robot::default(), q0, SimConfig::default());
        first(&mut sim, &plan, configs);
        let t = sim.now_ns() + gap_ms * 1_000_000;
        sim.run_until(t).unwrap();
        let mut upload = Session::new(&plan, configs, SessionOptions::default()).unwrap();
        let what = format!("upload {gap_ms} ms after {what}");
        let r = run_session(&mut sim, &mut upload, &what, |_| false);
        let (done, faults) = r.unwrap();
        assert!(done, "{faults}");
    }
}

#[test]
fn back_to_back_sessions_on_new_host_clocks_start_whatever_the_gap() {
    // What `upload --approach` does first: configure, read positions.
    upload_after("a configuration", |sim, plan, configs| {
        let opts = SessionOptions {
            configure_only: true,
            ..SessionOptions::default()
        };
        let mut configure = Session::new(plan, configs, opts).unwrap();
        let r = run_session(sim, &mut configure, "configure", |_| false);
        let (done, faults) = r.unwrap();
        assert!(done, "{faults}");
    });
}

#[test]
fn a_session_after_one_that_left_the_drives_loaded_starts() {
    // A host that loaded the drives and went before Arm: they keep its
    // time base until Reset.
    upload_after("a session that left them loaded", |sim, plan, configs| {
        let mut first = Session::new(plan, configs, SessionOptions::default()).unwrap();
        let loaded = |sim: &Sim| sim.nodes.iter().all(|n| n.node.state() == State::Loaded);
        assert!(run_session(sim, &mut first, "loading", loaded).is_none());
    });
}
