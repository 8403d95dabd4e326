//! Homing in the drive: the Home command, the homing step of the tick and
//! the new axis zero when it is done. The motion itself is the `homing`
//! module's; here it meets the state machine and the encoder's frame.

use triquint_shared::protocol::{FaultCode, State};

use super::{Drive, StopReason};
use crate::derived_config::DerivedConfig;
use crate::f32_cast::{to_f32, to_i64};
use crate::homing::{Homing, HomingEvent, HomingLimits};

impl<const Q: usize> Drive<Q> {
    /// Home: Idle with a configuration, switch not active. A switch already
    /// active is a fault (the axis is on or beyond it: homing would not
    /// see an edge).
    pub(super) fn home(&mut self, local_us: u64) -> FaultCode {
        if self.state != State::Idle {
            return FaultCode::WrongState;
        }
        if self.active.is_none() {
            return FaultCode::NoConfig;
        }
        if self.switch_active {
            self.fault_now(FaultCode::HomeSwitchActive);
            return FaultCode::HomeSwitchActive;
        }
        // From the reference the loop holds now: no step.
        self.homing = Some(Homing::new(self.hold_own, local_us));
        self.state = State::Homing;
        FaultCode::None
    }

    /// Stop or QuickStop while homing: slow to rest, then Idle (not homed).
    pub(super) fn abort_homing(&mut self) {
        if let Some(h) = self.homing.as_mut() {
            h.abort();
        }
    }

    /// An Emergency while homing: the axis slows to rest with the homing
    /// ramp (as a plan stops along its path; holding at once would be a step
    /// in velocity), Stopping meanwhile, then Fault. The Emergency goes out
    /// at once, so peers stop together.
    pub(super) fn fault_homing(&mut self, code: FaultCode) {
        self.abort_homing();
        self.state = State::Stopping;
        self.stop_reason = Some(StopReason::Fault(code));
        self.fault = code;
        self.emergency(code);
    }

    /// One homing period: the reference of this tick (in this tick's frame).
    // Not inlined: the tick's own code must fit the ESC1's CCM SRAM.
    #[inline(never)]
    pub(super) fn homing_step(
        &mut self,
        a: &DerivedConfig,
        q: f32,
        edge: Option<i64>,
        now_us: u64,
    ) -> f32 {
        let Some(mut h) = self.homing else {
            return self.hold_own;
        };
        let l = HomingLimits::new(&self.cfg);
        let edge = edge.map(|c| c.wrapping_sub(self.home_offset));
        match h.step(&l, a.dt, q, edge, now_us) {
            HomingEvent::Moving => {
                self.homing = Some(h);
            }
            HomingEvent::Done { edge_counts } => {
                // The edge is at the switch height: the new zero, and the
                // reference and last measurement moved into its frame.
                let cpm = self.cfg.counts_per_metre;
                let zero = edge_counts - to_i64(self.cfg.switch_height * cpm);
                let shift = to_f32(-zero) * a.inv_cpm;
                self.home_offset = self.home_offset.wrapping_add(zero);
                self.hold_own = h.q + shift;
                self.last_q = self.last_q.map(|x| x + shift);
                self.hold = None;
                self.homed = true;
                self.homing = None;
                self.state = State::Idle;
            }
            HomingEvent::Aborted => {
                self.hold_own = h.q;
                self.homing = None;
                // At rest after a Stop (Idle) or an Emergency (Fault, its code kept).
                if self.state == State::Stopping {
                    self.stop_reason = None;
                    self.state = State::Fault;
                    self.react_at_rest(self.fault);
                } else {
                    self.state = State::Idle;
                }
            }
            HomingEvent::Fault(code) => {
                self.homing = Some(h);
                self.fault_now(code);
            }
        }
        h.q
    }

    /// Is `node` the drive of one of this robot's axes (configured)?
    pub(super) fn is_peer(&self, node: u8) -> bool {
        self.peer_axis(node).is_some()
    }

    /// The axis (0–2) whose drive is `node`, by the configuration.
    pub(super) fn peer_axis(&self, node: u8) -> Option<usize> {
        self.active?;
        self.cfg.axis_nodes().iter().position(|&n| n == node as f32)
    }
}
