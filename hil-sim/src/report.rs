//! The JSON fields of one simulated run, written by both `triquint simulate
//! --json` (in process) and `triquint-sim --report` (on SocketCAN), so the
//! two reports cannot drift apart.

use serde::Serialize;

use crate::sim::FaultEvent;

/// A fault a node reported, at `t_s` seconds of plan time.
#[derive(Clone, Debug, Serialize)]
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

/// The fields every run report has.
#[derive(Clone, Debug, Serialize)]
pub struct RunJson {
    pub rms_error_m: [f64; 3],
    pub max_error_m: [f64; 3],
    pub peak_torque_nm: [f64; 3],
    pub bus_load: f64,
    pub frames: u64,
    pub faults: Vec<JsonFault>,
    pub completed: bool,
}
