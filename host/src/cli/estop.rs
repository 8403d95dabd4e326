//! `triquint estop --iface IFACE`: the host's emergency frame (Emergency
//! from node 0). Every drive stops: a moving one along its path within its
//! stop time, an idle one goes to Fault; `triquint clear` afterwards.

use crate::cli::listen::open;
use crate::cli::send::send_emergency;
use crate::exit::{CliError, CliResult};
use clap::Args;
use triquint_cli_common::outln;

#[derive(Args, Debug)]
pub struct EstopArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
}

pub fn run(args: &EstopArgs) -> CliResult {
    let mut port = open(&args.iface)?;
    // The controller's queue may be full for a moment: tried for 100 ms.
    if send_emergency(&mut port)? {
        outln!("emergency stop sent on {}", args.iface)?;
        return Ok(());
    }
    Err(CliError::device(format!(
        "{}: the emergency frame could not be sent (transmit queue full)",
        args.iface
    )))
}
