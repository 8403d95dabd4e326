//! `triquint status --iface IFACE [--json]`: what state each drive is in,
//! read-only (it sends nothing, so it never configures or moves a drive).
//! Exit 0 when every drive sends heartbeats, whatever its state; 4 if one
//! is silent.

use std::time::Duration;

use clap::Args;
use triquint_cli_common::outln;
use triquint_link::{Listener, MachineStatus};
use triquint_shared::Robot;
use triquint_shared::machine::Machine;

use crate::cli::bus_args::node_ids;
use crate::cli::status_text::print_text;
use crate::exit::{CliError, CliResult};
use crate::ops::listen::{listen, open};

#[derive(Args, Debug)]
pub struct StatusArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
    /// Node ids of the drives of axes 1, 2, 3 (1 to 15) [default: the
    /// machine file's `axis.N.node_id`].
    #[arg(long, value_name = "A,B,C")]
    pub nodes: Option<String>,
    /// Print exactly one JSON document.
    #[arg(long)]
    pub json: bool,
    /// How long to listen (s): long enough for a few heartbeats.
    #[arg(long, default_value_t = 0.5, value_name = "S")]
    pub wait: f64,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

/// Listens to the drives of `ids` for up to `wait` seconds.
pub fn machine_status(
    iface: &str,
    ids: [u8; 3],
    wait: f64,
    robot: &Robot,
) -> CliResult<MachineStatus> {
    let mut port = open(iface)?;
    let mut l = Listener::new(ids);
    listen(&mut port, &mut l, Duration::from_secs_f64(wait), true)?;
    Ok(l.status(robot))
}

pub fn run(args: &StatusArgs, machine: &Machine) -> CliResult {
    if !(args.wait.is_finite() && args.wait > 0.0 && args.wait <= 60.0) {
        return Err(CliError::bad_input(format!(
            "--wait {}: must be 0 to 60 seconds",
            args.wait
        )));
    }
    let ids = node_ids(args.nodes.as_deref(), machine)?;
    let s = machine_status(&args.iface, ids, args.wait, &machine.robot)?;
    if args.json {
        outln!(
            "{}",
            serde_json::to_string_pretty(&s).map_err(|e| CliError::device(e.to_string()))?
        )?;
    } else {
        print_text(&s)?;
    }
    match s.nodes.iter().find(|n| !n.heard) {
        None => Ok(()),
        Some(n) => Err(CliError::device(format!(
            "{}: node {} (axis {}) sent no heartbeat within {} s",
            args.iface, n.id, n.axis, args.wait
        ))),
    }
}
