//! Reference generation: the start trigger, the position reference on the
//! path (queue advance, plan end, end of a stop, underrun) or at the hold
//! pose, and the motion the feedforward is evaluated on.

use triquint_shared::protocol::{FaultCode, State};
use triquint_shared::quintic::JointMotion;

use super::{Drive, FF_LOOKAHEAD_NS_PER_S, StopReason};
use crate::derived_config::DerivedConfig;
use crate::f32_cast::to_i64;
use crate::scaling::{Phase, TimeScaling};
use crate::segment::scale;

impl<const Q: usize> Drive<Q> {
    /// Armed with a start time that has come: Running from its plan time 0.
    pub(super) fn trigger_start(&mut self, host_ns: i64) {
        if self.state == State::Armed
            && let Some(t0) = self.start_ns
            && host_ns >= t0
        {
            self.state = State::Running;
            // A latched hold starts at rest; otherwise at the override (the
            // plan starts at rest, so any constant σ is continuous there).
            let q16 = if self.hold_latched {
                0
            } else {
                self.override_q16
            };
            self.scaling = TimeScaling::constant(t0, 0, q16);
            self.stop_reason = self.hold_latched.then_some(StopReason::Hold);
            self.hold_latched = false;
            self.stats.started_at_ns = Some(host_ns);
        }
    }

    /// The position reference now, and the motion the feedforward is taken
    /// from: on the path when Running or Stopping, else the hold pose.
    pub(super) fn reference(
        &mut self,
        a: &DerivedConfig,
        host_ns: i64,
    ) -> (JointMotion<f32>, JointMotion<f32>) {
        let moving = matches!(self.state, State::Running | State::Stopping);
        let reference = if moving {
            self.path_reference(a, host_ns)
        } else {
            None
        };
        let reference = match reference {
            Some(r) => r,
            None => self.hold_reference(),
        };
        // The torque computed now acts from the next tick on (and is held for
        // one tick): evaluate the feedforward 1.5 ticks ahead on the path.
        let ff_ref = if matches!(self.state, State::Running | State::Stopping) {
            self.lookahead(host_ns + to_i64(FF_LOOKAHEAD_NS_PER_S * a.dt))
                .unwrap_or(reference)
        } else {
            reference
        };
        (reference, ff_ref)
    }

    pub(super) fn hold_reference(&self) -> JointMotion<f32> {
        let mut m = JointMotion::default();
        if let Some(h) = self.hold {
            m.q = h;
        }
        if let Some(a) = &self.active {
            m.q[a.axis.min(2)] = self.hold_own;
        }
        m
    }

    /// The path motion at host time `host_ns` without changing any state.
    pub(super) fn lookahead(&self, host_ns: i64) -> Option<JointMotion<f32>> {
        // A copy of the scaling only when a transition ends in between.
        let sc = self.scaling.peek(host_ns).unwrap_or_else(|| {
            let mut sc = self.scaling;
            sc.at(host_ns)
        });
        let (head, tail) = self.queue.as_slices();
        let seg = head
            .iter()
            .chain(tail)
            .find(|g| sc.s_ns < g.end_ns())
            .or_else(|| self.queue.back())?;
        Some(scale(&seg.eval(sc.s_ns), sc.sigma, sc.sigma_d, sc.sigma_dd))
    }

    /// A stop for a fault came to rest: Fault, and the reaction at rest.
    // Cold, out of line: the tick's own code must fit the ESC1's CCM SRAM.
    #[cold]
    #[inline(never)]
    fn stopped_in_fault(&mut self, code: FaultCode) {
        self.state = State::Fault;
        self.fault = code;
        self.queue.clear();
        self.ramps_cleared();
        self.react_at_rest(code);
    }

    /// Reference on the path (Running/Stopping); handles queue advance, the
    /// end of the plan, the end of a stop and underrun.
    pub(super) fn path_reference(
        &mut self,
        a: &DerivedConfig,
        host_ns: i64,
    ) -> Option<JointMotion<f32>> {
        let sc = self.scaling.at(host_ns);
        while self.queue.len() > 1 {
            match self.queue.front() {
                Some(f) if sc.s_ns >= f.end_ns() => {
                    let (seq, r) = (f.seq, f.ramps_us);
                    let dropped = (f.start_ns, f.duration_us, f.unit_ramps);
                    self.queue.pop_front();
                    self.dropped = dropped;
                    self.ramps_left(seq, r, dropped.2.largest);
                }
                _ => break,
            }
        }
        // Read the front in place: copying a whole segment would cost the tick
        // more than evaluating it.
        let front = self.queue.front()?;
        let path = front.eval(sc.s_ns);
        let (front_last, front_end_ns) = (front.last, front.end_ns());
        self.current_seq = front.seq;
        self.plan_ns = sc.s_ns;
        let m = scale(&path, sc.sigma, sc.sigma_d, sc.sigma_dd);
        self.hold = Some(m.q);
        self.hold_own = m.q[a.axis.min(2)];

        let at_rest = self.scaling.phase == Phase::Rest;
        let last_queued = self.queue.back().map(|b| b.last).unwrap_or(false);
        if self.state == State::Stopping && at_rest {
            match self.stop_reason {
                Some(StopReason::Fault(code)) => self.stopped_in_fault(code),
                _ => {
                    self.flush();
                    self.state = State::Idle;
                }
            }
            return Some(m);
        }
        if self.state == State::Running {
            if front_last && sc.s_ns >= front_end_ns {
                // Plan complete: hold the end.
                self.flush();
                self.state = State::Idle;
                return Some(m);
            }
            let ahead = self.queued_end_ns - sc.s_ns;
            let need = TimeScaling::stop_distance_ns(self.ramps_ns(a).0, self.scaling.target_q16())
                + a.margin_ns;
            if !last_queued
                && matches!(self.scaling.phase, Phase::Nominal | Phase::Accel)
                && ahead < need
            {
                // From where the queue fell short (the same instant on every
                // node that holds the same segments), not this tick.
                let t = self
                    .scaling
                    .constant_host_time_ns(self.queued_end_ns - need)
                    .map_or(host_ns, |t| t.min(host_ns));
                self.begin_stop(StopReason::Fault(FaultCode::Underrun), false, t);
            }
        }
        Some(m)
    }
}
