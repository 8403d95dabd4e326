//! Uploading and running a plan on the drives over SocketCAN: heartbeat
//! check, configuration, segment streaming with flow control, time sync,
//! arm, common start, then each node's final state and fault code. Whoever
//! runs it watches through [`RunWatch`] (the CLI's progress line and keys),
//! so the loop itself neither draws nor reads a terminal.

use std::time::{Duration, Instant};

use serde::Serialize;
use triquint_link::{DriveConfigs, Feed, Outcome, Progress, Session, SessionOptions, open_host};
use triquint_shared::machine::Machine;
use triquint_shared::plan::Plan;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{FaultCode, State};

use crate::ops::bus::Bus;
use crate::ops::error::{OpError, OpResult};

/// What an upload did.
#[derive(Clone, Debug, Serialize)]
pub struct UploadSummary {
    pub completed: bool,
    /// Stopped on request (a stop key, `triquint stop`): at rest on the path.
    pub stopped: bool,
    /// The override cap the drives were configured with (σ).
    pub override_cap: f64,
    pub segments: usize,
    pub frames_sent: u64,
    pub segment_frames: u64,
    pub retransmits: u64,
    /// From the first frame until every segment was acknowledged by every node (s).
    pub upload_s: f64,
    /// From the first frame until every node reported rest (s).
    pub total_s: f64,
    pub nodes: Vec<NodeSummary>,
    pub faults: Vec<FaultSummary>,
}

#[derive(Clone, Debug, Serialize)]
pub struct NodeSummary {
    pub node: u8,
    pub state: &'static str,
    pub fault: u8,
    pub fault_name: &'static str,
}

#[derive(Clone, Debug, Serialize)]
pub struct FaultSummary {
    pub node: u8,
    pub code: u8,
    pub name: &'static str,
}

/// Who watches a run: is told its progress and may send feed commands.
pub trait RunWatch {
    /// The override (per mille) to set before the start; 100 % sends none.
    fn initial_override_pm(&self) -> Option<u16>;
    /// The run begins: `segments` to upload.
    fn start(&mut self, segments: usize);
    /// The feed commands to send now, from what the session knows
    /// (`progress`); `cap_pm` is the configured override cap (per mille).
    fn feed(&mut self, progress: &Progress, cap_pm: u16) -> Vec<Feed>;
    /// Progress after one poll of the bus.
    fn progress(&mut self, progress: &Progress);
    /// The run failed.
    fn abandon(&mut self);
    /// The run ended (completed, stopped or faulted).
    fn finish(&mut self);
}

/// Uploads and runs `plan` over `bus`, told to `watch`.
pub fn run_plan(
    plan: &Plan,
    bus: &Bus,
    machine: &Machine,
    clear: bool,
    watch: &mut dyn RunWatch,
) -> OpResult<UploadSummary> {
    let settings = DriveSettings {
        control_rate: bus.rate,
        node_ids: bus.ids,
        ..machine.drive_settings()
    };
    let configs = DriveConfigs::for_plan(plan, &settings)?;
    let override_cap = configs.override_cap;
    let cap_pm = configs.override_cap_permille();
    let configs = configs.nodes;
    let opts = SessionOptions {
        fd: bus.fd,
        response_timeout_us: (bus.timeout_s * 1e6) as u64,
        clear_faults: clear,
        // The override chosen while watching (in an approach before this plan).
        feed_override: watch.initial_override_pm().filter(|pm| *pm != 1000),
        ..SessionOptions::default()
    };
    let mut session = Session::new(plan, configs, opts).map_err(|e| OpError::upload(e, bus))?;
    let mut port = open_host(&bus.iface, bus.fd)?;
    watch.start(plan.segments.len());
    let t0 = Instant::now();
    let mut acked_at: Option<f64> = None;
    let outcome: Outcome = loop {
        for f in watch.feed(&session.progress(), cap_pm) {
            session.feed(f);
        }
        let polled = session.poll(&mut port);
        let p = session.progress();
        watch.progress(&p);
        if acked_at.is_none() && p.segments_acked == p.segments {
            acked_at = Some(t0.elapsed().as_secs_f64());
        }
        match polled {
            Ok(Some(o)) => break o,
            Ok(None) => {}
            Err(e) => {
                watch.abandon();
                return Err(OpError::upload(e, bus));
            }
        }
        // 1 ms: the window (4 segments) stays full and time stamps come from
        // the kernel, so polling faster only burns CPU.
        std::thread::sleep(Duration::from_millis(1));
    };
    watch.finish();
    let total_s = t0.elapsed().as_secs_f64();
    let nodes = session
        .node_states()
        .iter()
        .zip(session.nodes())
        .map(|((state, fault), v)| NodeSummary {
            node: v.id,
            state: state.map_or("silent", State::name),
            fault: *fault,
            fault_name: FaultCode::from_u8(*fault).map_or("unknown", FaultCode::name),
        })
        .collect();
    Ok(UploadSummary {
        completed: outcome.completed,
        stopped: outcome.stopped,
        override_cap,
        segments: plan.segments.len(),
        frames_sent: outcome.frames_sent,
        segment_frames: outcome.segment_frames_sent,
        retransmits: outcome.retransmits,
        upload_s: acked_at.unwrap_or(total_s),
        total_s,
        nodes,
        faults: outcome
            .faults
            .iter()
            .map(|f| FaultSummary {
                node: f.node,
                code: f.code as u8,
                name: f.code.name(),
            })
            .collect(),
    })
}

#[cfg(test)]
mod tests {
    use triquint_shared::{Limits, Robot};
    use triquint_sim::testplan;

    use super::*;
    use crate::exit::{CliError, Status};

    /// Which of its methods a run called.
    #[derive(Default)]
    struct Recorder {
        calls: Vec<&'static str>,
    }

    impl RunWatch for Recorder {
        fn initial_override_pm(&self) -> Option<u16> {
            None
        }
        fn start(&mut self, _: usize) {
            self.calls.push("start");
        }
        fn feed(&mut self, _: &Progress, _: u16) -> Vec<Feed> {
            self.calls.push("feed");
            Vec::new()
        }
        fn progress(&mut self, _: &Progress) {
            self.calls.push("progress");
        }
        fn abandon(&mut self) {
            self.calls.push("abandon");
        }
        fn finish(&mut self) {
            self.calls.push("finish");
        }
    }

    fn bus(iface: &str) -> Bus {
        Bus {
            iface: iface.to_string(),
            fd: false,
            ids: [1, 2, 3],
            rate: 1000.0,
            timeout_s: 2.0,
        }
    }

    fn plan() -> Plan {
        let pts = [[0.0, 0.0, 0.62], [0.005, 0.0, 0.62], [0.01, 0.0, 0.62]];
        testplan::plan_through(&Robot::default(), &Limits::default(), &pts, &[0.5, 0.5])
            .expect("a short move")
    }

    #[test]
    fn a_run_that_cannot_begin_never_starts_its_watch() {
        let (plan, machine) = (plan(), Machine::default());
        let mut w = Recorder::default();
        let e = run_plan(&plan, &bus("triquint-nosuch0"), &machine, false, &mut w)
            .expect_err("no such interface");
        assert!(matches!(e, OpError::Open(_)), "{e}");
        let e = CliError::from(e);
        assert_eq!(e.status, Status::Device, "{}", e.message);
        // A segment that is not a whole number of microseconds.
        let mut unsendable = plan.clone();
        unsendable.segments[0].duration_s += 0.4e-6;
        let e = run_plan(
            &unsendable,
            &bus("triquint-nosuch0"),
            &machine,
            false,
            &mut w,
        )
        .expect_err("an unsendable plan");
        assert!(matches!(e, OpError::Upload { .. }), "{e}");
        let e = CliError::from(e);
        assert_eq!(e.status, Status::BadInput, "{}", e.message);
        assert!(
            w.calls.is_empty(),
            "watched a run that never began: {:?}",
            w.calls
        );
    }
}
