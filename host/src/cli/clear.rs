//! `triquint clear --iface IFACE`: faulted drives back to Idle
//! (ClearFault to each), then their states as heard. Homing survives it.
//! Exit 0 when every drive is out of Fault, 4 if one is silent, 5 if one
//! stays faulted.

use std::time::{Duration, Instant};

use clap::Args;
use triquint_cli_common::outln;
use triquint_link::Listener;
use triquint_shared::machine::Machine;
use triquint_shared::protocol::{CommandCode, State};

use crate::cli::bus_args::node_ids;
use crate::cli::status_text::print_text;
use crate::exit::{CliError, CliResult};
use crate::ops::listen::{listen, open};
use crate::ops::send::send_command;
use crate::ops::shown::drive_name;

#[derive(Args, Debug)]
pub struct ClearArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
    /// Node ids of the drives of axes 1, 2, 3 (1 to 15) [default: the
    /// machine file's `axis.N.node_id`].
    #[arg(long, value_name = "A,B,C")]
    pub nodes: Option<String>,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

pub fn run(args: &ClearArgs, machine: &Machine) -> CliResult {
    let ids = node_ids(args.nodes.as_deref(), machine)?;
    let mut port = open(&args.iface)?;
    let mut l = Listener::new(ids);
    listen(&mut port, &mut l, Duration::from_millis(500), false)?;
    if let Some(v) = l.nodes.0.iter().find(|v| v.heartbeat_at.is_none()) {
        return Err(CliError::device(format!(
            "{}: {} sent no heartbeat within 0.5 s",
            args.iface,
            drive_name(ids, v.id)
        )));
    }
    let faulted: Vec<u8> = l
        .nodes
        .0
        .iter()
        .filter(|v| v.state == Some(State::Fault))
        .map(|v| v.id)
        .collect();
    for (k, id) in faulted.iter().enumerate() {
        send_command(&mut port, *id, CommandCode::ClearFault, 0xC0 | k as u8)?;
    }
    // Heartbeats after the clear: a fresh listener.
    let t0 = Instant::now();
    let mut after = Listener::new(ids);
    while t0.elapsed() < Duration::from_secs(1) {
        listen(&mut port, &mut after, Duration::from_millis(300), false)?;
        if after.all_heard() && after.nodes.all(|v| v.state != Some(State::Fault)) {
            break;
        }
        after = Listener::new(ids);
    }
    let s = after.status(&machine.robot);
    print_text(&s)?;
    match s.nodes.iter().find(|n| n.state == Some("Fault")) {
        None if faulted.is_empty() => {
            outln!("no drive was faulted")?;
            Ok(())
        }
        None => Ok(()),
        Some(n) => Err(CliError::motion_fault(format!(
            "{}: {} is still in Fault ({})",
            args.iface,
            drive_name(ids, n.id),
            n.fault.name
        ))),
    }
}
