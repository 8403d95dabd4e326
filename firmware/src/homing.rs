//! Homing of one axis as a pure state machine: seek the limit switch at a
//! jerk-limited speed, latch the encoder count of its edge (a capture
//! input), brake, back off, settle. The reference it produces is in the
//! encoder's own frame (the axis zero is unknown until it is done); the
//! drive closes its loop on it without feedforward (the pose is unknown).
//! Every bound that protects the machine while the pose is unknown is
//! checked here: maximum travel, timeout, following error.

use triquint_shared::protocol::{DriveConfig, FaultCode};

/// Below this speed (m/s) a settling reference is taken as at rest.
const REST_SPEED: f32 = 1e-5;

/// Where homing is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HomingPhase {
    /// Moving toward the switch at the homing speed.
    Seek,
    /// Edge latched: slowing to rest.
    Brake,
    /// Moving back off the switch.
    BackOff,
    /// Slowing to rest at the end of the back-off.
    Settle,
    /// Stop commanded: slowing to rest, then Idle, not homed.
    Abort,
}

/// The limits of the homing motion, from a configuration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HomingLimits {
    pub velocity: f32,
    pub acceleration: f32,
    pub jerk: f32,
    /// +1 or −1: the direction of the switch.
    pub direction: f32,
    pub backoff: f32,
    pub max_travel: f32,
    pub timeout_us: u64,
    pub following_error_max: f32,
}

impl HomingLimits {
    pub fn new(cfg: &DriveConfig) -> Self {
        let t = cfg.homing_timeout * 1e6;
        Self {
            velocity: cfg.homing_velocity,
            acceleration: cfg.homing_acceleration,
            jerk: cfg.homing_jerk,
            direction: if cfg.homing_direction < 0.0 {
                -1.0
            } else {
                1.0
            },
            backoff: cfg.homing_backoff,
            max_travel: cfg.homing_max_travel,
            timeout_us: if t > 0.0 { t as u64 } else { 0 },
            following_error_max: cfg.homing_following_error_max,
        }
    }
}

/// What one step of homing gives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HomingEvent {
    /// Still homing.
    Moving,
    /// At rest after the back-off: the switch edge was at this encoder count.
    Done { edge_counts: i64 },
    /// Homing failed.
    Fault(FaultCode),
    /// Stopped on command, at rest.
    Aborted,
}

/// One homing run of one axis. Positions in metres in the encoder's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Homing {
    pub phase: HomingPhase,
    /// Reference position, velocity and acceleration.
    pub q: f32,
    pub v: f32,
    pub a: f32,
    start_q: f32,
    started_us: u64,
    /// Encoder count of the switch edge, and the reference when it came.
    edge: Option<(i64, f32)>,
}

impl Homing {
    /// Homing from rest at `q` (m), local time `now_us`.
    pub fn new(q: f32, now_us: u64) -> Self {
        Self {
            phase: HomingPhase::Seek,
            q,
            v: 0.0,
            a: 0.0,
            start_q: q,
            started_us: now_us,
            edge: None,
        }
    }

    /// Moves the reference one period `dt` toward speed `target` with the
    /// acceleration and jerk limits (the acceleration heads for the value
    /// that reaches `target` without overshoot).
    fn toward(&mut self, target: f32, l: &HomingLimits, dt: f32) {
        let dv = target - self.v;
        // Half a period of the current acceleration is still to come
        // (discrete steps): without it the arrival would drop ~0.7 of a
        // period's jerk.
        let left = (dv.abs() - 0.5 * self.a.abs() * dt).max(0.0);
        let reach = libm::sqrtf(2.0 * l.jerk * left).min(l.acceleration);
        let want = if dv >= 0.0 { reach } else { -reach };
        let da = (want - self.a).max(-l.jerk * dt).min(l.jerk * dt);
        self.a += da;
        let v = self.v + self.a * dt;
        // Reaching the target within the period: arrive, do not overshoot.
        if (target - v) * dv < 0.0 {
            self.v = target;
            self.a = 0.0;
        } else {
            self.v = v;
        }
        self.q += self.v * dt;
    }

    /// Distance (m) the reference needs to come to rest, jerk-limited: an
    /// acceleration along the motion first ramps to zero (gaining speed),
    /// then the speed v comes down in a trapezoidal acceleration profile,
    /// v²/2A + vA/2J, or a triangular one, v·√(v/J), when v < A²/J.
    fn stop_distance(&self, l: &HomingLimits) -> f32 {
        let s = if self.v < 0.0 { -1.0 } else { 1.0 };
        let (v, a) = (self.v * s, (self.a * s).max(0.0));
        let t1 = a / l.jerk;
        let ramp = v * t1 + 0.5 * a * t1 * t1 - l.jerk * t1 * t1 * t1 / 6.0;
        let v1 = v + 0.5 * a * t1;
        let brake = if v1 >= l.acceleration * l.acceleration / l.jerk {
            v1 * v1 / (2.0 * l.acceleration) + v1 * l.acceleration / (2.0 * l.jerk)
        } else {
            v1 * libm::sqrtf(v1 / l.jerk)
        };
        ramp + brake
    }

    /// One control period: the measured position `q_meas` (m), the switch's
    /// latest edge (captured count), local time `now_us`.
    pub fn step(
        &mut self,
        l: &HomingLimits,
        dt: f32,
        q_meas: f32,
        edge: Option<i64>,
        now_us: u64,
    ) -> HomingEvent {
        if l.timeout_us > 0 && now_us.saturating_sub(self.started_us) > l.timeout_us {
            return HomingEvent::Fault(FaultCode::HomingTimeout);
        }
        if (self.q - q_meas).abs() > l.following_error_max {
            return HomingEvent::Fault(FaultCode::FollowingError);
        }
        let dir = l.direction;
        match self.phase {
            HomingPhase::Seek => {
                if let Some(c) = edge {
                    self.edge = Some((c, self.q));
                    self.phase = HomingPhase::Brake;
                } else if (self.q - self.start_q).abs() > l.max_travel {
                    return HomingEvent::Fault(FaultCode::HomeSwitchNeverTriggered);
                } else {
                    self.toward(dir * l.velocity, l, dt);
                }
            }
            HomingPhase::Brake => {
                self.toward(0.0, l, dt);
                if self.at_rest(l, dt) {
                    self.rest();
                    self.phase = HomingPhase::BackOff;
                }
            }
            HomingPhase::BackOff => {
                let from = self.edge.map_or(self.q, |e| e.1);
                let backed = (from - self.q) * dir;
                if backed + self.stop_distance(l) >= l.backoff {
                    self.phase = HomingPhase::Settle;
                } else {
                    self.toward(-dir * l.velocity, l, dt);
                }
            }
            HomingPhase::Abort => {
                self.toward(0.0, l, dt);
                if self.at_rest(l, dt) {
                    self.rest();
                    return HomingEvent::Aborted;
                }
            }
            HomingPhase::Settle => {
                self.toward(0.0, l, dt);
                if self.at_rest(l, dt) {
                    self.rest();
                    if let Some((c, _)) = self.edge {
                        return HomingEvent::Done { edge_counts: c };
                    }
                }
            }
        }
        HomingEvent::Moving
    }

    /// Slow enough, with little enough acceleration, to stop now (within
    /// one period's jerk).
    fn at_rest(&self, l: &HomingLimits, dt: f32) -> bool {
        self.v.abs() <= REST_SPEED && self.a.abs() <= l.jerk * dt
    }

    /// Slow to rest and stop homing (a Stop command).
    pub fn abort(&mut self) {
        self.phase = HomingPhase::Abort;
    }

    /// At rest: the last tiny speed is dropped (at most `REST_SPEED`).
    fn rest(&mut self) {
        self.v = 0.0;
        self.a = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn limits() -> HomingLimits {
        HomingLimits {
            velocity: 0.025,
            acceleration: 0.25,
            jerk: 2.5,
            direction: 1.0,
            backoff: 0.005,
            max_travel: 0.4,
            timeout_us: 30_000_000,
            following_error_max: 2e-3,
        }
    }

    /// Runs homing on a perfect axis with a switch at `switch` (m); counts at 1 µm.
    fn run(l: &HomingLimits, start: f32, switch: Option<f32>) -> (HomingEvent, Homing, u64) {
        let mut h = Homing::new(start, 0);
        let dt = 1e-3;
        let mut was_on = switch.is_some_and(|s| (start - s) * l.direction >= 0.0);
        for k in 1..100_000u64 {
            let on = switch.is_some_and(|s| (h.q - s) * l.direction >= 0.0);
            let edge = (on && !was_on).then_some((h.q * 1e6) as i64);
            was_on = on;
            let q = h.q;
            match h.step(l, dt, q, edge, k * 1000) {
                HomingEvent::Moving => {}
                e => return (e, h, k),
            }
        }
        (HomingEvent::Moving, h, 0)
    }

    #[test]
    fn seeks_latches_backs_off_and_settles_within_the_limits() {
        let l = limits();
        let (e, h, ticks) = run(&l, 0.1, Some(0.42));
        let HomingEvent::Done { edge_counts } = e else {
            panic!("{e:?}");
        };
        // The edge within a tick's travel (25 µm) of the switch.
        assert!((edge_counts - 420_000).abs() <= 26, "{edge_counts}");
        // Backed off the back-off from the switch (within the edge's tick
        // and the discrete stop), at rest: the travel's end, not short of it.
        let backed = 0.42 - h.q;
        assert!((backed - l.backoff).abs() < 1e-4, "{backed}");
        assert_eq!((h.v, h.a), (0.0, 0.0));
        // 0.32 m at 25 mm/s: about 13 s.
        assert!((12_000..16_000).contains(&ticks), "{ticks}");
    }

    #[test]
    fn speed_acceleration_and_jerk_stay_within_the_limits() {
        let l = limits();
        let mut h = Homing::new(0.0, 0);
        let dt = 1e-3;
        let mut last_a = 0.0f32;
        for k in 1..4000u64 {
            let edge = (k == 2000).then_some(1);
            let q = h.q;
            match h.step(&l, dt, q, edge, k * 1000) {
                HomingEvent::Moving => {}
                HomingEvent::Done { edge_counts } => {
                    assert_eq!(edge_counts, 1);
                    break;
                }
                e => panic!("{e:?}"),
            }
            assert!(h.v.abs() <= l.velocity * 1.001, "{}", h.v);
            assert!(h.a.abs() <= l.acceleration * 1.001, "{}", h.a);
            // Arriving at a speed drops what is left of the acceleration:
            // at most two periods' worth of jerk.
            assert!(
                (h.a - last_a).abs() <= 2.0 * l.jerk * dt * 1.001,
                "{k} {:?} {} {}",
                h.phase,
                h.a,
                last_a
            );
            last_a = h.a;
        }
    }

    #[test]
    fn downward_homing_mirrors_upward() {
        let l = HomingLimits {
            direction: -1.0,
            ..limits()
        };
        let (e, h, _) = run(&l, 0.3, Some(0.05));
        assert!(matches!(e, HomingEvent::Done { .. }), "{e:?}");
        assert!(h.q > 0.05 && h.q < 0.05 + 0.009, "{}", h.q);
    }

    #[test]
    fn a_dead_switch_ends_at_the_maximum_travel() {
        let l = limits();
        let (e, h, _) = run(&l, 0.1, None);
        assert_eq!(e, HomingEvent::Fault(FaultCode::HomeSwitchNeverTriggered));
        assert!((h.q - 0.1 - l.max_travel).abs() < 1e-3, "{}", h.q);
    }

    #[test]
    fn timeout_and_following_error_fault() {
        let l = HomingLimits {
            timeout_us: 1_000_000,
            ..limits()
        };
        let (e, _, ticks) = run(&l, 0.1, Some(0.42));
        assert_eq!(e, HomingEvent::Fault(FaultCode::HomingTimeout));
        assert_eq!(ticks, 1001);
        let mut h = Homing::new(0.0, 0);
        assert_eq!(
            h.step(&limits(), 1e-3, 0.003, None, 1000),
            HomingEvent::Fault(FaultCode::FollowingError)
        );
    }
}
