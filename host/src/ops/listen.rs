//! Listening to the drives without sending anything: what `status`,
//! `clear`, `home` and `move-to` know of the machine before they act.

use std::time::{Duration, Instant, SystemTime};

use triquint_link::{CanPort, Listener, SocketCanPort};

use crate::ops::error::OpResult;

/// Opens `iface` for listening (a CAN-FD socket receives classic and FD frames).
pub fn open(iface: &str) -> OpResult<SocketCanPort> {
    Ok(SocketCanPort::open(iface, true, false, SystemTime::now())?)
}

/// Takes in what the drives of `ids` send for `wait`, or until every one
/// sent a heartbeat, its extension and (if `positions`) a position.
pub fn listen(
    port: &mut SocketCanPort,
    listener: &mut Listener,
    wait: Duration,
    positions: bool,
) -> OpResult {
    let t0 = Instant::now();
    while t0.elapsed() < wait {
        match CanPort::recv(port)? {
            Some(rx) => listener.take(&rx),
            None => std::thread::sleep(Duration::from_millis(1)),
        }
        let have_pos = !positions || listener.nodes.all(|v| v.position.is_some());
        if listener.all_heard() && have_pos {
            break;
        }
    }
    Ok(())
}

/// Takes in every frame waiting now, without waiting for more.
pub fn drain(port: &mut SocketCanPort, listener: &mut Listener) -> OpResult {
    while let Some(rx) = CanPort::recv(port)? {
        listener.take(&rx);
    }
    Ok(())
}
