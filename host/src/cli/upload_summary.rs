//! What `upload` and `move-to` print of a run, and the exit it ends with.

use triquint_cli_common::outln;

use crate::exit::{CliError, CliResult, Status};
use crate::ops::bus::Bus;
use crate::ops::run::UploadSummary;
use crate::ops::shown::drive_name;

/// Prints the summary; exit 0 only when every node completed without a fault.
pub fn show(s: &UploadSummary, bus: &Bus, json: bool) -> CliResult {
    if json {
        outln!(
            "{}",
            serde_json::to_string(s).map_err(|e| CliError::device(e.to_string()))?
        )?;
    } else {
        outln!(
            "{} segments over {} ({}): {} frames ({} segment frames, {} retransmissions); all acknowledged after {:.3} s, done after {:.3} s",
            s.segments,
            bus.iface,
            if bus.fd { "CAN-FD" } else { "classic CAN" },
            s.frames_sent,
            s.segment_frames,
            s.retransmits,
            s.upload_s,
            s.total_s
        )?;
        for n in &s.nodes {
            outln!(
                "{}: {}, fault {} ({})",
                drive_name(bus.ids, n.node),
                n.state,
                n.fault_name,
                n.fault
            )?;
        }
    }
    if s.completed && s.faults.is_empty() {
        return Ok(());
    }
    if s.stopped && s.faults.is_empty() {
        return Err(CliError::new(
            Status::Cancelled,
            "stopped on request before the plan's end: at rest on its path, every drive Idle",
        ));
    }
    Err(CliError::motion_fault(match s.faults.first() {
        Some(f) => format!(
            "{} faulted: {} ({})",
            drive_name(bus.ids, f.node),
            f.name,
            f.code
        ),
        None => "the plan did not complete".to_string(),
    }))
}
