//! The bus options of the commands that drive the machine, and what an
//! upload's error means for the person at the machine.

use clap::Args;
use triquint_link::UploadError;
use triquint_shared::machine::Machine;

use crate::exit::{CliError, CliResult};
use crate::ops::listen::nodes_arg;

/// The bus options shared by `upload` and `move-to`.
#[derive(Args, Debug, Clone)]
pub struct BusArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
    /// CAN-FD: 64-byte segment frames (the interface needs MTU 72).
    #[arg(long)]
    pub fd: bool,
    /// Control tick rate the drives are configured for (Hz), 1000 to
    /// 10000 [default: the machine file's `drive.control_rate`].
    #[arg(long = "rate", value_name = "HZ")]
    pub rate_arg: Option<f64>,
    /// How long a node may stay silent before the upload fails (s).
    #[arg(long, default_value_t = 2.0, value_name = "S")]
    pub timeout: f64,
    /// Node ids of the drives of axes 1, 2, 3 (1 to 15) [default: the
    /// machine file's `axis.N.node_id`].
    #[arg(long = "nodes", value_name = "A,B,C")]
    pub nodes_arg: Option<String>,
    /// What the flags leave open, from the machine ([`BusArgs::for_machine`]).
    #[arg(skip)]
    pub machine_ids: Option<[u8; 3]>,
    #[arg(skip)]
    pub machine_rate: Option<f64>,
}

impl BusArgs {
    /// The flags, with the machine's node ids and rate where none is given.
    pub fn for_machine(&self, machine: &Machine) -> Self {
        Self {
            machine_ids: Some(machine.axes.each_ref().map(|a| a.node_id)),
            machine_rate: Some(machine.drive.control_rate),
            ..self.clone()
        }
    }

    /// The node ids of `--nodes`, else the machine's, else 1, 2, 3.
    pub fn ids(&self) -> CliResult<[u8; 3]> {
        match &self.nodes_arg {
            Some(n) => triquint_cli_common::parse::parse_axis_nodes("--nodes", n),
            None => Ok(self.machine_ids.unwrap_or([1, 2, 3])),
        }
    }

    /// The control rate of `--rate`, else the machine's, else 1 kHz.
    pub fn rate(&self) -> f64 {
        self.rate_arg.or(self.machine_rate).unwrap_or(1000.0)
    }
}

pub fn check_bus_args(b: &BusArgs) -> CliResult {
    triquint_cli_common::parse::check_rate("--rate", b.rate())?;
    if !(b.timeout.is_finite() && b.timeout > 0.0) {
        return Err(CliError::bad_input(format!(
            "--timeout {}: must be a positive number of seconds",
            b.timeout
        )));
    }
    b.ids()?;
    Ok(())
}

/// An upload's error for people: refusals say what to run.
pub fn upload_error(e: UploadError, bus: &BusArgs) -> CliError {
    let iface = &bus.iface;
    let n = nodes_arg(bus.ids().unwrap_or([1, 2, 3]));
    match e {
        e if e.is_config() => CliError::bad_input(e),
        e @ (UploadError::Segment { .. } | UploadError::Unstreamable { .. }) => {
            CliError::bad_input(e)
        }
        e @ UploadError::Faulted { .. } => CliError::refused(format!(
            "{iface}: {e}: see why with `triquint status --iface {iface}{n}`, clear it with `triquint clear --iface {iface}{n}` (or upload with --clear)"
        )),
        e @ UploadError::NotHomed { .. } => CliError::refused(format!(
            "{iface}: {e}: run `triquint home --iface {iface}{n}` first"
        )),
        ref e @ UploadError::ArmTooFar { start_mm, .. } => CliError::refused(format!(
            "{iface}: {e}; run `triquint move-to {} {} {} --iface {iface}{n}` first",
            mm(start_mm[0]),
            mm(start_mm[1]),
            mm(start_mm[2])
        )),
        e @ (UploadError::Refused { .. } | UploadError::Version { .. }) => {
            CliError::refused(format!("{iface}: {e}"))
        }
        e @ UploadError::Timeout { .. } => {
            CliError::device(format!("{iface}: {e} (silent for {} s)", bus.timeout))
        }
        e => CliError::device(format!("{iface}: {e}")),
    }
}

/// A millimetre figure as a command argument: 3 decimals, no trailing zeros.
fn mm(x: f64) -> String {
    let s = format!("{x:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}
