//! `triquint stop --iface IFACE [--quick]`: a running (or held) plan stops
//! along its path with the stop ramp (`--quick`: the quick-stop ramp) and
//! the drives go Idle, queue flushed, no fault (the upload ends "stopped",
//! exit 7); an armed plan is disarmed. Not an emergency stop (`estop`).
//! Exit 0 when every drive took it, 4 when one was silent.

use clap::Args;
use triquint_link::Feed;

use crate::cli::drives_args::DrivesArgs;
use crate::exit::CliResult;

#[derive(Args, Debug)]
pub struct StopArgs {
    #[command(flatten)]
    pub drives: DrivesArgs,
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
    crate::cli::feed::run(&args.drives, f, what)
}
