//! Where the drives report the machine is.

use std::time::Duration;

use nalgebra::Vector3;
use triquint_link::{Listener, SocketCanPort};
use triquint_shared::machine::Machine;

use crate::ops::bus::Bus;
use crate::ops::configure::configure;
use crate::ops::error::{OpError, OpResult};
use crate::ops::listen::{listen, open};
use crate::ops::shown::Drive;

/// Joint positions (m) from every drive's Telemetry within `wait`, and
/// whether each is homed.
fn listen_positions(
    port: &mut SocketCanPort,
    ids: [u8; 3],
    wait: Duration,
) -> OpResult<([Option<f64>; 3], [bool; 3])> {
    let mut l = Listener::new(ids);
    listen(port, &mut l, wait, true)?;
    Ok((
        l.nodes.0.map(|v| v.position.map(f64::from)),
        l.nodes.0.map(|v| v.homed && v.sync_seen_at.is_some()),
    ))
}

/// Where the drives on `bus` report the joints (m), configuring them first
/// if they do not report a position; refused when one is not homed.
pub fn reported_joints(machine: &Machine, bus: &Bus) -> OpResult<Vector3<f64>> {
    let ids = bus.ids;
    let mut port = open(&bus.iface)?;
    let (mut q, mut homed) = listen_positions(&mut port, ids, Duration::from_millis(300))?;
    if q.iter().any(Option::is_none) {
        configure(machine, bus, false)?;
        (q, homed) = listen_positions(&mut port, ids, Duration::from_secs_f64(bus.timeout_s))?;
    }
    drop(port);
    if let Some(i) = homed.iter().position(|h| !h) {
        return Err(OpError::NotHomed {
            iface: bus.iface.clone(),
            ids,
            drive: Drive::of(ids, i),
        });
    }
    match q {
        [Some(a), Some(b), Some(c)] => Ok(Vector3::new(a, b, c)),
        _ => {
            let i = q.iter().position(Option::is_none).unwrap_or(0);
            Err(OpError::NoPosition {
                iface: bus.iface.clone(),
                drive: Drive::of(ids, i),
                within_s: bus.timeout_s,
            })
        }
    }
}
