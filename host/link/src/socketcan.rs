//! A Linux SocketCAN interface as a CAN port (the `socketcan` crate):
//! classic `CanSocket`, or `CanFdSocket` for CAN-FD, non-blocking, with the
//! kernel's receive timestamps (`SO_TIMESTAMPNS`). The one SocketCAN access
//! of the project: the host's `triquint upload/move-to/monitor --iface`
//! ([`open_host`], the session's [`CanPort`]), and `triquint-sim`'s virtual
//! drives and fault proxy.

use std::collections::VecDeque;
use std::io;
use std::time::SystemTime;

use socketcan::id::FdFlags;
use socketcan::{
    CanAnyFrame, CanDataFrame, CanFdFrame, CanFdSocket, CanFrame, CanSocket, EmbeddedFrame, Id,
    ShouldRetry, Socket, SocketOptions, StandardId,
};
use triquint_shared::protocol::Frame;

use crate::{CanPort, PortError, Received};

/// A SocketCAN failure, naming the interface and what was being done.
#[derive(Debug, thiserror::Error)]
pub enum SocketCanError {
    #[error("{iface}: cannot open SocketCAN interface: {source}")]
    Open {
        iface: String,
        #[source]
        source: io::Error,
    },
    #[error("{iface}: {what}: {source}")]
    Io {
        iface: String,
        what: &'static str,
        #[source]
        source: io::Error,
    },
    #[error(
        "{iface}: a CAN-FD frame (0x{id:03X}) needs --fd (a CAN-FD socket and an interface with MTU 72)"
    )]
    NeedsFd { iface: String, id: u16 },
}

/// A received frame with the kernel's receive time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SocketRx {
    pub frame: Frame,
    /// Receive time (ns since the port's epoch).
    pub t_ns: u64,
    /// This port's own frame, echoed back by the kernel (transmit confirmation).
    pub own: bool,
}

enum Sock {
    Classic(CanSocket),
    Fd(CanFdSocket),
}

/// One socket on one interface.
pub struct SocketCanPort {
    iface: String,
    sock: Sock,
    epoch: SystemTime,
    /// Frames sent and not yet seen echoed (when receiving own frames).
    sent: VecDeque<Frame>,
    recv_own: bool,
    /// Frames on the bus that are not protocol frames (extended, remote, error).
    pub foreign: u64,
}

impl std::os::fd::AsRawFd for SocketCanPort {
    fn as_raw_fd(&self) -> std::os::fd::RawFd {
        match &self.sock {
            Sock::Classic(s) => s.as_raw_fd(),
            Sock::Fd(s) => s.as_raw_fd(),
        }
    }
}

/// Wall-clock time (ns) since `epoch`: the clock of kernel receive timestamps.
pub fn ns_since(epoch: SystemTime, t: SystemTime) -> u64 {
    t.duration_since(epoch).map_or(0, |d| d.as_nanos() as u64)
}

impl SocketCanPort {
    /// Opens `iface` (classic CAN, or CAN-FD with `fd`), non-blocking, with
    /// receive timestamps. Times are ns since `epoch` (share one epoch between
    /// ports of one process). `recv_own`: the kernel echoes this socket's
    /// frames back (transmit confirmations, for time sync).
    pub fn open(
        iface: &str,
        fd: bool,
        recv_own: bool,
        epoch: SystemTime,
    ) -> Result<Self, SocketCanError> {
        let open_err = |source| SocketCanError::Open {
            iface: iface.to_string(),
            source,
        };
        let sock = if fd {
            Sock::Fd(CanFdSocket::open(iface).map_err(open_err)?)
        } else {
            Sock::Classic(CanSocket::open(iface).map_err(open_err)?)
        };
        let port = Self {
            iface: iface.to_string(),
            sock,
            epoch,
            sent: VecDeque::new(),
            recv_own,
            foreign: 0,
        };
        let setup = || -> io::Result<()> {
            match &port.sock {
                Sock::Classic(s) => {
                    s.set_nonblocking(true)?;
                    s.set_recv_timestamp(true)?;
                    s.set_recv_own_msgs(recv_own)
                }
                Sock::Fd(s) => {
                    s.set_nonblocking(true)?;
                    s.set_recv_timestamp(true)?;
                    s.set_recv_own_msgs(recv_own)
                }
            }
        };
        setup().map_err(|e| port.io("setting socket options", e))?;
        Ok(port)
    }

    fn io(&self, what: &'static str, source: io::Error) -> SocketCanError {
        SocketCanError::Io {
            iface: self.iface.clone(),
            what,
            source,
        }
    }

    pub fn iface(&self) -> &str {
        &self.iface
    }

    pub fn is_fd(&self) -> bool {
        matches!(self.sock, Sock::Fd(_))
    }

    /// Now (ns since the epoch), on the clock of the receive timestamps.
    pub fn now_ns(&self) -> u64 {
        ns_since(self.epoch, SystemTime::now())
    }

    /// Queues a frame; `Ok(false)` when the interface's queue is full (try later).
    pub fn send(&mut self, frame: &Frame) -> Result<bool, SocketCanError> {
        let id = StandardId::new(frame.id).unwrap_or(StandardId::ZERO);
        let res = match (&self.sock, frame.fd) {
            (Sock::Classic(_), true) => {
                return Err(SocketCanError::NeedsFd {
                    iface: self.iface.clone(),
                    id: frame.id,
                });
            }
            (Sock::Classic(s), false) => match CanDataFrame::new(id, frame.payload()) {
                Some(f) => s.write_frame(&CanFrame::Data(f)),
                None => Err(io::Error::from(io::ErrorKind::InvalidInput)),
            },
            (Sock::Fd(s), false) => match CanDataFrame::new(id, frame.payload()) {
                Some(f) => s.write_frame(&CanAnyFrame::Normal(f)),
                None => Err(io::Error::from(io::ErrorKind::InvalidInput)),
            },
            (Sock::Fd(s), true) => {
                match CanFdFrame::with_flags(id, frame.payload(), FdFlags::BRS) {
                    Some(f) => s.write_frame(&CanAnyFrame::Fd(f)),
                    None => Err(io::Error::from(io::ErrorKind::InvalidInput)),
                }
            }
        };
        match res {
            Ok(()) => {
                if self.recv_own {
                    // Bounded: echoes the kernel never delivers must not pile up.
                    if self.sent.len() >= 256 {
                        self.sent.pop_front();
                    }
                    self.sent.push_back(*frame);
                }
                Ok(true)
            }
            // Full transmit queue (ENOBUFS on SocketCAN) or would block.
            Err(e) if e.should_retry() || e.raw_os_error() == Some(libc::ENOBUFS) => Ok(false),
            Err(e) => Err(self.io("sending a frame", e)),
        }
    }

    /// The next received frame, if any. Non-protocol frames (extended
    /// identifiers, remote and error frames) are counted in `foreign` and skipped.
    pub fn recv(&mut self) -> Result<Option<SocketRx>, SocketCanError> {
        loop {
            let res = match &self.sock {
                Sock::Classic(s) => s
                    .read_frame_with_timestamp()
                    .map(|(f, t)| (CanAnyFrame::from(f), t)),
                Sock::Fd(s) => s.read_frame_with_timestamp(),
            };
            let (any, t) = match res {
                Ok(x) => x,
                Err(e) if e.should_retry() => return Ok(None),
                Err(e) => return Err(self.io("receiving a frame", e)),
            };
            let Some(frame) = to_frame(&any) else {
                self.foreign += 1;
                continue;
            };
            let own = self.recv_own && self.sent.front().is_some_and(|s| same(s, &frame));
            if own {
                self.sent.pop_front();
            }
            return Ok(Some(SocketRx {
                frame,
                t_ns: ns_since(self.epoch, t),
                own,
            }));
        }
    }
}

/// Same identifier and payload (an FD echo comes back padded to its DLC length).
fn same(sent: &Frame, got: &Frame) -> bool {
    sent.id == got.id
        && sent.fd == got.fd
        && got.payload().starts_with(sent.payload())
        && got.payload()[sent.payload().len()..]
            .iter()
            .all(|b| *b == 0)
}

/// A protocol frame (11-bit data frame, classic or FD), or `None`.
pub fn to_frame(any: &CanAnyFrame) -> Option<Frame> {
    let (id, data, fd) = match any {
        CanAnyFrame::Normal(f) => (f.id(), f.data(), false),
        CanAnyFrame::Fd(f) => (f.id(), f.data(), true),
        _ => return None,
    };
    match id {
        Id::Standard(s) => Some(Frame::with_payload(s.as_raw(), data, fd)),
        Id::Extended(_) => None,
    }
}

/// Opens `iface` for the host (classic CAN, or CAN-FD with `fd`), with
/// transmit confirmations, so the time sync carries the kernel's timestamp
/// of each sync frame.
pub fn open_host(iface: &str, fd: bool) -> Result<SocketCanPort, SocketCanError> {
    SocketCanPort::open(iface, fd, true, SystemTime::now())
}

impl CanPort for SocketCanPort {
    fn now_us(&mut self) -> u64 {
        self.now_ns() / 1000
    }
    fn send(&mut self, frame: &Frame) -> Result<bool, PortError> {
        Ok(SocketCanPort::send(self, frame)?)
    }
    fn recv(&mut self) -> Result<Option<Received>, PortError> {
        Ok(SocketCanPort::recv(self)?.map(|r| Received {
            frame: r.frame,
            t_us: r.t_ns / 1000,
            own: r.own,
        }))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn opening_a_missing_interface_names_it() {
        let e = SocketCanPort::open("triquint-no-such0", false, false, SystemTime::now())
            .err()
            .expect("no such interface");
        let text = e.to_string();
        assert!(text.starts_with("triquint-no-such0: cannot open"), "{text}");
    }

    #[test]
    fn frames_convert_both_ways() {
        let id = StandardId::new(0x110).unwrap();
        let fd = CanFdFrame::with_flags(id, &[7u8; 62], FdFlags::BRS).unwrap();
        let f = to_frame(&CanAnyFrame::Fd(fd)).unwrap();
        assert!(f.fd && f.id == 0x110 && f.len == 64);
        let sent = Frame::with_payload(0x110, &[7u8; 62], true);
        // The echo comes back zero-padded to 64 bytes: still our frame.
        assert!(same(&sent, &f));
        assert!(!same(&Frame::with_payload(0x110, &[8u8; 62], true), &f));
        let ext = CanDataFrame::new(socketcan::ExtendedId::new(0x1234).unwrap(), &[1]).unwrap();
        assert_eq!(to_frame(&CanAnyFrame::Normal(ext)), None);
    }
}
