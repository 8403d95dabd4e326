//! Supervision: what stops the drive besides a command. Emergencies and
//! peers' heartbeats (a peer faulted, reset, silent or left behind), the
//! time base, and the motion itself (following error, soft limits); each
//! check gives the fault it calls for, the tick or the item handler acts.

use triquint_shared::protocol::contract::PEER_SKEW_MARGIN_US;
use triquint_shared::protocol::{FaultCode, Heartbeat, State};

use super::{Drive, StopReason};
use crate::derived_config::DerivedConfig;
use crate::enable_check::{Expected, Verdict};
use crate::reaction::{self, Reaction};
use crate::scaling::Retarget;

impl<const Q: usize> Drive<Q> {
    pub(super) fn on_emergency(
        &mut self,
        code: FaultCode,
        t: i64,
        ready: Option<&Retarget>,
        ramp_100us: u16,
    ) {
        match self.state {
            State::Running => {
                self.begin_stop_dated(StopReason::Fault(code), false, t, ready, Some(ramp_100us))
            }
            State::Stopping if !matches!(self.stop_reason, Some(StopReason::Fault(_))) => {
                self.stop_reason = Some(StopReason::Fault(code));
                self.fault = code;
            }
            State::Homing => self.fault_homing(code),
            State::Loaded | State::Armed => self.fault_now(code),
            State::Idle if code == FaultCode::HostEmergency => self.fault_now(code),
            _ => {}
        }
    }

    /// Peer supervision: a peer that reports a fault (its Emergency may have
    /// been lost) or has lost its configuration (it was reset) stops us too.
    pub(super) fn on_peer_heartbeat(&mut self, node: u8, h: &Heartbeat, rx_us: u64) {
        let Some(slot) = self
            .peer_axis(node)
            .and_then(|i| self.peer_seen_us.get_mut(i))
        else {
            return;
        };
        *slot = Some(rx_us);
        if self.state != State::Running {
            return;
        }
        let peer = h.state().ok();
        let code = if !matches!(h.fault(), Ok(FaultCode::None | FaultCode::QuickStop)) {
            FaultCode::PeerEmergency
        } else if h.config_crc == 0 || self.peer_left_behind(peer, rx_us) {
            FaultCode::PeerLost
        } else {
            return;
        };
        let t = self.sync.host_ns(rx_us).unwrap_or(0);
        self.on_emergency(code, t, None, 0);
    }

    /// A peer still Loaded or Armed (it missed the Start) well after we
    /// started, or Idle before our plan's last segment: it is not moving
    /// with us. The margins cover the start skew (one tick) and the end skew.
    pub(super) fn peer_left_behind(&self, peer: Option<State>, local_us: u64) -> bool {
        const MARGIN_NS: i64 = PEER_SKEW_MARGIN_US as i64 * 1000;
        let (Some(t), Some(t0)) = (self.sync.host_ns(local_us), self.stats.started_at_ns) else {
            return false;
        };
        match peer {
            Some(State::Loaded | State::Armed) => t - t0 > MARGIN_NS,
            Some(State::Idle) => self
                .queue
                .back()
                .is_some_and(|b| !b.last || self.plan_ns + MARGIN_NS < b.end_ns()),
            _ => false,
        }
    }

    /// A peer (seen at least once) whose heartbeat has been missing for the
    /// sync timeout.
    pub(super) fn peer_silent(&self, a: &DerivedConfig, now_us: u64) -> bool {
        self.peer_seen_us
            .iter()
            .enumerate()
            .filter(|(i, _)| *i != a.axis)
            .any(|(_, t)| t.is_some_and(|t| now_us.saturating_sub(t) > a.sync_timeout_us))
    }

    /// Supervision of the time base and the peers: the fault it calls for, if any.
    pub(super) fn time_fault(
        &self,
        a: &DerivedConfig,
        has_host_time: bool,
        now_us: u64,
    ) -> Option<FaultCode> {
        let lost = self.sync.lost(now_us, a.sync_timeout_us) || !has_host_time;
        if lost && matches!(self.state, State::Armed | State::Running) {
            Some(FaultCode::LostSync)
        } else if self.state == State::Running && self.peer_silent(a, now_us) {
            Some(FaultCode::PeerLost)
        } else {
            None
        }
    }

    // Cold, out of line: the tick's own code must fit the ESC1's CCM SRAM.
    #[cold]
    #[inline(never)]
    pub(super) fn on_time_fault(&mut self, code: FaultCode, now_us: u64, timeout_us: u64) {
        match self.state {
            State::Armed => self.fault_now(code),
            // Without a time base, keep stepping on the local clock; from
            // the instant the sync was lost, as every node dates it.
            _ => {
                let now = self.sync.host_ns(now_us).unwrap_or(0);
                let t = match code {
                    FaultCode::LostSync => self.sync.lost_at_ns(now_us, timeout_us),
                    _ => None,
                };
                self.begin_stop(
                    StopReason::Fault(code),
                    false,
                    t.map_or(now, |t| t.min(now)),
                )
            }
        }
    }

    /// Supervision of the motion in every powered state (the servo loop is
    /// closed from the configuration on): following error beyond its bound,
    /// or, once homed, a measured position outside the soft limits (accepted
    /// segments stay inside them: a runaway axis). At rest the travel check
    /// needs the reference inside, so an axis powered on beyond a limit is
    /// not faulted for standing still. Homing has its own bound; a Fault is
    /// already held.
    pub(super) fn motion_fault(&self, error: f32, q: f32, r: f32) -> Option<FaultCode> {
        let inside = |x: f32| x >= self.cfg.soft_limit_min && x <= self.cfg.soft_limit_max;
        if self.state == State::Fault || self.homing.is_some() {
            None
        } else if error.abs() > self.cfg.following_error_max {
            Some(FaultCode::FollowingError)
        } else if self.homed && !inside(q) && (self.state == State::Running || inside(r)) {
            Some(FaultCode::SoftLimit)
        } else {
            None
        }
    }

    /// The reaction to a motion fault, from the reaction table: moving,
    /// stop along the path (then Fault at rest) or, where the loop may be
    /// positive feedback, torque off at once; at rest, Fault with the
    /// table's reaction at rest.
    // Cold, out of line: the tick's own code must fit the ESC1's CCM SRAM.
    #[cold]
    #[inline(never)]
    pub(super) fn on_motion_fault(&mut self, code: FaultCode, now_us: u64) {
        let moving = matches!(self.state, State::Running | State::Stopping);
        if moving && reaction::reaction(code, true, self.reaction_axis()) == Reaction::TorqueOff {
            self.queue.clear();
            self.ramps_cleared();
            self.stop_reason = None;
            self.fault_now(code);
            self.torque_off = true;
            return;
        }
        match self.state {
            State::Running => {
                let t = self.sync.host_ns(now_us).unwrap_or(0);
                self.begin_stop(StopReason::Fault(code), false, t)
            }
            State::Stopping if !matches!(self.stop_reason, Some(StopReason::Fault(_))) => {
                self.stop_reason = Some(StopReason::Fault(code));
                self.fault = code;
                self.emergency(code);
            }
            State::Idle | State::Loaded | State::Armed => self.fault_now(code),
            _ => {}
        }
    }

    /// After the law, when the enable check runs or the drive is in Fault:
    /// a tick of the check, the Fault state's supervision, and the torque
    /// to command (the open-loop hold's in place of the loop's).
    #[cold]
    #[inline(never)]
    pub(super) fn check_and_fault(
        &mut self,
        torque: f32,
        error: f32,
        q: f32,
        dt: f32,
        now_us: u64,
    ) -> f32 {
        if self.check.is_some() {
            self.step_check(q, torque, dt, now_us);
        }
        if self.state == State::Fault && !self.torque_off {
            self.supervise_fault(error);
        }
        self.open_loop.unwrap_or(torque)
    }

    /// Supervision of the Fault state: an axis held in Fault whose
    /// following error exceeds its bound is not being held; the table's
    /// reaction to a following error at rest then applies (torque off
    /// where it allows, with an Emergency saying why).
    #[cold]
    #[inline(never)]
    pub(super) fn supervise_fault(&mut self, error: f32) {
        // Held open loop (a wrong encoder scale), the axis may sink slowly:
        // torque off would let it sink faster. Rising beyond the bound, the
        // open-loop torque exceeds the weight: torque off ends that.
        let bound = self.cfg.following_error_max;
        let beyond = match self.open_loop {
            Some(_) => -error > bound,
            None => error.abs() > bound,
        };
        if beyond
            && reaction::reaction(FaultCode::FollowingError, false, self.reaction_axis())
                == Reaction::TorqueOff
        {
            self.torque_off = true;
            self.check = None;
            self.emergency(FaultCode::FollowingError);
        }
    }

    /// One tick of the enable check (at rest only: a move or homing before
    /// its verdict leaves the axis unverified). Its verdict: passed, or a
    /// fault naming what is wrong.
    #[cold]
    #[inline(never)]
    pub(super) fn step_check(&mut self, q: f32, torque: f32, dt: f32, now_us: u64) {
        let at_rest = matches!(self.state, State::Idle | State::Loaded | State::Armed)
            && self.homing.is_none();
        let model = Expected::of(&self.model);
        let verdict = match (at_rest, self.check.as_mut()) {
            (true, Some(c)) => match c.step(q, torque, dt, &model) {
                Some(v) => {
                    self.stats.check_gain_ratio = c.gain() / model.gain;
                    self.measured_load = c.load();
                    self.stats.check_load_ratio = c.load().unwrap_or(0.0) / model.load;
                    v
                }
                None => return,
            },
            _ => Verdict::Inconclusive,
        };
        self.check = None;
        match verdict {
            Verdict::Pass => self.verified = true,
            Verdict::Inconclusive => {}
            Verdict::WrongDirection => self.on_motion_fault(FaultCode::WrongDirection, now_us),
            Verdict::WrongScale => self.on_motion_fault(FaultCode::WrongScale, now_us),
        }
    }
}
