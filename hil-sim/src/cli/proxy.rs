//! `triquint-sim proxy --a IFACE --b IFACE [faults]`: bridges two CAN
//! interfaces both ways through the seeded fault model of the in-process bus
//! (`triquint_sim::proxy`), e.g. the host on vcan0 and the drives on vcan1.
//! Runs until SIGINT/SIGTERM, then writes its counts. Exit status: 0 stopped
//! by a signal, 2 bad input, 4 interface or bus failure.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use triquint_sim::faults::{Fault, FaultWindow};
use triquint_sim::proxy::{self, A, B, Bridge};

use triquint_cli_common::{CliError, CliResult};

use crate::stop_on_signals;

/// A side of the bridge.
#[derive(Clone, Copy, Debug, PartialEq, Eq, ValueEnum)]
pub enum Side {
    A,
    B,
}

#[derive(Args, Debug)]
pub struct ProxyArgs {
    /// Interface of side A (the host's side; fault windows are timed from its first frame).
    #[arg(long, value_name = "IFACE")]
    a: String,
    /// Interface of side B (the drives' side).
    #[arg(long, value_name = "IFACE")]
    b: String,
    /// CAN-FD sockets on both sides (both interfaces need MTU 72).
    #[arg(long)]
    fd: bool,
    /// Seed of the fault decisions.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Probability that a frame is lost.
    #[arg(long, default_value_t = 0.0, value_name = "P")]
    loss: f64,
    /// Probability that a segment part gets one payload bit flipped.
    #[arg(long, default_value_t = 0.0, value_name = "P")]
    corrupt: f64,
    /// Probability that a frame is delivered twice.
    #[arg(long, default_value_t = 0.0, value_name = "P")]
    dup: f64,
    /// Probability that a frame is delivered after the next one.
    #[arg(long, default_value_t = 0.0, value_name = "P")]
    reorder: f64,
    /// Extra latency of every frame (µs).
    #[arg(long, default_value_t = 0, value_name = "US")]
    delay_us: u64,
    /// Further latency of each frame, uniform in 0..=J (µs).
    #[arg(long, default_value_t = 0, value_name = "J")]
    jitter_us: u64,
    /// This side is bus-off in the window (neither sends nor receives).
    #[arg(long, value_name = "SIDE")]
    bus_off: Option<Side>,
    /// Only frames with identifiers in LO-HI (hex with 0x, or decimal).
    #[arg(long, default_value = "0x000-0x7FF", value_name = "LO-HI")]
    ids: String,
    /// Window start, ms after side A's first frame.
    #[arg(long, default_value_t = 0.0, value_name = "MS")]
    from_ms: f64,
    /// Window end, ms after side A's first frame (default: never).
    #[arg(long, value_name = "MS")]
    until_ms: Option<f64>,
    /// Write the counts (JSON) here on exit.
    #[arg(long, value_name = "FILE.json")]
    report: Option<PathBuf>,
}

fn parse_id(text: &str) -> Option<u16> {
    let t = text.trim();
    let v = match t.strip_prefix("0x").or_else(|| t.strip_prefix("0X")) {
        Some(h) => u16::from_str_radix(h, 16).ok()?,
        None => t.parse().ok()?,
    };
    (v <= 0x7FF).then_some(v)
}

fn parse_ids(text: &str) -> CliResult<core::ops::RangeInclusive<u16>> {
    let err = || {
        CliError::bad_input(format!(
            "--ids {text}: not LO-HI with 11-bit identifiers, LO ≤ HI (e.g. 0x100-0x110)"
        ))
    };
    let (lo, hi) = text.split_once('-').ok_or_else(err)?;
    match (parse_id(lo), parse_id(hi)) {
        (Some(lo), Some(hi)) if lo <= hi => Ok(lo..=hi),
        _ => Err(err()),
    }
}

fn ms_to_ns(flag: &str, ms: f64) -> CliResult<u64> {
    if !(ms.is_finite() && ms >= 0.0) {
        return Err(CliError::bad_input(format!(
            "{flag} {ms}: must be a time ≥ 0 ms"
        )));
    }
    Ok((ms * 1e6).round() as u64)
}

/// The fault schedule the options describe.
fn schedule(args: &ProxyArgs) -> CliResult<Vec<FaultWindow>> {
    for (flag, p) in [
        ("--loss", args.loss),
        ("--corrupt", args.corrupt),
        ("--dup", args.dup),
        ("--reorder", args.reorder),
    ] {
        if !(0.0..=1.0).contains(&p) {
            return Err(CliError::bad_input(format!(
                "{flag} {p}: must be a probability in 0..1"
            )));
        }
    }
    let from = ms_to_ns("--from-ms", args.from_ms)?;
    let until = match args.until_ms {
        Some(ms) => ms_to_ns("--until-ms", ms)?,
        None => u64::MAX,
    };
    if until <= from {
        return Err(CliError::bad_input(format!(
            "--until-ms {}: must be after --from-ms {}",
            args.until_ms.unwrap_or_default(),
            args.from_ms
        )));
    }
    let ids = parse_ids(&args.ids)?;
    let mut faults = Vec::new();
    if args.loss > 0.0 {
        faults.push(Fault::Loss { rate: args.loss });
    }
    if args.corrupt > 0.0 {
        faults.push(Fault::Corrupt { rate: args.corrupt });
    }
    if args.dup > 0.0 {
        faults.push(Fault::Duplicate { rate: args.dup });
    }
    if args.reorder > 0.0 {
        faults.push(Fault::Reorder { rate: args.reorder });
    }
    if args.delay_us > 0 {
        faults.push(Fault::Late {
            ns: args.delay_us * 1000,
        });
    }
    if args.jitter_us > 0 {
        faults.push(Fault::Jitter {
            max_ns: args.jitter_us * 1000,
        });
    }
    if let Some(side) = args.bus_off {
        faults.push(Fault::BusOff {
            station: if side == Side::A { A } else { B },
        });
    }
    Ok(faults
        .into_iter()
        .map(|f| FaultWindow::new(f, from, until).on_ids(ids.clone()))
        .collect())
}

pub fn run(args: &ProxyArgs) -> CliResult {
    let windows = schedule(args)?;
    let stop = stop_on_signals()?;
    let ports = proxy::open(&args.a, &args.b, args.fd).map_err(CliError::device)?;
    triquint_cli_common::errln!(
        "triquint-sim proxy: {} <-> {} ({}), seed {}, {} fault windows; SIGINT/SIGTERM to stop",
        args.a,
        args.b,
        if args.fd { "CAN-FD" } else { "classic CAN" },
        args.seed,
        windows.len()
    );
    let mut bridge = Bridge::new(windows, args.seed);
    let result = proxy::run(ports, &mut bridge, &stop);
    let r = &bridge.report;
    triquint_cli_common::errln!(
        "triquint-sim proxy: A→B {} in, {} out; B→A {} in, {} out; {:?}",
        r.from_a,
        r.to_b,
        r.from_b,
        r.to_a,
        r.faults
    );
    if let Some(path) = &args.report {
        let text = serde_json::to_string_pretty(r).unwrap_or_default();
        super::write_report(path, &text, &mut std::io::stdout().lock())?;
    }
    result.map_err(CliError::device)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct T {
        #[command(flatten)]
        p: ProxyArgs,
    }

    fn sched(extra: &[&str]) -> Result<Vec<FaultWindow>, String> {
        let mut argv = vec!["x", "--a", "vcan0", "--b", "vcan1"];
        argv.extend_from_slice(extra);
        schedule(&T::parse_from(argv).p).map_err(|e| e.message)
    }

    #[test]
    fn options_become_one_window_per_fault() {
        let w = sched(&[
            "--loss",
            "0.02",
            "--dup",
            "0.1",
            "--jitter-us",
            "200",
            "--ids",
            "0x100-0x18F",
            "--from-ms",
            "300",
            "--until-ms",
            "900",
        ])
        .unwrap();
        assert_eq!(w.len(), 3);
        assert_eq!(w[0].fault, Fault::Loss { rate: 0.02 });
        assert_eq!(w[2].fault, Fault::Jitter { max_ns: 200_000 });
        assert!(w.iter().all(|w| w.ids == (0x100..=0x18F)
            && w.from_ns == 300_000_000
            && w.until_ns == 900_000_000));
        let b = sched(&["--bus-off", "b"]).unwrap();
        assert_eq!(b[0].fault, Fault::BusOff { station: B });
        assert_eq!(b[0].until_ns, u64::MAX);
        assert!(sched(&[]).unwrap().is_empty());
    }

    #[test]
    fn bad_options_are_one_line_naming_the_option() {
        for (argv, flag) in [
            (&["--loss", "1.5"][..], "--loss"),
            (&["--corrupt", "NaN"], "--corrupt"),
            (&["--ids", "0x100"], "--ids"),
            (&["--ids", "0x200-0x100"], "--ids"),
            (&["--ids", "0x100-0x800"], "--ids"),
            (&["--from-ms=-1"], "--from-ms"),
            (&["--from-ms", "10", "--until-ms", "5"], "--until-ms"),
        ] {
            let e = sched(argv).unwrap_err();
            assert!(e.starts_with(flag) && !e.contains('\n'), "{e}");
        }
    }
}
