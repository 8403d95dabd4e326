//! The page's control buttons: feed hold, resume and stop for every drive
//! (a Command to node 0), sent on the bus with the existing send helper.
//! The hold/resume/override subcommands will share one sender after merge.

use std::sync::atomic::{AtomicU8, Ordering};

use triquint_shared::protocol::CommandCode;

use crate::cli::send::send_command;

/// A control request of the page.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Action {
    Hold,
    Resume,
    Stop,
}

impl Action {
    /// `/api/hold` → Hold, …
    pub fn from_path(path: &str) -> Option<Self> {
        match path {
            "/api/hold" => Some(Self::Hold),
            "/api/resume" => Some(Self::Resume),
            "/api/stop" => Some(Self::Stop),
            _ => None,
        }
    }

    pub fn code(self) -> CommandCode {
        match self {
            Self::Hold => CommandCode::FeedHold,
            Self::Resume => CommandCode::Resume,
            Self::Stop => CommandCode::Stop,
        }
    }
}

static TOKEN: AtomicU8 = AtomicU8::new(0x80);

/// Sends `action` to every drive on `iface` (node 0: all nodes); the
/// drives answer with CommandAck frames, seen on the page like any frame.
pub fn send(iface: &str, action: Action) -> Result<(), String> {
    let mut port = super::source::open_live(iface)?;
    let token = TOKEN.fetch_add(1, Ordering::Relaxed);
    send_command(&mut port, 0, action.code(), token).map_err(|e| e.to_string())
}
