//! `triquint hold --iface IFACE`: feed hold. A running plan slows to rest
//! on its path (the stop ramp) and waits there for `triquint resume`; before
//! Start the hold is kept and the plan starts held. Exit 0 when every drive
//! took it, 8 when one refused (faulted), 4 when one was silent.

use clap::Args;
use triquint_link::Feed;

use crate::cli::drives_args::DrivesArgs;
use crate::exit::CliResult;

#[derive(Args, Debug)]
pub struct HoldArgs {
    #[command(flatten)]
    pub drives: DrivesArgs,
}

pub fn run(args: &HoldArgs) -> CliResult {
    crate::cli::feed::run(&args.drives, Feed::Hold, "feed hold")
}
