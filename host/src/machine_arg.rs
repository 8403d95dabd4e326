//! `--machine FILE.toml` (alias `--robot`), offered by the commands that
//! use the machine, and what "a plan made for this machine" means.

use std::path::{Path, PathBuf};

use clap::Args;
use triquint_shared::machine::Machine;
use triquint_shared::plan::Plan;
use triquint_shared::readable::readable;

use crate::exit::{CliError, CliResult};

/// The machine file argument.
#[derive(Args, Debug, Clone, Default)]
pub struct MachineArg {
    /// Machine file (TOML, SI units; docs/machine.md): robot, homing,
    /// axes, ceilings. Without it, the paper's machine.
    #[arg(long = "machine", visible_alias = "robot", value_name = "FILE.toml")]
    pub file: Option<PathBuf>,
}

impl MachineArg {
    /// The machine (bad input, exit 2, when its file is refused).
    pub fn load(&self) -> CliResult<Machine> {
        triquint_cli_common::machine_file::load_machine(self.file.as_deref())
    }

    /// With a machine file, the plan must be one made for it (see
    /// [`plan_for_machine`]); without one, any plan.
    pub fn check_plan(&self, plan: &Plan, path: &Path) -> CliResult {
        match &self.file {
            Some(_) => plan_for_machine(plan, path, &self.load()?, &self.shown()),
            None => Ok(()),
        }
    }

    /// How messages name the machine.
    pub fn shown(&self) -> String {
        self.file
            .as_ref()
            .map_or("the default machine".to_string(), |f| {
                f.display().to_string()
            })
    }
}

/// A plan is for `machine` when it records the machine's robot, travel and
/// ceilings; otherwise bad input (exit 2) naming the first difference.
pub fn plan_for_machine(plan: &Plan, path: &Path, machine: &Machine, shown: &str) -> CliResult {
    let differs = |what: String| {
        Err(CliError::bad_input(format!(
            "{}: planned for another machine than {shown}: {what}",
            path.display()
        )))
    };
    if let Some((key, p, m)) = plan.robot.first_difference(&machine.robot) {
        return differs(format!(
            "robot.{key} is {} in the plan, {} in the machine",
            readable(p),
            readable(m)
        ));
    }
    let travel = machine.travel();
    for a in 0..3 {
        for (end, p, m) in [
            ("min", plan.travel.min[a], travel.min[a]),
            ("max", plan.travel.max[a], travel.max[a]),
        ] {
            if p.to_bits() != m.to_bits() {
                return differs(format!(
                    "axis {} travel {end} is {} mm in the plan, {} mm in the machine",
                    a + 1,
                    readable(p * 1e3),
                    readable(m * 1e3)
                ));
            }
        }
    }
    let ceilings = machine.effective_ceilings().named();
    for ((name, p), (_, m)) in plan.ceilings.named().into_iter().zip(ceilings) {
        if p.to_bits() != m.to_bits() {
            return differs(format!(
                "ceiling {name} is {} in the plan, {} in the machine",
                readable(p),
                readable(m)
            ));
        }
    }
    Ok(())
}

/// Before anything moves: the plan passes every row of the independent
/// check, so no drive is configured from a summary the segments do not
/// bear out (a tampered `max_abs`, limits above the ceilings).
pub fn verified(plan: &Plan, path: &Path) -> CliResult {
    let rows = triquint_planner::check(plan)
        .map_err(|e| CliError::bad_input(format!("{}: not a valid plan: {e}", path.display())))?;
    match rows.iter().find(|r| !r.ok) {
        None => Ok(()),
        Some(r) => Err(CliError::bad_input(format!(
            "{}: fails check, nothing sent: {} is {:e}, bound {:e} (`triquint check {}` lists every row)",
            path.display(),
            r.what,
            r.value,
            r.bound,
            path.display()
        ))),
    }
}
