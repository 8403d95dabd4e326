//! Writing the drives' configuration without motion.

use std::time::Duration;

use triquint_link::{DriveConfigs, Session, SessionOptions, UploadError};
use triquint_shared::Limits;
use triquint_shared::machine::Machine;
use triquint_shared::protocol::config::DriveSettings;

use crate::ops::bus::Bus;
use crate::ops::error::{OpError, OpResult};

/// Writes and commits the drives' configuration (limits-sized, with the
/// homing settings), without motion; `unlock_ceilings`: in each drive's
/// maintenance window, so the machine file may raise its ceilings or
/// widen its travel (docs/safety.md, "The ceiling lock").
pub fn configure(machine: &Machine, bus: &Bus, unlock_ceilings: bool) -> OpResult {
    let settings = DriveSettings {
        control_rate: bus.rate,
        node_ids: bus.ids,
        ..machine.drive_settings()
    };
    let configs =
        DriveConfigs::for_limits(&machine.robot, &machine_limits(machine), &settings).nodes;
    let opts = SessionOptions {
        fd: bus.fd,
        response_timeout_us: (bus.timeout_s * 1e6) as u64,
        unlock_ceilings,
        ..SessionOptions::default()
    };
    let mut session = Session::configure(configs, opts);
    let mut port = triquint_link::open_host(&bus.iface, bus.fd)?;
    loop {
        match session.poll(&mut port) {
            Ok(Some(_)) => return Ok(()),
            Ok(None) => std::thread::sleep(Duration::from_millis(1)),
            Err(source @ (UploadError::Timeout { .. } | UploadError::Port(_))) => {
                return Err(OpError::Configure {
                    iface: bus.iface.clone(),
                    source,
                });
            }
            Err(e) => return Err(OpError::upload(e, bus)),
        }
    }
}

/// The default limits held to the machine's ceilings: what the drives are
/// configured with before there is a plan, and what `move-to` plans with.
pub fn machine_limits(machine: &Machine) -> Limits {
    let c = machine.effective_ceilings();
    let d = Limits::default();
    Limits {
        velocity: d.velocity.min(c.velocity),
        acceleration: d.acceleration.min(c.acceleration),
        jerk: d.jerk.min(c.jerk),
        torque: d.torque.min(c.torque),
        total_time: d.total_time,
    }
}
