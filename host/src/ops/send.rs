//! Frames the commands send outside an upload session: a node command
//! (`home`, `clear`) and the host's emergency frame (`estop`, `home`).

use std::time::Duration;

use triquint_link::{CanPort, SocketCanPort};
use triquint_shared::protocol::{Command, CommandCode, Emergency, FaultCode, State};

use crate::ops::error::OpResult;

/// Sends `code` to node `id`, waiting while the transmit queue is full.
pub fn send_command(port: &mut SocketCanPort, id: u8, code: CommandCode, token: u8) -> OpResult {
    let f = Command {
        command: code as u8,
        token,
        arg: 0,
        arg2: 0,
    }
    .to_frame(id);
    while !CanPort::send(port, &f)? {
        std::thread::sleep(Duration::from_millis(1));
    }
    Ok(())
}

/// Sends the host's emergency frame (every drive stops); false when the
/// transmit queue stayed full for 100 ms.
pub fn send_emergency(port: &mut SocketCanPort) -> OpResult<bool> {
    let f = Emergency {
        code: FaultCode::HostEmergency as u8,
        state: State::Fault as u8,
        ramp_100us: 0,
        plan_time_us: 0,
    }
    .to_frame(0);
    for _ in 0..100 {
        if CanPort::send(port, &f)? {
            return Ok(true);
        }
        std::thread::sleep(Duration::from_millis(1));
    }
    Ok(false)
}
