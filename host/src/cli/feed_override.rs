//! `triquint override PERCENT --iface IFACE`: feed override, the plan's
//! speed along its path in per cent (100 = as planned), changed smoothly
//! from where it is; it persists (across a hold, and for the next plan).
//! Above the configured plan's cap (computed by `upload`) every drive
//! refuses it and the message gives the cap: exit 8. Exit 2 for a
//! percentage that is not a number in 0.1–3200.

use clap::Args;
use triquint_link::Feed;

use crate::cli::drives_args::DrivesArgs;
use crate::exit::{CliError, CliResult};
use crate::ops::shown::percent;

#[derive(Args, Debug)]
pub struct OverrideArgs {
    /// Feed override in per cent of the planned speed (e.g. 50, 110).
    #[arg(value_name = "PERCENT")]
    pub percent: String,
    #[command(flatten)]
    pub drives: DrivesArgs,
}

/// "50", "50%", "117.5" → per mille (1–32000).
pub fn parse_percent(s: &str) -> CliResult<u16> {
    let t = s.trim().trim_end_matches('%').trim();
    let p: f64 = t.parse().map_err(|_| {
        CliError::bad_input(format!("override {s}: not a percentage (e.g. 50 or 110)"))
    })?;
    let pm = (p * 10.0).round();
    if !(p.is_finite() && (1.0..=32_000.0).contains(&pm)) {
        return Err(CliError::bad_input(format!(
            "override {s}: must be 0.1 to 3200 per cent"
        )));
    }
    Ok(pm as u16)
}

pub fn run(args: &OverrideArgs) -> CliResult {
    let pm = parse_percent(&args.percent)?;
    let what = format!("feed override {} %", percent(pm as u32));
    crate::cli::feed::run(&args.drives, Feed::Override(pm), &what)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentages_parse_to_per_mille_and_bad_ones_are_bad_input() {
        assert_eq!(parse_percent("50").unwrap(), 500);
        assert_eq!(parse_percent("117.7%").unwrap(), 1177);
        assert_eq!(parse_percent(" 100 ").unwrap(), 1000);
        for bad in ["", "fast", "0", "-10", "NaN", "inf", "3200.1", "0.01"] {
            let e = parse_percent(bad).unwrap_err();
            assert_eq!(
                e.status,
                triquint_cli_common::exit::Status::BadInput,
                "{bad}"
            );
        }
    }
}
