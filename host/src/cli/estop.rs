//! `triquint estop --iface IFACE`: the host's emergency frame (Emergency
//! from node 0). Every drive stops: a moving one along its path within its
//! stop time, an idle one goes to Fault; `triquint clear` afterwards.

use clap::Args;
use triquint_link::CanPort;
use triquint_shared::protocol::{Emergency, FaultCode, State};

use crate::cli::listen::open;
use crate::exit::{CliError, CliResult};

#[derive(Args, Debug)]
pub struct EstopArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
}

pub fn run(args: &EstopArgs) -> CliResult {
    let mut port = open(&args.iface)?;
    let f = Emergency {
        code: FaultCode::HostEmergency as u8,
        state: State::Fault as u8,
        segment: 0,
        plan_time_us: 0,
    }
    .to_frame(0);
    // The controller's queue may be full for a moment: try for 100 ms.
    for _ in 0..100 {
        if CanPort::send(&mut port, &f).map_err(CliError::device)? {
            println!("emergency stop sent on {}", args.iface);
            return Ok(());
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
    Err(CliError::device(format!(
        "{}: the emergency frame could not be sent (transmit queue full)",
        args.iface
    )))
}
