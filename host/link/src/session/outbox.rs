//! Frames waiting for the port, and the command tokens.

use std::collections::VecDeque;

use triquint_shared::protocol::{Command, CommandCode, Frame};

use crate::{CanPort, PortError};

/// The session's transmit queue: time syncs and urgent resends go to the
/// front, everything else to the back, in the order queued.
#[derive(Clone, Debug, Default)]
pub(crate) struct Outbox {
    frames: VecDeque<Frame>,
    /// Token of the latest command.
    token: u8,
    /// Frames the port took.
    pub sent: u64,
}

impl Outbox {
    pub fn push_back(&mut self, f: Frame) {
        self.frames.push_back(f);
    }

    pub fn push_front(&mut self, f: Frame) {
        self.frames.push_front(f);
    }

    pub fn len(&self) -> usize {
        self.frames.len()
    }

    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// The frames queued, in order (tests).
    #[cfg(test)]
    pub fn frames(&self) -> impl Iterator<Item = &Frame> {
        self.frames.iter()
    }

    /// Queues a command to `node` (0: every node) with a new token; returns it.
    pub fn command(&mut self, node: u8, code: CommandCode, arg: u32) -> u8 {
        let token = self.next_token();
        self.push_back(command_frame(node, code, token, arg));
        token
    }

    /// A new command token.
    pub fn next_token(&mut self) -> u8 {
        self.token = self.token.wrapping_add(1);
        self.token
    }

    /// Hands the port what it takes, in order.
    pub fn flush<P: CanPort>(&mut self, port: &mut P) -> Result<(), PortError> {
        while let Some(f) = self.frames.front() {
            if !port.send(f)? {
                break;
            }
            self.sent += 1;
            self.frames.pop_front();
        }
        Ok(())
    }
}

/// A command frame with a given token (a resend repeats the token).
pub(crate) fn command_frame(node: u8, code: CommandCode, token: u8, arg: u32) -> Frame {
    Command {
        command: code as u8,
        token,
        arg,
        arg2: 0,
    }
    .to_frame(node)
}
