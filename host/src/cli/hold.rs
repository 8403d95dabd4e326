//! `triquint hold --iface IFACE`: feed hold. A running plan slows to rest
//! on its path (the stop ramp) and waits there for `triquint resume`; before
//! Start the hold is kept and the plan starts held. Exit 0 when every drive
//! took it, 8 when one refused (faulted), 4 when one was silent.

use clap::Args;
use triquint_link::Feed;

use crate::exit::CliResult;

#[derive(Args, Debug)]
pub struct HoldArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
    /// Node ids of the drives of axes 1, 2, 3 (1 to 15).
    #[arg(long, default_value = "1,2,3", value_name = "A,B,C")]
    pub nodes: String,
}

pub fn run(args: &HoldArgs) -> CliResult {
    crate::cli::feed::run(&args.iface, &args.nodes, Feed::Hold, "feed hold")
}
