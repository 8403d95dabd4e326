//! `triquint resume --iface IFACE`: a held plan (at rest or still slowing)
//! goes back to the override's speed along its path; before Start it
//! clears a kept hold. Exit 0 when every drive took it, 8 when one refused
//! (faulted), 4 when one was silent.

use clap::Args;
use triquint_link::Feed;

use crate::exit::CliResult;

#[derive(Args, Debug)]
pub struct ResumeArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
    /// Node ids of the drives of axes 1, 2, 3 (1 to 15).
    #[arg(long, default_value = "1,2,3", value_name = "A,B,C")]
    pub nodes: String,
}

pub fn run(args: &ResumeArgs) -> CliResult {
    crate::cli::feed::run(&args.iface, &args.nodes, Feed::Resume, "resume")
}
