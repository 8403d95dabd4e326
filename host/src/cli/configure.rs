//! `triquint configure --iface IFACE`: writes the machine file's
//! configuration to the drives and checks it, without motion. A drive that
//! holds a configuration takes tighter ceilings and travel, never wider
//! ones; `--unlock-ceilings` is the maintenance path that raises them
//! (each drive's maintenance window, `UnlockCeilings`, then the commit;
//! docs/safety.md, "The ceiling lock"). Exit 0 configured, 8 refused
//! (`CeilingsLocked`, a drive faulted or not Idle), 4 silent.

use clap::Args;
use triquint_cli_common::outln;
use triquint_shared::machine::Machine;

use crate::cli::bus_args::BusArgs;
use crate::exit::CliResult;
use crate::ops::configure::configure;
use crate::ops::shown::nodes_arg;

#[derive(Args, Debug)]
pub struct ConfigureArgs {
    #[command(flatten)]
    pub bus: BusArgs,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
    /// Maintenance, with the machine at rest: let the drives take raised
    /// ceilings or wider travel from the machine file (without it they
    /// refuse them, CeilingsLocked).
    #[arg(long)]
    pub unlock_ceilings: bool,
}

pub fn run(args: &ConfigureArgs, machine: &Machine) -> CliResult {
    let bus = args.bus.bus(machine)?;
    configure(machine, &bus, args.unlock_ceilings)?;
    let c = machine.effective_ceilings();
    outln!(
        "{}{}: drives configured; ceilings v {} m/s, a {} m/s², j {} m/s³, torque {} N·m{}",
        bus.iface,
        nodes_arg(bus.ids),
        c.velocity,
        c.acceleration,
        c.jerk,
        c.torque,
        if args.unlock_ceilings {
            " (maintenance: raised ones taken)"
        } else {
            ""
        }
    )?;
    Ok(())
}
