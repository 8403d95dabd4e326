//! The arm/start sequence: once every node has its first segments, Arm to
//! all (resent with the same token to a node that has not answered, see
//! [`ARM_RESENDS`]); once every node armed, Start at a common time
//! ahead of now by the larger of `start_lead_us` and a few Arm round trips
//! ([`start_lead_us`]), resent to a silent node while that time is still
//! ahead ([`START_RETRY_US`]).

use triquint_shared::protocol::{CommandCode, FaultCode};

use super::nodes::{AXES, Nodes};
use super::outbox::{Outbox, command_frame};
use super::{SessionOptions, UploadError};

/// Arm resends, `setup_retry_us` apart: all within the drives' 100 ms
/// repeat window of the first, so a drive that did arm (its answer lost)
/// answers again instead of executing Arm twice (which it would refuse).
pub const ARM_RESENDS: u32 = 2;

/// Start resends to a drive that has not answered, this far apart, only
/// before the start time (`start_lead_us` after the first) and within the
/// repeat window: a drive that missed Start would stop every axis (`PeerLost`).
pub const START_RETRY_US: u64 = 10_000;

/// The Start's lead in Arm round trips: a drive slowed down (a loaded
/// host, a busy bus, an emulated CPU) answered Arm late and would receive
/// a Start with a fixed lead after its time (`StartInPast`).
pub const START_LEAD_ROUND_TRIPS: u64 = 4;

/// The longest lead: a round trip beyond this is a fault, not latency.
pub const MAX_START_LEAD_US: u64 = 500_000;

/// How far ahead the start time goes: `floor_us` (the session's
/// `start_lead_us`) or [`START_LEAD_ROUND_TRIPS`] times the Arm's round
/// trip if longer, at most [`MAX_START_LEAD_US`] (never below the floor).
pub fn start_lead_us(floor_us: u64, arm_round_trip_us: u64) -> u64 {
    arm_round_trip_us
        .saturating_mul(START_LEAD_ROUND_TRIPS)
        .min(MAX_START_LEAD_US)
        .max(floor_us)
}

/// A command sent to every node, and how often it went out again.
#[derive(Clone, Copy, Debug, Default)]
struct Pending {
    token: u8,
    sent_at: u64,
    resends: u32,
}

#[derive(Clone, Debug, Default)]
pub(crate) struct StartSequence {
    arm: Pending,
    start: Pending,
    /// Host time (µs) the first Arm went out.
    arm_first_us: u64,
    /// Host time (µs) of the start (0 before).
    pub start_us: u64,
}

impl StartSequence {
    /// Sends Arm to every node.
    pub fn arm(&mut self, now: u64, out: &mut Outbox) {
        let token = out.command(0, CommandCode::Arm, 0);
        self.arm = Pending {
            token,
            sent_at: now,
            resends: 0,
        };
        self.arm_first_us = now;
    }

    /// Each node's answer to the Arm.
    pub fn arm_answers(&self, nodes: &Nodes) -> [Option<u8>; AXES] {
        nodes.answers_to(self.arm.token)
    }

    /// `Ok(true)` once every node armed and Start went out; an Arm refused
    /// is a motion fault.
    pub fn poll_arm(
        &mut self,
        now: u64,
        nodes: &Nodes,
        opts: &SessionOptions,
        out: &mut Outbox,
    ) -> Result<bool, UploadError> {
        let Pending {
            token,
            sent_at,
            resends,
        } = self.arm;
        let acks = self.arm_answers(nodes);
        if acks.iter().any(Option::is_none)
            && resends < ARM_RESENDS
            && now.saturating_sub(sent_at) > opts.setup_retry_us
        {
            // The same command (same token) to each silent node: one
            // that did arm answers again, one that missed it arms.
            for i in (0..AXES).filter(|&i| acks[i].is_none()) {
                out.push_back(command_frame(nodes.id(i), CommandCode::Arm, token, 0));
            }
            self.arm = Pending {
                token,
                sent_at: now,
                resends: resends + 1,
            };
        }
        if !acks.iter().all(Option::is_some) {
            return Ok(false);
        }
        if let Some(i) = acks.iter().position(|r| *r != Some(0)) {
            let code = acks[i]
                .and_then(FaultCode::from_u8)
                .unwrap_or(FaultCode::None);
            return Err(UploadError::Refused {
                node: nodes.drive(i),
                command: CommandCode::Arm,
                code: Some(code),
            });
        }
        let lead = start_lead_us(opts.start_lead_us, now.saturating_sub(self.arm_first_us));
        let start = now + lead;
        let token = out.command(0, CommandCode::Start, start as u32);
        self.start = Pending {
            token,
            sent_at: now,
            resends: 0,
        };
        self.start_us = start;
        Ok(true)
    }

    /// Start again (same token) to each drive that has not answered it,
    /// while the start time is ahead.
    pub fn resend_start(&mut self, now: u64, nodes: &Nodes, out: &mut Outbox) {
        let Pending { token, sent_at, .. } = self.start;
        if now + START_RETRY_US >= self.start_us || now.saturating_sub(sent_at) < START_RETRY_US {
            return;
        }
        let acks = nodes.answers_to(token);
        for i in (0..AXES).filter(|&i| acks[i].is_none()) {
            out.push_front(command_frame(
                nodes.id(i),
                CommandCode::Start,
                token,
                self.start_us as u32,
            ));
        }
        self.start.sent_at = now;
        self.start.resends += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_start_lead_follows_a_slow_arm_round_trip_within_bounds() {
        // A prompt answer keeps the floor.
        assert_eq!(start_lead_us(50_000, 2_000), 50_000);
        // A slow one: four round trips.
        assert_eq!(start_lead_us(50_000, 30_000), 120_000);
        // Never beyond the ceiling, never below the floor.
        assert_eq!(start_lead_us(50_000, 10_000_000), MAX_START_LEAD_US);
        assert_eq!(start_lead_us(800_000, 10_000_000), 800_000);
    }
}
