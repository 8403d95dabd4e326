//! `triquint resume --iface IFACE`: a held plan (at rest or still slowing)
//! goes back to the override's speed along its path; before Start it
//! clears a kept hold. Exit 0 when every drive took it, 8 when one refused
//! (faulted), 4 when one was silent.

use clap::Args;
use triquint_link::Feed;

use crate::cli::drives_args::DrivesArgs;
use crate::exit::CliResult;

#[derive(Args, Debug)]
pub struct ResumeArgs {
    #[command(flatten)]
    pub drives: DrivesArgs,
}

pub fn run(args: &ResumeArgs) -> CliResult {
    crate::cli::feed::run(&args.drives, Feed::Resume, "resume")
}
