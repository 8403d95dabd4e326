//! `triquint home --iface IFACE`: homes all three axes together, at the
//! same speed (moving one slider alone would push the platform sideways):
//! each axis stops at its own switch, latches the edge, backs off and sets
//! its zero from the switch height of the robot file's `[homing]` table.
//! The drives are configured first (homing needs its parameters). A line
//! per axis as it goes. Exit 0 all homed, 8 refused (a drive faulted, or
//! Home refused), 5 a homing fault, 4 silent or too slow.

use std::time::{Duration, Instant};

use clap::Args;
use triquint_cli_common::outln;
use triquint_link::Listener;
use triquint_shared::machine::Machine;
use triquint_shared::protocol::{CommandCode, FaultCode, State, flags};

use crate::cli::bus_args::BusArgs;
use crate::exit::{CliError, CliResult};
use crate::ops::configure::configure;
use crate::ops::listen::{drain, open};
use crate::ops::send::{send_command, send_emergency};
use crate::ops::shown::nodes_arg;

#[derive(Args, Debug)]
pub struct HomeArgs {
    #[command(flatten)]
    pub bus: BusArgs,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

/// The host's emergency frame: every drive stops.
fn estop(port: &mut triquint_link::SocketCanPort) -> CliResult {
    if send_emergency(port)? {
        return Ok(());
    }
    Err(CliError::device("the emergency frame could not be sent"))
}

/// What one axis is doing, for its progress line.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Progress {
    Homing { travelled_mm: f64 },
    Homed { after_s: f64 },
    Failed(FaultCode),
}

pub fn run(args: &HomeArgs, machine: &Machine) -> CliResult {
    let bus = &args.bus.bus(machine)?;
    let homing = &machine.homing;
    let ids = bus.ids;
    configure(machine, bus, false)?;
    let mut port = open(&bus.iface)?;
    // Every axis at once: the commands go out back to back (well within a tick).
    for (k, id) in ids.iter().enumerate() {
        send_command(&mut port, *id, CommandCode::Home, 0xB0 | k as u8)?;
    }
    let t0 = Instant::now();
    let limit = Duration::from_secs_f64(homing.timeout + 5.0);
    let mut l = Listener::new(ids);
    let mut start_pos: [Option<f32>; 3] = [None; 3];
    let mut shown: [Option<Progress>; 3] = [None; 3];
    // Homed counts only after the axis was seen homing (a heartbeat sent
    // before the Home arrived still says Idle).
    let mut seen_homing = [false; 3];
    // An axis whose switch was active once is not seeking any more (its
    // position also jumps when its new zero is set).
    let mut switch_seen = [false; 3];
    // Where each axis was when the first switch was reached: the skew bound.
    let mut at_first_switch: Option<[Option<f32>; 3]> = None;
    let mut next_line = Instant::now();
    let n = nodes_arg(ids);
    loop {
        // A few frames at a time, 20 ms apart: no busy loop next to the drives.
        std::thread::sleep(Duration::from_millis(20));
        drain(&mut port, &mut l)?;
        let now_s = t0.elapsed().as_secs_f64();
        let mut progress = [None; 3];
        for (i, v) in l.nodes.0.iter().enumerate() {
            if let Some(a) = v
                .last_answer
                .filter(|a| a.command == CommandCode::Home as u8)
                && a.result != 0
                && a.result != FaultCode::HomeSwitchActive as u8
            {
                let code = FaultCode::from_u8(a.result).map_or("unknown", FaultCode::name);
                return Err(CliError::refused(format!(
                    "{}: node {} refused Home: {code} (see `triquint status --iface {}{n}`)",
                    bus.iface, v.id, bus.iface
                )));
            }
            if start_pos[i].is_none() {
                start_pos[i] = v.position;
            }
            seen_homing[i] |= v.state == Some(State::Homing);
            switch_seen[i] |= v.flags & flags::SWITCH != 0 || v.homed && seen_homing[i];
            progress[i] = match (v.state, v.homed) {
                (Some(State::Fault), _) => Some(Progress::Failed(
                    FaultCode::from_u8(v.fault).unwrap_or(FaultCode::None),
                )),
                (Some(State::Idle), true) if seen_homing[i] => Some(Progress::Homed {
                    after_s: shown[i].map_or(now_s, |p| match p {
                        Progress::Homed { after_s } => after_s,
                        _ => now_s,
                    }),
                }),
                (Some(State::Homing), _) => Some(Progress::Homing {
                    travelled_mm: match (v.position, start_pos[i]) {
                        (Some(q), Some(q0)) => f64::from(q - q0).abs() * 1e3,
                        _ => 0.0,
                    },
                }),
                _ => None,
            };
        }
        if at_first_switch.is_none() && l.nodes.any(|v| v.flags & flags::SWITCH != 0) {
            at_first_switch = Some(l.nodes.0.map(|v| v.position));
        }
        if let Some(p0) = at_first_switch {
            for (i, v) in l.nodes.0.iter().enumerate() {
                let beyond = match (v.position, p0[i]) {
                    (Some(q), Some(q0)) => f64::from(q - q0).abs(),
                    _ => 0.0,
                };
                if v.state == Some(State::Homing) && !switch_seen[i] && beyond > homing.max_skew {
                    estop(&mut port)?;
                    return Err(CliError::motion_fault(format!(
                        "{}: axis {} (node {}) travelled {:.0} mm after the first switch without reaching its own (max_skew {:.0} mm): emergency stop; check its switch, then `triquint clear --iface {}{n}`",
                        bus.iface,
                        i + 1,
                        v.id,
                        beyond * 1e3,
                        homing.max_skew * 1e3,
                        bus.iface
                    )));
                }
            }
        }
        let line_due = Instant::now() >= next_line;
        for i in 0..3 {
            let (p, old) = (progress[i], shown[i]);
            let changed = match (p, old) {
                (Some(Progress::Homing { .. }), Some(Progress::Homing { .. })) => line_due,
                _ => p != old,
            };
            if let Some(p) = p
                && changed
            {
                let what = match p {
                    Progress::Homing { travelled_mm } => {
                        format!("homing, {travelled_mm:.1} mm travelled")
                    }
                    Progress::Homed { after_s } => format!("homed after {after_s:.1} s"),
                    Progress::Failed(c) => {
                        format!("failed: {} ({})", c.name(), triquint_link::status::hint(c))
                    }
                };
                triquint_cli_common::errln!("axis {} (node {}): {what}", i + 1, ids[i]);
                shown[i] = Some(p);
            }
        }
        if line_due {
            next_line = Instant::now() + Duration::from_secs(1);
        }
        // The cause first: a drive that failed on its own, not one that
        // stopped for its peer's Emergency.
        let failed = |i: usize| match shown[i] {
            Some(Progress::Failed(c)) => Some((i, c)),
            _ => None,
        };
        let cause = (0..3)
            .filter_map(failed)
            .find(|(_, c)| *c != FaultCode::PeerEmergency)
            .or_else(|| (0..3).find_map(failed));
        if let Some((i, c)) = cause {
            return Err(CliError::motion_fault(format!(
                "{}: axis {} (node {}) failed to home: {}; `triquint clear --iface {}{n}`, then home again",
                bus.iface,
                i + 1,
                ids[i],
                c.name(),
                bus.iface
            )));
        }
        if shown
            .iter()
            .all(|p| matches!(p, Some(Progress::Homed { .. })))
        {
            outln!("all axes homed in {:.1} s", t0.elapsed().as_secs_f64())?;
            return Ok(());
        }
        if t0.elapsed() > limit {
            let i = shown
                .iter()
                .position(|p| !matches!(p, Some(Progress::Homed { .. })))
                .unwrap_or(0);
            return Err(CliError::device(format!(
                "{}: axis {} (node {}) not homed after {:.0} s",
                bus.iface,
                i + 1,
                ids[i],
                limit.as_secs_f64()
            )));
        }
    }
}
