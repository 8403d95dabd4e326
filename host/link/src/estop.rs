//! The host's emergency stop, confirmed: the Emergency frame from node 0,
//! then a bounded wait for every addressed drive to show it stopped. A
//! drive that hears it sends its own Emergency frame at once (Fault when
//! it was still, Stopping when it was moving) and reports the host's code
//! in its heartbeats; the frame is sent again while a drive is silent
//! (drives take a repeat as a no-op). The kernel taking the frame proves
//! nothing: a drive may be off the bus.

use triquint_shared::protocol::{Emergency, FaultCode, Frame, Msg, State, decode};

use crate::session::AXES;
use crate::{CanPort, PortError, Received};

/// The frame is sent again this long after the previous one while a drive
/// has not answered.
pub const RESEND_US: u64 = 50_000;

/// How a drive showed that it stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstopAnswer {
    /// It heard the host's emergency (its own Emergency frame, or a
    /// heartbeat with the host's code), now in `state` (Fault or Stopping).
    Heard { state: State },
    /// It was already stopping or in Fault for another reason (`fault`):
    /// stopped, though whether it heard the host is not known.
    Already { state: State, fault: FaultCode },
}

/// Why the emergency frame could not go out.
#[derive(Debug, thiserror::Error)]
pub enum EstopError {
    #[error(transparent)]
    Port(#[from] PortError),
    #[error("the emergency frame could not be sent (transmit queue full for {0} ms)")]
    NotSent(u64),
}

/// The host's emergency frame (from node 0).
pub fn emergency_frame() -> Frame {
    Emergency::host_stop()
}

/// The answers of the drives on `ids` (axis i on `ids[i]`) to an emergency stop.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EstopWatch {
    ids: [u8; AXES],
    answers: [Option<EstopAnswer>; AXES],
}

impl EstopWatch {
    pub fn new(ids: [u8; AXES]) -> Self {
        Self {
            ids,
            answers: [None; AXES],
        }
    }

    /// Takes in a received frame: an addressed drive's Emergency frame or a
    /// heartbeat in Fault, or Stopping for a fault.
    pub fn take(&mut self, rx: &Received) {
        if rx.own {
            return;
        }
        let Ok((msg, node)) = decode(&rx.frame) else {
            return;
        };
        let Some(i) = (node != 0)
            .then(|| self.ids.iter().position(|&id| id == node))
            .flatten()
        else {
            return;
        };
        let (state, code) = match msg {
            Msg::Emergency(e) => (State::from_u8(e.state), e.code),
            Msg::Heartbeat(h) => (State::from_u8(h.state), h.fault),
            _ => return,
        };
        let fault = FaultCode::from_u8(code).unwrap_or(FaultCode::None);
        let answer = match (state, fault) {
            (Some(s @ (State::Fault | State::Stopping)), FaultCode::HostEmergency) => {
                EstopAnswer::Heard { state: s }
            }
            // A stop without a fault (Stop, QuickStop) ends Idle: not stopped for good.
            (Some(State::Stopping), FaultCode::None | FaultCode::QuickStop) => return,
            (Some(s @ (State::Fault | State::Stopping)), fault) => {
                EstopAnswer::Already { state: s, fault }
            }
            _ => return,
        };
        // Having heard the host outranks "already".
        if !matches!(self.answers[i], Some(EstopAnswer::Heard { .. })) {
            self.answers[i] = Some(answer);
        }
    }

    /// Each drive's answer (`None`: nothing yet), axis 1 first.
    pub fn answers(&self) -> [Option<EstopAnswer>; AXES] {
        self.answers
    }

    /// The node ids the answers are for.
    pub fn ids(&self) -> [u8; AXES] {
        self.ids
    }

    /// Node ids of the drives that have not answered.
    pub fn silent(&self) -> Vec<u8> {
        (0..AXES)
            .filter(|&i| self.answers[i].is_none())
            .map(|i| self.ids[i])
            .collect()
    }

    /// Every drive answered (heard the host, or was already stopped).
    pub fn all_answered(&self) -> bool {
        self.answers.iter().all(Option::is_some)
    }
}

/// Sends the emergency frame on `port` and waits up to `wait_us` (port
/// clock) for every drive of `ids` to answer, resending it every
/// [`RESEND_US`] meanwhile; `idle` is called when nothing is waiting
/// (a short sleep on a real port). Fails only if the frame never went out.
pub fn emergency_stop<P: CanPort>(
    port: &mut P,
    ids: [u8; AXES],
    wait_us: u64,
    mut idle: impl FnMut(),
) -> Result<EstopWatch, EstopError> {
    let frame = emergency_frame();
    let t0 = port.now_us();
    let mut sent_at = loop {
        if port.send(&frame)? {
            break port.now_us();
        }
        let now = port.now_us();
        if now.saturating_sub(t0) >= wait_us {
            return Err(EstopError::NotSent(wait_us / 1000));
        }
        idle();
    };
    let mut watch = EstopWatch::new(ids);
    loop {
        while let Some(rx) = port.recv()? {
            watch.take(&rx);
        }
        if watch.all_answered() {
            return Ok(watch);
        }
        let now = port.now_us();
        if now.saturating_sub(t0) >= wait_us {
            return Ok(watch);
        }
        if now.saturating_sub(sent_at) >= RESEND_US && port.send(&frame)? {
            sent_at = now;
        }
        idle();
    }
}

#[cfg(test)]
mod tests {
    use std::collections::VecDeque;

    use super::*;
    use triquint_shared::protocol::Heartbeat;

    /// Drives behind a fake port whose clock moves 1 ms a reading: each
    /// drive of `answer` answers every emergency frame with `reply`.
    struct Drives {
        now: u64,
        rx: VecDeque<Received>,
        sent: usize,
        /// Node id and what it sends on each emergency frame.
        answer: Vec<(u8, Msg)>,
        /// The transmit queue is full for this many tries.
        full: usize,
    }

    impl CanPort for Drives {
        fn now_us(&mut self) -> u64 {
            self.now += 1_000;
            self.now
        }
        fn send(&mut self, frame: &Frame) -> Result<bool, PortError> {
            if self.full > 0 {
                self.full -= 1;
                return Ok(false);
            }
            assert_eq!(*frame, emergency_frame());
            self.sent += 1;
            for (node, m) in &self.answer {
                let frame = match m {
                    Msg::Emergency(e) => e.to_frame(*node),
                    Msg::Heartbeat(h) => h.to_frame(*node),
                    _ => unreachable!(),
                };
                self.rx.push_back(Received {
                    frame,
                    t_us: self.now,
                    own: false,
                });
            }
            Ok(true)
        }
        fn recv(&mut self) -> Result<Option<Received>, PortError> {
            Ok(self.rx.pop_front())
        }
    }

    fn emergency(state: State, code: FaultCode) -> Msg {
        Msg::Emergency(Emergency {
            code: code as u8,
            state: state as u8,
            ramp_100us: 0,
            plan_time_us: 0,
        })
    }

    fn heartbeat(state: State, code: FaultCode) -> Msg {
        Msg::Heartbeat(Heartbeat {
            state: state as u8,
            fault: code as u8,
            ..Heartbeat::default()
        })
    }

    fn drives(answer: Vec<(u8, Msg)>) -> Drives {
        Drives {
            now: 0,
            rx: VecDeque::new(),
            sent: 0,
            answer,
            full: 0,
        }
    }

    #[test]
    fn every_drive_answers_at_once() {
        let mut d = drives(vec![
            (4, emergency(State::Fault, FaultCode::HostEmergency)),
            (5, emergency(State::Stopping, FaultCode::HostEmergency)),
            (6, heartbeat(State::Fault, FaultCode::HostEmergency)),
        ]);
        let w = emergency_stop(&mut d, [4, 5, 6], 200_000, || {}).unwrap();
        assert!(w.all_answered() && w.silent().is_empty());
        assert_eq!(
            w.answers(),
            [
                Some(EstopAnswer::Heard {
                    state: State::Fault
                }),
                Some(EstopAnswer::Heard {
                    state: State::Stopping
                }),
                Some(EstopAnswer::Heard {
                    state: State::Fault
                }),
            ]
        );
        assert_eq!(d.sent, 1, "no resend once all answered");
        assert!(d.now < 10_000, "returns at once: {} µs", d.now);
    }

    #[test]
    fn a_silent_drive_is_named_after_the_wait_with_resends() {
        // Node 3 is off the bus; a heartbeat of node 7 (not addressed) and a
        // drive stopping without a fault (a Stop) do not count.
        let mut d = drives(vec![
            (1, emergency(State::Fault, FaultCode::HostEmergency)),
            (2, heartbeat(State::Stopping, FaultCode::None)),
            (7, emergency(State::Fault, FaultCode::HostEmergency)),
        ]);
        let w = emergency_stop(&mut d, [1, 2, 3], 200_000, || {}).unwrap();
        assert_eq!(w.silent(), vec![2, 3]);
        assert!(!w.all_answered());
        assert!((200_000..210_000).contains(&d.now), "{} µs", d.now);
        // Sent at 0 and resent every 50 ms while silent.
        assert_eq!(d.sent, 4);
    }

    #[test]
    fn a_drive_already_in_fault_is_stopped_but_not_heard() {
        let mut d = drives(vec![
            (1, heartbeat(State::Fault, FaultCode::FollowingError)),
            (2, emergency(State::Fault, FaultCode::HostEmergency)),
            (3, heartbeat(State::Stopping, FaultCode::SoftLimit)),
        ]);
        let w = emergency_stop(&mut d, [1, 2, 3], 200_000, || {}).unwrap();
        assert!(w.all_answered());
        assert_eq!(
            w.answers()[0],
            Some(EstopAnswer::Already {
                state: State::Fault,
                fault: FaultCode::FollowingError
            })
        );
        assert_eq!(
            w.answers()[2],
            Some(EstopAnswer::Already {
                state: State::Stopping,
                fault: FaultCode::SoftLimit
            })
        );
    }

    #[test]
    fn a_full_transmit_queue_is_waited_for_then_an_error() {
        let mut d = drives(vec![(1, emergency(State::Fault, FaultCode::HostEmergency))]);
        d.full = 5;
        let w = emergency_stop(&mut d, [1, 2, 3], 200_000, || {}).unwrap();
        assert_eq!(w.silent(), vec![2, 3]);
        let mut d = drives(Vec::new());
        d.full = usize::MAX;
        let e = emergency_stop(&mut d, [1, 2, 3], 200_000, || {}).unwrap_err();
        assert!(matches!(e, EstopError::NotSent(200)), "{e}");
    }
}
