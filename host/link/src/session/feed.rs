//! Feed hold, resume, override and stop during an upload: queued by the
//! caller (keys, a test) at any moment, sent ahead of every segment (the
//! drives take them in their never-dropped lane), each carrying the host
//! time it was sent at, so every drive applies it at the same instant.
//! Also what the session learns of such commands from others on the bus:
//! an acknowledged override's value, and that a stop was acknowledged.

use triquint_shared::protocol::{Command, CommandAck, CommandCode, FaultCode, State};

use super::nodes::{AXES, CommandAnswer};
use super::outbox::Outbox;

/// Feed commands whose answers are kept (the latest).
const KEPT: usize = 32;

/// A feed command to every drive.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feed {
    Hold,
    Resume,
    /// A stop along the path with the stop ramp (then Idle).
    Stop,
    /// A stop along the path with the quick-stop ramp.
    QuickStop,
    /// Feed override σ in per mille (1000 = 100 %).
    Override(u16),
}

impl Feed {
    pub fn code(self) -> CommandCode {
        match self {
            Feed::Hold => CommandCode::FeedHold,
            Feed::Resume => CommandCode::Resume,
            Feed::Stop => CommandCode::Stop,
            Feed::QuickStop => CommandCode::QuickStop,
            Feed::Override(_) => CommandCode::Override,
        }
    }

    fn arg2(self) -> u16 {
        match self {
            Feed::Override(pm) => pm,
            _ => 0,
        }
    }

    /// The command frame's fields for host time `t_us` (wrapping).
    pub fn command(self, token: u8, t_us: u64) -> Command {
        self.command_dated(token, t_us, 0)
    }

    /// [`Feed::command`], a stop or hold carrying the ramp `dated_100us`
    /// for the path ahead of its instant (0: the drives' full ramp).
    pub fn command_dated(self, token: u8, t_us: u64, dated_100us: u16) -> Command {
        let arg2 = match self {
            Feed::Stop | Feed::QuickStop | Feed::Hold => dated_100us,
            _ => self.arg2(),
        };
        Command {
            command: self.code() as u8,
            token,
            // 0 means "on receipt": the one host time that cannot be sent.
            arg: (t_us as u32).max(1),
            arg2,
        }
    }
}

/// What the session sent and learnt of feed commands.
#[derive(Clone, Debug, Default)]
pub(crate) struct FeedState {
    pending: Vec<(Feed, u8)>,
    /// Override commands seen (own or another station's): token, per mille.
    overrides: Vec<(u8, u16)>,
    /// The override the drives hold (per mille): acknowledged to an
    /// Override, or reported in the answer to Arm.
    pub override_permille: Option<u32>,
    /// A drive acknowledged a stop (or reported Stopping without a fault).
    pub stopped: bool,
    /// A hold, resume or override was seen or sent: the host's plan clock
    /// is an estimate, not the drives' plan time.
    clock_inexact: bool,
    /// Each drive's answer to the session's own feed commands, by token.
    answers: Vec<(u8, [Option<CommandAnswer>; AXES])>,
}

impl FeedState {
    /// Queues `f`; returns the token its answers will carry.
    pub fn queue(&mut self, f: Feed, out: &mut Outbox) -> u8 {
        let token = out.next_token();
        self.pending.push((f, token));
        self.answers.retain(|(t, _)| *t != token);
        self.answers.push((token, [None; AXES]));
        if self.answers.len() > KEPT {
            self.answers.remove(0);
        }
        token
    }

    /// Sends what was queued, ahead of everything, at host time `now`;
    /// a stop or hold with the ramp `dated` gives it (100 µs units, 0 for
    /// the drives' full ramp).
    pub fn send(&mut self, now: u64, out: &mut Outbox, dated: impl Fn(Feed) -> u16) {
        for (f, token) in self.pending.drain(..).rev() {
            match f {
                Feed::Override(pm) => self.overrides.push((token, pm)),
                // Our own stop: the session ends stopped whatever the state.
                Feed::Stop | Feed::QuickStop => self.stopped = true,
                _ => {}
            }
            // Once the plan time is no longer exact (a hold or an override
            // sent), every later transition takes the full ramp.
            let d = if self.clock_inexact { 0 } else { dated(f) };
            if matches!(f, Feed::Hold | Feed::Resume | Feed::Override(_)) {
                self.clock_inexact = true;
            }
            out.push_front(f.command_dated(token, now, d).to_frame(0));
        }
    }

    /// A Command frame of another station.
    pub fn seen(&mut self, c: &Command) {
        self.clock_inexact = true;
        if c.command == CommandCode::Override as u8 {
            self.overrides.push((c.token, c.arg2));
            if self.overrides.len() > 16 {
                self.overrides.remove(0);
            }
        }
    }

    /// Each drive's answer to the session's feed command `token`.
    pub fn answers(&self, token: u8) -> Option<[Option<CommandAnswer>; AXES]> {
        self.answers.iter().find(|(t, _)| *t == token).map(|x| x.1)
    }

    /// A CommandAck of the drive at index `i`.
    pub fn answered(&mut self, i: usize, a: &CommandAck) {
        if let Some((_, slots)) = self.answers.iter_mut().find(|(t, _)| *t == a.token)
            && let Some(slot) = slots.get_mut(i)
        {
            *slot = Some((*a).into());
        }
        let done = a.result == FaultCode::None as u8;
        // Arm's answer carries the override the plan starts at: one set
        // before this session (another process) is known from here on.
        // 0: a drive older than that answer.
        if a.command == CommandCode::Arm as u8 && done && a.value > 0 {
            self.override_permille = Some(a.value);
        }
        if a.command == CommandCode::Override as u8 && done {
            if let Some((_, pm)) = self.overrides.iter().rev().find(|(t, _)| *t == a.token) {
                self.override_permille = Some(*pm as u32);
            }
        }
        let stop =
            a.command == CommandCode::Stop as u8 || a.command == CommandCode::QuickStop as u8;
        // Stopping from Running; Loaded: disarmed before Start.
        let stopping = a.state == State::Stopping as u8 || a.state == State::Loaded as u8;
        if stop && done && stopping {
            self.stopped = true;
        }
    }
}
