//! `hold`, `resume`, `stop` and `override` on the command line: send the
//! command to every drive ([`crate::ops::feed`]), print each drive's
//! answer, exit with the verdict.

use triquint_cli_common::outln;
use triquint_link::Feed;
use triquint_shared::protocol::{FaultCode, State};

use crate::cli::drives_args::DrivesArgs;
use crate::exit::CliResult;
use crate::ops::feed::{send_feed, verdict};
use crate::ops::listen::open;
use crate::ops::shown::{Drive, percent, state_name};

/// `what` to every drive on `iface`: prints each drive's answer; exit 0 when
/// every drive did it, 8 when one refused (the cap for an override above
/// it), 4 when one did not answer.
pub fn run(drives: &DrivesArgs, f: Feed, what: &str) -> CliResult {
    let ids = drives.ids()?;
    let iface = drives.iface.as_str();
    let mut port = open(iface)?;
    let sent = send_feed(&mut port, ids, f)?;
    match sent.host_us {
        Some(t) => outln!("{what} at host time {t} µs (from the running upload's time sync)")?,
        None => outln!("{what} on receipt (no time sync on the bus: no upload is running)")?,
    }
    for (i, a) in sent.answers.iter().enumerate() {
        match a {
            Some(a) => outln!(
                "{}: {} → {}{}",
                Drive::of(ids, i),
                sent.states_before[i].map_or("unknown", State::name),
                state_name(a.state),
                match FaultCode::from_u8(a.result) {
                    Some(FaultCode::None) => String::new(),
                    Some(c) => format!(", refused: {}", c.name()),
                    None => format!(", refused: code {}", a.result),
                }
            )?,
            None => outln!("{}: no answer", Drive::of(ids, i))?,
        }
    }
    verdict(iface, ids, f, &sent.answers)?;
    if let (Feed::Override(_), Some(a)) = (f, sent.answers.iter().flatten().next()) {
        outln!("cap of the configured plan: {} %", percent(a.value))?;
    }
    let latched = sent.answers.iter().flatten().all(|a| {
        matches!(
            State::from_u8(a.state),
            Some(State::Idle | State::Loaded | State::Armed)
        )
    });
    if latched && matches!(f, Feed::Hold | Feed::Override(_)) {
        outln!("no plan is running: kept, the next plan starts with it")?;
    }
    Ok(())
}
