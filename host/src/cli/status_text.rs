//! The drives' status for people, one line per node: what `status` and
//! `clear` print.

use triquint_cli_common::outln;
use triquint_link::MachineStatus;

use crate::exit::CliResult;

fn fmt_mm(x: Option<f64>) -> String {
    x.map_or("unknown".to_string(), |x| format!("{x:.3} mm"))
}

/// The status for people, one line per node.
pub fn print_text(s: &MachineStatus) -> CliResult {
    for n in &s.nodes {
        if !n.heard {
            outln!("axis {} (node {}): silent", n.axis, n.id)?;
            continue;
        }
        let fault = if n.fault.code == 0 {
            String::new()
        } else {
            format!(
                ", fault {} ({}): {}",
                n.fault.name, n.fault.code, n.fault.hint
            )
        };
        let feed = match (n.held, n.override_active) {
            (true, true) => ", held, override set",
            (true, false) => ", held",
            (false, true) => ", override set",
            (false, false) => "",
        };
        outln!(
            "axis {} (node {}): {}, {}, position {}, queue {}, {}{}{}",
            n.axis,
            n.id,
            n.state.unwrap_or("?"),
            n.homing,
            fmt_mm(n.joint_position_mm),
            n.queue_depth,
            if n.synced { "synced" } else { "not synced" },
            feed,
            fault
        )?;
    }
    match s.platform_mm {
        Some(p) => outln!("platform at ({:.3}, {:.3}, {:.3}) mm", p[0], p[1], p[2])?,
        None => outln!("platform position unknown (every axis must be homed and report)")?,
    }
    Ok(())
}
