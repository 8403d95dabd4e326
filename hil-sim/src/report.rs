//! The one report of a simulated run: written by `triquint simulate --json`
//! (in process), by `triquint-sim --report` (on SocketCAN, for every run
//! and, flattened, the last one), and carried by the in-process runs, so
//! the reports cannot drift apart. The field names are what the HIL suite
//! (`hil-sim/python/`) and `scripts/hil_figures.py` read.

use serde::Serialize;

use crate::metrics::Tracking;
use crate::sim::FaultEvent;

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

    /// Sets the tracking figures.
    pub fn set_tracking(&mut self, t: &Tracking) {
        self.rms_error_m = t.rms_error_m;
        self.max_error_m = t.max_error_m;
        self.tracking_samples = t.samples;
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
