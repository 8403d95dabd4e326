//! Writing the drives' configuration without motion.

use std::time::Duration;

use triquint_link::{DriveConfigs, Session, SessionOptions, UploadError};
use triquint_shared::protocol::config::{DriveSettings, HomingSettings};
use triquint_shared::{Limits, Robot};

use crate::exit::{CliError, CliResult};
use crate::ops::bus::{BusArgs, upload_error};

/// Writes and commits the drives' configuration (limits-sized, with the
/// homing settings), without motion.
pub fn configure(robot: &Robot, homing: &HomingSettings, bus: &BusArgs) -> CliResult {
    let settings = DriveSettings {
        control_rate: bus.rate,
        node_ids: bus.ids()?,
        homing: homing.clone(),
        ..DriveSettings::default()
    };
    let configs = DriveConfigs::for_limits(robot, &Limits::default(), &settings).nodes;
    let opts = SessionOptions {
        fd: bus.fd,
        response_timeout_us: (bus.timeout * 1e6) as u64,
        ..SessionOptions::default()
    };
    let mut session = Session::configure(configs, opts);
    let mut port = triquint_link::open_host(&bus.iface, bus.fd).map_err(CliError::device)?;
    loop {
        match session.poll(&mut port) {
            Ok(Some(_)) => return Ok(()),
            Ok(None) => std::thread::sleep(Duration::from_millis(1)),
            Err(e @ (UploadError::Timeout { .. } | UploadError::Port(_))) => {
                return Err(CliError::device(format!(
                    "{}: configuring the drives: {e}",
                    bus.iface
                )));
            }
            Err(e) => return Err(upload_error(e, bus)),
        }
    }
}
