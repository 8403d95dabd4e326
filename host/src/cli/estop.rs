//! `triquint estop --iface IFACE [--nodes A,B,C]`: the host's emergency
//! frame (Emergency from node 0). Every drive stops: a moving one along its
//! path with its stop ramp, an idle one goes to Fault; `triquint clear`
//! afterwards. The frame going out proves nothing, so the command waits
//! (`--wait`, 200 ms) for every drive to report it (Fault or Stopping with
//! the host's code), resending meanwhile: exit 0 when each did, 4 naming
//! the drives that did not.

use std::time::Duration;

use clap::Args;
use triquint_link::{EstopAnswer, EstopWatch, emergency_stop};
use triquint_shared::protocol::{FaultCode, State};

use crate::cli::drives_args::DrivesArgs;
use crate::exit::{CliError, CliResult};
use crate::ops::listen::open;
use crate::ops::shown::{Drive, drive_name, nodes_arg};
use triquint_cli_common::outln;

/// Longest `--wait` (ms): an emergency stop must not hang.
const MAX_WAIT_MS: u64 = 5_000;

#[derive(Args, Debug)]
pub struct EstopArgs {
    /// The drives that must confirm (the frame reaches every drive).
    #[command(flatten)]
    pub drives: DrivesArgs,
    /// How long to wait for every drive to confirm (ms, 1 to 5000).
    #[arg(long, default_value_t = 200, value_name = "MS")]
    pub wait: u64,
}

pub fn run(args: &EstopArgs) -> CliResult {
    let iface = args.drives.iface.as_str();
    // A bad --nodes is refused before anything is sent; a machine file that
    // cannot be read must not keep the frame from going out: it only says
    // which drives must confirm.
    let ids = match args.drives.ids() {
        Err(e) if args.drives.nodes.is_some() => return Err(e),
        ids => ids,
    };
    if !(1..=MAX_WAIT_MS).contains(&args.wait) {
        return Err(CliError::bad_input(format!(
            "--wait {}: must be 1 to {MAX_WAIT_MS} ms",
            args.wait
        )));
    }
    let mut port = open(iface)?;
    let watch = emergency_stop(
        &mut port,
        *ids.as_ref().unwrap_or(&DEFAULT_IDS),
        args.wait * 1000,
        || std::thread::sleep(Duration::from_millis(1)),
    )
    .map_err(|e| CliError::device(format!("{iface}: {e}")))?;
    outln!("emergency stop sent on {iface}")?;
    if let Err(e) = ids {
        return Err(CliError {
            message: format!(
                "{}; which drives had to confirm is unknown: check with `triquint status --iface {iface} --nodes A,B,C`",
                e.message
            ),
            ..e
        });
    }
    for line in lines(&watch) {
        outln!("{line}")?;
    }
    verdict(iface, &watch, args.wait)
}

/// The ids watched while the frame goes out when the machine file could
/// not be read (the frame itself reaches every drive).
const DEFAULT_IDS: [u8; 3] = [1, 2, 3];

/// A line per drive: what it reported.
pub fn lines(watch: &EstopWatch) -> Vec<String> {
    let ids = watch.ids();
    watch
        .answers()
        .iter()
        .enumerate()
        .map(|(i, a)| (Drive::of(ids, i), a))
        .map(|(d, a)| match a {
            Some(EstopAnswer::Heard { state }) => {
                format!("{d}: {} (HostEmergency)", state.name())
            }
            Some(EstopAnswer::Already { state, fault }) => format!(
                "{d}: already {} ({}): stopped, not known to have heard the emergency stop",
                state.name(),
                fault.name()
            ),
            None => format!("{d}: no answer"),
        })
        .collect()
}

/// Exit 0 when every drive confirmed, 4 naming those that did not.
pub fn verdict(iface: &str, watch: &EstopWatch, wait_ms: u64) -> CliResult {
    let silent = watch.silent();
    if silent.is_empty() {
        return Ok(());
    }
    let ids = watch.ids();
    let names: Vec<String> = silent.iter().map(|n| drive_name(ids, *n)).collect();
    let pronoun = if silent.len() == 1 { "it" } else { "they" };
    Err(CliError::device(format!(
        "{iface}: {} did not confirm the emergency stop within {wait_ms} ms (no Emergency frame, no heartbeat in {} or {} with {}): {} may be off the bus or still moving; check with `triquint status --iface {iface}{}`",
        names.join(", "),
        State::Fault.name(),
        State::Stopping.name(),
        FaultCode::HostEmergency.name(),
        pronoun,
        nodes_arg(ids),
    )))
}

#[cfg(test)]
mod tests {
    use super::*;
    use triquint_cli_common::exit::Status;
    use triquint_link::Received;
    use triquint_shared::protocol::Emergency;

    fn heard(w: &mut EstopWatch, node: u8, state: State, code: FaultCode) {
        let frame = Emergency {
            code: code as u8,
            state: state as u8,
            ramp_100us: 0,
            plan_time_us: 0,
        }
        .to_frame(node);
        w.take(&Received {
            frame,
            t_us: 0,
            own: false,
        });
    }

    #[test]
    fn a_drive_that_did_not_confirm_is_named_and_exit_4() {
        let mut w = EstopWatch::new([4, 5, 6]);
        heard(&mut w, 4, State::Fault, FaultCode::HostEmergency);
        heard(&mut w, 6, State::Stopping, FaultCode::HostEmergency);
        let e = verdict("vcan0", &w, 200).unwrap_err();
        assert_eq!(e.status, Status::Device);
        assert!(
            e.message
                .contains("axis 2 (node 5) did not confirm the emergency stop within 200 ms"),
            "{e}"
        );
        assert!(e.message.contains("--nodes 4,5,6"), "{e}");
        assert_eq!(
            lines(&w),
            [
                "axis 1 (node 4): Fault (HostEmergency)",
                "axis 2 (node 5): no answer",
                "axis 3 (node 6): Stopping (HostEmergency)"
            ]
        );
        heard(&mut w, 5, State::Fault, FaultCode::FollowingError);
        assert!(verdict("vcan0", &w, 200).is_ok());
        assert!(lines(&w)[1].starts_with("axis 2 (node 5): already Fault (FollowingError)"));
    }

    #[test]
    fn a_wait_out_of_range_or_bad_nodes_are_bad_input() {
        for (nodes, wait) in [
            ("1,2,3", 0),
            ("1,2,3", 5_001),
            ("1,1,3", 200),
            ("0,1,2", 200),
        ] {
            let args = EstopArgs {
                drives: DrivesArgs {
                    iface: "triquint-no-such-iface".into(),
                    nodes: Some(nodes.into()),
                    machine: Default::default(),
                },
                wait,
            };
            let e = run(&args).unwrap_err();
            assert_eq!(e.status, Status::BadInput, "{nodes} {wait}: {e}");
        }
    }

    /// An unreadable machine file only says which drives must confirm: the
    /// frame is still sent (here the interface is what fails, exit 4).
    #[test]
    fn an_unreadable_machine_file_does_not_keep_the_frame_back() {
        let args = EstopArgs {
            drives: DrivesArgs {
                iface: "triquint-no-such-iface".into(),
                nodes: None,
                machine: crate::machine_arg::MachineArg {
                    file: Some("triquint-no-such-machine.toml".into()),
                },
            },
            wait: 200,
        };
        let e = run(&args).unwrap_err();
        assert_eq!(e.status, Status::Device, "{e}");
        assert!(e.message.contains("triquint-no-such-iface"), "{e}");
    }
}
