//! `triquint stop --iface IFACE [--quick]`: a running (or held) plan stops
//! along its path with the stop ramp (`--quick`: the quick-stop ramp) and
//! the drives go Idle, queue flushed, no fault (the upload ends "stopped",
//! exit 7); an armed plan is disarmed. Not an emergency stop (`estop`).
//! Exit 0 when every drive took it, 4 when one was silent.

use clap::Args;
use triquint_link::Feed;

use crate::exit::CliResult;

#[derive(Args, Debug)]
pub struct StopArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
    /// Node ids of the drives of axes 1, 2, 3 (1 to 15).
    #[arg(long, default_value = "1,2,3", value_name = "A,B,C")]
    pub nodes: String,
    /// Stop with the quick-stop ramp (three times the jerk budget).
    #[arg(long)]
    pub quick: bool,
}

pub fn run(args: &StopArgs) -> CliResult {
    let (f, what) = if args.quick {
        (Feed::QuickStop, "quick stop")
    } else {
        (Feed::Stop, "stop")
    };
    crate::cli::feed::run(&args.iface, &args.nodes, f, what)
}
