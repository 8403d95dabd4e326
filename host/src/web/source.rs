//! Where the frames come from: a SocketCAN interface (live), or a
//! `candump -L` log played at its recorded pace from server start, looping.
//! One thread reads and feeds the [`Model`]; it holds the model's lock only
//! to take in a frame, and never waits on a client.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant, SystemTime};

use triquint_link::{CanPort, PortError, Received, SocketCanError, SocketCanPort};

use super::candump::Logged;
use super::model::Model;

/// The frames of a monitor.
pub enum Source {
    /// SocketCAN interface (opened in the thread's caller).
    Live(SocketCanPort),
    /// A log (times from 0), replayed in a loop.
    Replay(Vec<Logged>),
}

/// Opens `iface` for listening with its clock's epoch now.
pub fn open_live(iface: &str) -> Result<SocketCanPort, SocketCanError> {
    SocketCanPort::open(iface, true, false, SystemTime::now())
}

fn lock(model: &Mutex<Model>) -> std::sync::MutexGuard<'_, Model> {
    model.lock().unwrap_or_else(|p| p.into_inner())
}

/// Feeds `model` from `source` until `stop`; a live port error ends it
/// (the page then shows every node stale).
pub fn run(
    source: Source,
    model: Arc<Mutex<Model>>,
    stop: Arc<AtomicBool>,
) -> Result<(), PortError> {
    match source {
        Source::Live(mut port) => {
            while !stop.load(Ordering::Relaxed) {
                match CanPort::recv(&mut port)? {
                    Some(rx) => lock(&model).take(&rx),
                    None => {
                        let now = CanPort::now_us(&mut port);
                        lock(&model).tick(now);
                        std::thread::sleep(Duration::from_millis(1));
                    }
                }
            }
            Ok(())
        }
        Source::Replay(log) => {
            let period = log.last().map_or(0, |l| l.t_us) + 100_000;
            let start = Instant::now();
            for lap in 0u64.. {
                for l in &log {
                    let t_us = lap * period + l.t_us;
                    loop {
                        if stop.load(Ordering::Relaxed) {
                            return Ok(());
                        }
                        let now = start.elapsed().as_micros() as u64;
                        if now >= t_us {
                            break;
                        }
                        lock(&model).tick(now);
                        std::thread::sleep(Duration::from_micros((t_us - now).min(5_000)));
                    }
                    lock(&model).take(&Received {
                        frame: l.frame,
                        t_us,
                        own: false,
                    });
                }
            }
            Ok(())
        }
    }
}
