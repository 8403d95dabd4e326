//! `triquint`: plan, check and run minimum-jerk trajectories for a 3-PUU robot.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use triquint_host::cli;
use triquint_host::exit::CliResult;

#[derive(Parser, Debug)]
#[command(name = "triquint", version, about, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Slider positions (mm) for a platform position (mm).
    Ik(cli::ik::IkArgs),
    /// Platform position (mm) for slider positions (mm), closed form.
    Fk(cli::fk::FkArgs),
    /// Motor torques (N·m) for joint positions, velocities, accelerations (SI).
    Torque(cli::torque::TorqueArgs),
    /// Plan a job: globally min-max-jerk C3 quintic joint trajectory.
    Plan(cli::plan::PlanArgs),
    /// Re-verify a plan: interpolation, C3, rest at the ends, every limit.
    Check(cli::check::CheckArgs),
    /// Tables and plots of a plan (like the paper's Tables 4/5/7/8, Figures 10/12).
    Report(cli::report::ReportArgs),
    /// Run a plan on the in-process virtual hardware.
    Simulate(cli::simulate::SimulateArgs),
    /// Upload and run a plan on the drives over SocketCAN.
    Upload(cli::upload::UploadArgs),
    /// Plan and run a point-to-point move from the reported position to X Y Z (mm).
    MoveTo(cli::move_to::MoveToArgs),
    /// Decode live bus traffic with the protocol declaration.
    Monitor(cli::monitor::MonitorArgs),
    /// What state each drive is in (read-only).
    Status(cli::status::StatusArgs),
    /// Home all three axes together on their limit switches.
    Home(cli::home::HomeArgs),
    /// Write the machine file's configuration to the drives, no motion;
    /// --unlock-ceilings to raise ceilings or widen travel (maintenance).
    Configure(cli::configure::ConfigureArgs),
    /// Return faulted drives to Idle.
    Clear(cli::clear::ClearArgs),
    /// Send the host's emergency stop frame; wait for every drive to confirm it.
    Estop(cli::estop::EstopArgs),
    /// Feed hold: a running plan slows to rest on its path and waits.
    Hold(cli::hold::HoldArgs),
    /// Resume a held plan along its path.
    Resume(cli::resume::ResumeArgs),
    /// Stop a running plan along its path (drives go Idle, no fault).
    Stop(cli::stop::StopArgs),
    /// Feed override in per cent of the planned speed (persists).
    Override(cli::feed_override::OverrideArgs),
    /// The flexible machine's modes at a pose or across the workspace, and a shaper.
    Resonance(cli::resonance::ResonanceArgs),
}

fn run(cli: Cli) -> CliResult {
    match &cli.command {
        Command::Ik(a) => cli::ik::run(a, &a.machine.load()?),
        Command::Fk(a) => cli::fk::run(a, &a.machine.load()?),
        Command::Torque(a) => cli::torque::run(a, &a.machine.load()?),
        Command::Plan(a) => cli::plan::run(a),
        Command::Check(a) => cli::check::run(a),
        Command::Report(a) => cli::report::run(a),
        Command::Simulate(a) => cli::simulate::run(a),
        Command::Upload(a) => cli::upload::run(a, &a.machine.load()?),
        Command::MoveTo(a) => cli::move_to::run(a, &a.machine.load()?),
        Command::Monitor(a) => cli::monitor::run(a, &a.machine.load()?),
        Command::Status(a) => cli::status::run(a, &a.machine.load()?),
        Command::Home(a) => cli::home::run(a, &a.machine.load()?),
        Command::Configure(a) => cli::configure::run(a, &a.machine.load()?),
        Command::Clear(a) => cli::clear::run(a, &a.machine.load()?),
        Command::Estop(a) => cli::estop::run(a),
        Command::Hold(a) => cli::hold::run(a),
        Command::Resume(a) => cli::resume::run(a),
        Command::Stop(a) => cli::stop::run(a),
        Command::Override(a) => cli::feed_override::run(a),
        Command::Resonance(a) => cli::resonance::run(a, &a.machine.load()?),
    }
}

fn main() -> ExitCode {
    triquint_cli_common::main_exit("triquint", run(Cli::parse()))
}
