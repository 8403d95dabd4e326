//! The page's control buttons: feed hold, resume and stop for every drive,
//! sent as `triquint hold | resume | stop` send them (`ops/feed.rs`: one
//! Command to node 0 dated by the running upload's host time, resent until
//! every drive answered; a refusal or a silent drive is an error).

use triquint_link::Feed;
use triquint_shared::protocol::CommandCode;

use crate::ops::error::OpResult;
use crate::ops::feed::{send_feed, verdict};

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
        self.feed().code()
    }

    pub fn feed(self) -> Feed {
        match self {
            Self::Hold => Feed::Hold,
            Self::Resume => Feed::Resume,
            Self::Stop => Feed::Stop,
        }
    }
}

/// Sends `action` to the drives `ids` on `iface` (node 0: all nodes); the
/// drives answer with CommandAck frames, seen on the page like any frame.
/// An error (the interface, a refusal, a silent drive) is the page's
/// message, as `hold`, `resume` and `stop` report it.
pub fn send(iface: &str, ids: [u8; 3], action: Action) -> OpResult {
    let mut port = super::source::open_live(iface)?;
    let f = action.feed();
    let sent = send_feed(&mut port, ids, f)?;
    verdict(iface, ids, f, &sent.answers)
}
