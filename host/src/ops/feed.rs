//! What `hold`, `resume`, `stop`, `override` and the web page's buttons
//! share: listen to the bus
//! (the drives' states, and the host time from the TimeSync frames of the
//! running upload), send one Command to every drive carrying that host
//! time, so all of them apply it at the same instant, resend it unchanged
//! until each drive answered (a drive that already acted answers again:
//! the repeat window), and turn the answers into an exit status.

use std::time::{Duration, Instant};

use triquint_link::{CanPort, Feed, HostClock, Listener};
use triquint_shared::protocol::{CommandAck, Msg, State, decode};

use crate::ops::error::{OpError, OpResult};
use crate::ops::shown::Drive;

/// How long to listen first: a heartbeat from every drive (100 ms apart)
/// and two TimeSyncs (100 ms apart while an upload runs).
const LISTEN: Duration = Duration::from_millis(350);
/// The command is dated this far back (µs): the drives apply a time up to
/// 100 ms old exactly (closed form from that instant), a later one on
/// receipt, so a small margin keeps every drive on the exact instant.
const DATED_BACK_US: u32 = 1_000;
/// Resent (unchanged) after this, at most `RESENDS` times: all inside the
/// drives' 100 ms repeat window.
const RESEND_AFTER: Duration = Duration::from_millis(25);
const RESENDS: u32 = 3;

/// Each drive's answer (None: silent) and the host time the command carried.
pub struct Sent {
    pub answers: [Option<CommandAck>; 3],
    pub host_us: Option<u32>,
    pub states_before: [Option<State>; 3],
}

/// Listens, then sends `f` to every drive of `ids` on `port` (SocketCAN;
/// any port in tests).
pub fn send_feed<P: CanPort>(port: &mut P, ids: [u8; 3], f: Feed) -> OpResult<Sent> {
    let mut listener = Listener::new(ids);
    let mut clock = HostClock::default();
    let t0 = Instant::now();
    while t0.elapsed() < LISTEN && !(listener.all_heard() && clock.known()) {
        match CanPort::recv(port)? {
            Some(rx) => {
                listener.take(&rx);
                clock.take(&rx);
            }
            None => std::thread::sleep(Duration::from_millis(1)),
        }
    }
    let states_before = listener.nodes.0.map(|v| v.state);
    if let Some(i) = listener
        .nodes
        .0
        .iter()
        .position(|v| v.heartbeat_at.is_none())
    {
        return Err(OpError::NoHeartbeat {
            drive: Drive::of(ids, i),
            within_s: LISTEN.as_secs_f64(),
        });
    }
    // No TimeSync: no upload runs, no drive is moving; "on receipt" (0).
    let now = port.now_us();
    let host_us = clock.host_us(now).map(|t| t.wrapping_sub(DATED_BACK_US));
    let token = (now as u8) | 0x80;
    let cmd = f.command(token, 0);
    let cmd = triquint_shared::protocol::Command {
        arg: host_us.map_or(0, |t| t.max(1)),
        ..cmd
    };
    let frame = cmd.to_frame(0);
    let mut answers: [Option<CommandAck>; 3] = [None; 3];
    for _ in 0..=RESENDS {
        let sent_at = Instant::now();
        while !CanPort::send(port, &frame)? {
            if sent_at.elapsed() > RESEND_AFTER {
                return Err(OpError::QueueFull);
            }
            std::thread::sleep(Duration::from_millis(1));
        }
        while sent_at.elapsed() < RESEND_AFTER && answers.iter().any(Option::is_none) {
            let Some(rx) = CanPort::recv(port)? else {
                std::thread::sleep(Duration::from_millis(1));
                continue;
            };
            if let Ok((Msg::CommandAck(a), node)) = decode(&rx.frame)
                && a.token == token
                && a.command == cmd.command
                && let Some(i) = ids.iter().position(|id| *id == node)
            {
                answers[i] = Some(a);
            }
        }
        if answers.iter().all(Option::is_some) {
            break;
        }
    }
    Ok(Sent {
        answers,
        host_us,
        states_before,
    })
}

/// The drives' `answers` to `f`: a refusal (with the cap for an override
/// above it, with `clear` for a faulted drive), a silent drive, or done.
pub fn verdict(iface: &str, ids: [u8; 3], f: Feed, answers: &[Option<CommandAck>; 3]) -> OpResult {
    let mut answered = answers
        .iter()
        .enumerate()
        .filter_map(|(i, a)| a.map(|a| (Drive::of(ids, i), a)));
    if let Some((drive, ack)) = answered.find(|(_, a)| a.result != 0) {
        return Err(OpError::FeedRefused {
            iface: iface.to_string(),
            ids,
            drive,
            feed: f,
            ack,
        });
    }
    if let Some(i) = answers.iter().position(Option::is_none) {
        return Err(OpError::NoAnswer {
            iface: iface.to_string(),
            drive: Drive::of(ids, i),
            within_ms: RESEND_AFTER.as_millis() * (RESENDS as u128 + 1),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use triquint_shared::protocol::FaultCode;

    use super::*;
    use crate::exit::{CliError, Status};

    fn ack(command: Feed, result: FaultCode, state: State, value: u32) -> Option<CommandAck> {
        Some(CommandAck {
            command: command.code() as u8,
            token: 0x81,
            result: result as u8,
            state: state as u8,
            value,
        })
    }

    #[test]
    fn answers_give_the_exit_status_of_the_table() {
        let ids = [1, 2, 3];
        let ok = ack(Feed::Hold, FaultCode::None, State::Running, 0);
        assert!(verdict("vcan0", ids, Feed::Hold, &[ok; 3]).is_ok());
        // Above the cap: refused, with the cap.
        let f = Feed::Override(1500);
        let capped = ack(f, FaultCode::OverrideAboveCap, State::Running, 1177);
        let e = CliError::from(verdict("vcan0", ids, f, &[capped; 3]).unwrap_err());
        assert_eq!(e.status, Status::Refused);
        assert!(
            e.message.contains("150 %") && e.message.contains("117.7 %"),
            "{e}"
        );
        // Faulted: refused, with what to run.
        let faulted = ack(Feed::Hold, FaultCode::WrongState, State::Fault, 0);
        let e = CliError::from(
            verdict("vcan0", [4, 5, 6], Feed::Hold, &[ok, faulted, ok]).unwrap_err(),
        );
        assert_eq!(e.status, Status::Refused);
        assert!(e.message.contains("axis 2 (node 5) is in Fault"), "{e}");
        assert!(
            e.message
                .contains("triquint clear --iface vcan0 --nodes 4,5,6"),
            "{e}"
        );
        // Silent: device.
        let e = CliError::from(verdict("vcan0", ids, Feed::Stop, &[ok, ok, None]).unwrap_err());
        assert_eq!(e.status, Status::Device);
        assert!(e.message.contains("axis 3 (node 3) did not answer"), "{e}");
    }

    /// Three drives behind a fake port: heartbeats and two TimeSyncs of a
    /// master whose clock reads 5 s more than ours; every Command answered,
    /// except the first transmission to node 3 (lost: resent, same frame).
    struct Drives {
        now: u64,
        rx: std::collections::VecDeque<triquint_link::Received>,
        sent: Vec<triquint_shared::protocol::Command>,
        drop_first: bool,
    }

    impl CanPort for Drives {
        fn now_us(&mut self) -> u64 {
            // Our clock: 200 ms, then 10 µs a reading.
            self.now += 10;
            self.now
        }
        fn send(
            &mut self,
            frame: &triquint_shared::protocol::Frame,
        ) -> Result<bool, triquint_link::PortError> {
            if let Ok((Msg::Command(c), 0)) = decode(frame) {
                self.sent.push(c);
                for node in [1u8, 2, 3] {
                    if node == 3 && self.drop_first && self.sent.len() == 1 {
                        continue;
                    }
                    let a = CommandAck {
                        command: c.command,
                        token: c.token,
                        result: 0,
                        state: State::Running as u8,
                        value: 1177,
                    };
                    self.rx.push_back(triquint_link::Received {
                        frame: a.to_frame(node),
                        t_us: 0,
                        own: false,
                    });
                }
            }
            Ok(true)
        }
        fn recv(&mut self) -> Result<Option<triquint_link::Received>, triquint_link::PortError> {
            Ok(self.rx.pop_front())
        }
    }

    fn drives(drop_first: bool) -> Drives {
        use triquint_shared::protocol::{
            Heartbeat, HeartbeatExt, PROTOCOL_VERSION, TimeSync, flags,
        };
        let rx = |frame, t_us| triquint_link::Received {
            frame,
            t_us,
            own: false,
        };
        let mut q = std::collections::VecDeque::new();
        q.push_back(rx(
            TimeSync {
                seq: 7,
                prev_tx_us: 0,
            }
            .to_frame(0),
            1_000,
        ));
        for node in [1u8, 2, 3] {
            let h = Heartbeat {
                state: State::Running as u8,
                protocol_version: PROTOCOL_VERSION,
                ..Heartbeat::default()
            };
            q.push_back(rx(h.to_frame(node), 50_000));
            let e = HeartbeatExt {
                flags: flags::SYNCED | flags::HOMED,
                ..HeartbeatExt::default()
            };
            q.push_back(rx(e.to_frame(node), 50_000));
        }
        let s = TimeSync {
            seq: 8,
            prev_tx_us: 5_001_000,
        };
        q.push_back(rx(s.to_frame(0), 101_000));
        Drives {
            now: 200_000,
            rx: q,
            sent: Vec::new(),
            drop_first,
        }
    }

    #[test]
    fn a_command_carries_the_masters_host_time_and_is_resent_until_answered() {
        let mut d = drives(true);
        let sent = send_feed(&mut d, [1, 2, 3], Feed::Override(500)).unwrap();
        assert!(
            sent.answers
                .iter()
                .all(|a| a.is_some_and(|a| a.result == 0))
        );
        assert_eq!(sent.states_before, [Some(State::Running); 3]);
        // Sent twice (node 3 missed the first), the same frame both times.
        assert_eq!(d.sent.len(), 2);
        assert_eq!(d.sent[0], d.sent[1]);
        let c = d.sent[0];
        assert_eq!((c.command, c.arg2), (Feed::Override(500).code() as u8, 500));
        // Our clock read 200.01 ms when it was sent: the master's 5 s more,
        // dated 1 ms back.
        let t = sent.host_us.unwrap();
        assert_eq!((c.arg, t), (5_199_010, 5_199_010));
        assert!(verdict("vcan0", [1, 2, 3], Feed::Override(500), &sent.answers).is_ok());
    }

    #[test]
    fn without_time_sync_the_command_applies_on_receipt() {
        let mut d = drives(false);
        d.rx.retain(|r| !matches!(decode(&r.frame), Ok((Msg::TimeSync(_), _))));
        let sent = send_feed(&mut d, [1, 2, 3], Feed::Hold).unwrap();
        assert_eq!(sent.host_us, None);
        assert_eq!(d.sent.len(), 1);
        assert_eq!(d.sent[0].arg, 0, "on receipt");
    }
}
