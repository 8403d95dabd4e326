//! The bus options of the commands that drive the machine (`upload`,
//! `move-to`, `home`, `configure`), checked into the operations' [`Bus`].

use clap::Args;
use triquint_shared::machine::Machine;

use crate::exit::{CliError, CliResult};
use crate::ops::bus::Bus;

/// The bus options shared by `upload`, `move-to`, `home` and `configure`.
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
    /// How long a node may stay silent before the command fails (s).
    #[arg(long, default_value_t = 2.0, value_name = "S")]
    pub timeout: f64,
    /// Node ids of the drives of axes 1, 2, 3 (1 to 15) [default: the
    /// machine file's `axis.N.node_id`].
    #[arg(long = "nodes", value_name = "A,B,C")]
    pub nodes_arg: Option<String>,
}

impl BusArgs {
    /// The bus the options give, with the machine's node ids and rate where
    /// none is given; bad input for an option out of range.
    pub fn bus(&self, machine: &Machine) -> CliResult<Bus> {
        let rate = self.rate_arg.unwrap_or(machine.drive.control_rate);
        triquint_cli_common::parse::check_rate("--rate", rate)?;
        if !(self.timeout.is_finite() && self.timeout > 0.0) {
            return Err(CliError::bad_input(format!(
                "--timeout {}: must be a positive number of seconds",
                self.timeout
            )));
        }
        let ids = node_ids(self.nodes_arg.as_deref(), machine)?;
        Ok(Bus {
            iface: self.iface.clone(),
            fd: self.fd,
            ids,
            rate,
            timeout_s: self.timeout,
        })
    }
}

/// The node ids of axes 1, 2, 3: `--nodes` when given, else the machine
/// file's `axis.N.node_id`.
pub fn node_ids(nodes_arg: Option<&str>, machine: &Machine) -> CliResult<[u8; 3]> {
    match nodes_arg {
        Some(n) => Ok(triquint_cli_common::parse::parse_axis_nodes("--nodes", n)?),
        None => Ok(machine.axes.each_ref().map(|a| a.node_id)),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exit::Status;

    fn args() -> BusArgs {
        BusArgs {
            iface: "vcan0".into(),
            fd: true,
            rate_arg: None,
            timeout: 2.0,
            nodes_arg: None,
        }
    }

    #[test]
    fn the_machine_fills_in_what_the_options_leave_open() {
        let mut machine = Machine::default();
        machine.drive.control_rate = 2000.0;
        for (a, id) in machine.axes.iter_mut().zip([7, 8, 9]) {
            a.node_id = id;
        }
        let b = args().bus(&machine).unwrap();
        assert_eq!((b.ids, b.rate, b.fd), ([7, 8, 9], 2000.0, true));
        let given = BusArgs {
            rate_arg: Some(4000.0),
            nodes_arg: Some("4,5,6".into()),
            ..args()
        };
        let b = given.bus(&machine).unwrap();
        assert_eq!((b.ids, b.rate), ([4, 5, 6], 4000.0));
    }

    #[test]
    fn an_option_out_of_range_is_bad_input() {
        let machine = Machine::default();
        for bad in [
            BusArgs {
                timeout: 0.0,
                ..args()
            },
            BusArgs {
                timeout: f64::NAN,
                ..args()
            },
            BusArgs {
                rate_arg: Some(10.0),
                ..args()
            },
            BusArgs {
                nodes_arg: Some("1,2".into()),
                ..args()
            },
        ] {
            let e = bad.bus(&machine).unwrap_err();
            assert_eq!(e.status, Status::BadInput, "{bad:?}: {}", e.message);
        }
    }
}
