//! The one report of a simulated run: written by `triquint simulate --json`
//! (in process), by `triquint-sim --report` (on SocketCAN, for every run
//! and, flattened, the last one), and returned by the seeded fault runs of
//! the fault tests and the soak (`host/src/inprocess/fault_run.rs`, with
//! their own figures in [`RunReport::fault_run`]), so the reports cannot
//! drift apart. The field names are what the HIL suite (`hil-sim/python/`)
//! and `scripts/hil_figures.py` read.

use serde::{Serialize, Serializer};
use triquint_shared::protocol::{DriveConfig, FaultCode, Reject};

use crate::faults::FaultStats;
use crate::metrics::Tracking;
use crate::sim::FaultEvent;
use crate::vibration::Residual;

/// A fault a node reported, at `t_s` seconds of plan time.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct JsonFault {
    pub node: u8,
    pub code: u8,
    pub name: &'static str,
    pub t_s: f64,
}

impl JsonFault {
    pub fn new(f: &FaultEvent, t_s: f64) -> Self {
        Self {
            node: f.node,
            code: f.code as u8,
            name: f.code.name(),
            t_s,
        }
    }
}

/// What one plan run did, from the host's first frame to every drive at rest.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunReport {
    /// Tracking error of each joint against the plan, from the common start.
    pub rms_error_m: [f64; 3],
    pub max_error_m: [f64; 3],
    pub peak_torque_nm: [f64; 3],
    /// Busy fraction of the bus over the run.
    pub bus_load: f64,
    pub frames: u64,
    /// Faults on the nodes, in time order.
    pub faults: Vec<JsonFault>,
    /// Every node ran the whole plan and is Idle, without a fault.
    pub completed: bool,
    /// Share of the bus taken by segment parts.
    pub segment_bus_load: f64,
    pub segment_frames: u64,
    pub segments: usize,
    pub plan_time_s: f64,
    /// From the host's first frame to the end of the run (s).
    pub duration_s: f64,
    /// Spread of the drives' first Running tick (µs).
    pub start_skew_us: f64,
    pub tracking_samples: usize,
    /// Per node (1, 2, 3), the (sequence, body CRC-32) of every segment it executed.
    pub executed: Vec<Vec<(u16, u32)>>,
    /// From the first fault to the last running axis at rest (s).
    pub stop_s: Option<f64>,
    /// Every faulted axis stopped inside the plan time it had buffered (or
    /// on the plan's own end, which is at rest).
    pub stopped_within_buffer: bool,
    /// Largest |joint jerk| of each drive's reference while stopping (m/s³).
    pub max_stop_jerk: [f64; 3],
    /// The stop ramp T_s the drives were configured with (s).
    pub stop_ramp_s: f64,
    /// The feed-override cap they were configured with (σ): with the
    /// plan's jerk it sets a stop's jerk budget, max(J, j·cap³ + J/2)
    /// (docs/protocol.md, "Stop ramp").
    pub override_cap: f64,
    /// Only in a seeded fault run: what the fault tests and the soak check
    /// (absent from the JSON otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub fault_run: Option<FaultRunFigures>,
    /// Only on the flexible plant: the residual vibration after the plan's
    /// end, from the platform's accelerometer (absent from the JSON otherwise).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub vibration: Option<Residual>,
}

/// How a fault run ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub enum Ending {
    /// Every node executed every segment, bit for bit, in order, and is Idle.
    Completed,
    /// Every running axis came to rest along the path with a fault code.
    Stopped,
    /// Nothing moved: refused or faulted before the start.
    NotStarted,
    /// Anything else (a test failure).
    Unsafe,
}

/// What a seeded fault run measures beyond the common report: the ending,
/// the integrity of what ran, and the fault codes on the bus. Times are the
/// simulator's true time (ns). The stop time, stop ramp, stop jerk, buffer
/// check and tracking are the common report's.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FaultRunFigures {
    pub ending: Ending,
    /// Final fault code of each node (None = no fault).
    #[serde(serialize_with = "code_names")]
    pub codes: [FaultCode; 3],
    /// Executions of a segment whose (sequence, CRC) is not the host's
    /// segment of that sequence number, or of the deliberately bad segment.
    pub corrupted_executions: usize,
    /// Every node executed segments 0..n in order with the host's CRCs.
    pub executed_whole_plan: bool,
    /// First fault on any node (true ns).
    pub first_fault_ns: Option<u64>,
    /// The stop's jerk budget B_s (m/s³): max(limit, plan's jerk · cap³ +
    /// limit/2), within the jerk ceiling.
    pub stop_jerk_bound: f64,
    /// Largest delay from an Emergency frame reaching a running node to its
    /// first stopping control tick, in ticks.
    pub emergency_to_stop_ticks: Option<f64>,
    /// Fault codes carried by Emergency frames and heartbeats on the bus
    /// (sending node, code).
    #[serde(serialize_with = "node_code_names")]
    pub emergency_codes: Vec<(u8, FaultCode)>,
    #[serde(serialize_with = "node_code_names")]
    pub heartbeat_codes: Vec<(u8, FaultCode)>,
    /// The last TimeSync on the bus (true ns) and the first LostSync fault.
    pub last_sync_ns: Option<u64>,
    pub lost_sync_ns: Option<u64>,
    /// Why the host's session gave up, if it did.
    pub host_error: Option<String>,
    pub retransmits: u64,
    /// Segment rejections counted by the nodes, by reason index.
    pub rejects: [u32; Reject::TABLE.len()],
    /// What the fault injector did.
    pub injected: FaultStats,
    pub tick_ns: u64,
    /// True time (ns) of the first Running tick of any node.
    pub start_ns: Option<u64>,
    /// The drives' sync (and peer heartbeat) timeout (ns).
    pub sync_timeout_ns: u64,
}

fn code_names<S: Serializer>(codes: &[FaultCode; 3], s: S) -> Result<S::Ok, S::Error> {
    s.collect_seq(codes.iter().map(|c| c.name()))
}

fn node_code_names<S: Serializer>(codes: &[(u8, FaultCode)], s: S) -> Result<S::Ok, S::Error> {
    s.collect_seq(codes.iter().map(|(n, c)| (n, c.name())))
}

impl Default for RunReport {
    /// No run: zeros, no faults, an empty execution list for each node.
    fn default() -> Self {
        Self {
            rms_error_m: [0.0; 3],
            max_error_m: [0.0; 3],
            peak_torque_nm: [0.0; 3],
            bus_load: 0.0,
            frames: 0,
            faults: Vec::new(),
            completed: false,
            segment_bus_load: 0.0,
            segment_frames: 0,
            segments: 0,
            plan_time_s: 0.0,
            duration_s: 0.0,
            start_skew_us: 0.0,
            tracking_samples: 0,
            executed: vec![Vec::new(); 3],
            stop_s: None,
            stopped_within_buffer: false,
            max_stop_jerk: [0.0; 3],
            stop_ramp_s: 0.0,
            override_cap: 1.0,
            fault_run: None,
            vibration: None,
        }
    }
}

impl RunReport {
    /// The tracking figures.
    pub fn tracking(&self) -> Tracking {
        Tracking {
            rms_error_m: self.rms_error_m,
            max_error_m: self.max_error_m,
            samples: self.tracking_samples,
        }
    }

    /// The override cap the drives were configured with (the largest of
    /// `configs`; 1 without any): [`RunReport::override_cap`].
    pub fn override_cap_of(configs: impl IntoIterator<Item = DriveConfig>) -> f64 {
        configs
            .into_iter()
            .map(|c| c.override_cap as f64)
            .fold(1.0, f64::max)
    }

    /// Sets the tracking figures.
    pub fn set_tracking(&mut self, t: &Tracking) {
        self.rms_error_m = t.rms_error_m;
        self.max_error_m = t.max_error_m;
        self.tracking_samples = t.samples;
    }

    /// The largest stop jerk of any drive (m/s³).
    pub fn worst_stop_jerk(&self) -> f64 {
        self.max_stop_jerk.iter().copied().fold(0.0, f64::max)
    }

    /// The largest tracking error of any joint (m).
    pub fn worst_error_m(&self) -> f64 {
        self.max_error_m.iter().copied().fold(0.0, f64::max)
    }

    /// The executed lists, per node, from (node, sequence, CRC) triples.
    pub fn executed_by_node(
        executed: impl IntoIterator<Item = (u8, u16, u32)>,
    ) -> Vec<Vec<(u16, u32)>> {
        let mut out = vec![Vec::new(); 3];
        for (node, seq, crc) in executed {
            if let Some(v) = out.get_mut((node as usize).wrapping_sub(1)) {
                v.push((seq, crc));
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_fault_run_figures_are_in_the_json_only_for_a_fault_run() {
        let mut r = RunReport::default();
        let plain = serde_json::to_value(&r).unwrap();
        assert!(plain.get("fault_run").is_none(), "{plain}");
        assert_eq!(plain["stop_s"], serde_json::Value::Null);
        r.fault_run = Some(FaultRunFigures {
            ending: Ending::Stopped,
            codes: [
                FaultCode::LostSync,
                FaultCode::PeerEmergency,
                FaultCode::None,
            ],
            corrupted_executions: 0,
            executed_whole_plan: false,
            first_fault_ns: Some(2_000_000_000),
            stop_jerk_bound: 5.0,
            emergency_to_stop_ticks: Some(0.5),
            emergency_codes: vec![(1, FaultCode::LostSync)],
            heartbeat_codes: vec![(2, FaultCode::PeerEmergency)],
            last_sync_ns: None,
            lost_sync_ns: None,
            host_error: None,
            retransmits: 0,
            rejects: [0; Reject::TABLE.len()],
            injected: FaultStats::default(),
            tick_ns: 1_000_000,
            start_ns: Some(277_075_827),
            sync_timeout_ns: 250_000_000,
        });
        let f = &serde_json::to_value(&r).unwrap()["fault_run"];
        assert_eq!(f["ending"], "Stopped");
        assert_eq!(
            f["codes"],
            serde_json::json!(["LostSync", "PeerEmergency", "None"])
        );
        assert_eq!(f["emergency_codes"], serde_json::json!([[1, "LostSync"]]));
        assert_eq!(f["first_fault_ns"], 2_000_000_000u64);
    }
}
