//! The control law of one axis as pure functions: the feedforward torque
//! from the reference motion (inverse dynamics row and identified friction)
//! and one step of the position loop (PID on the error, bumpless transfer
//! when the feedforward appears or vanishes, integral and torque limits).
//! No frames, no state machine: what the tick feeds in and what comes out,
//! so the law can be tested alone.

use nalgebra::Vector3;
use triquint_shared::Model;
use triquint_shared::dynamics;
use triquint_shared::protocol::DriveConfig;
use triquint_shared::quintic::JointMotion;

use crate::derived_config::DerivedConfig;

/// Slope of the smoothed Coulomb friction sign through zero speed (s/m):
/// tanh(v · 1000) is ±0.96 at ±2 mm/s.
pub const FRICTION_SMOOTHING: f32 = 1000.0;
/// tanh's argument is limited to ±this: tanh(20) is 1 in f32, and e^40 stays finite.
pub const FRICTION_SATURATION: f32 = 20.0;

/// x limited to ±lim. Unlike `f32::clamp`, no panic path (clamp asserts
/// min ≤ max), so the control tick has none.
pub fn limit(x: f32, lim: f32) -> f32 {
    x.max(-lim).min(lim)
}

/// Gains and limits of the position loop.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Gains {
    pub kp: f32,
    pub ki: f32,
    pub kd: f32,
    /// The integral term stays within ± this (N·m).
    pub integral_limit: f32,
    /// The torque command stays within ± this (N·m).
    pub max_torque: f32,
    /// Control period (s).
    pub dt: f32,
    /// First-order filter constant of the error derivative.
    pub vel_alpha: f32,
}

impl Gains {
    pub fn new(cfg: &DriveConfig, a: &DerivedConfig) -> Self {
        Self {
            kp: cfg.kp,
            ki: cfg.ki,
            kd: cfg.kd,
            integral_limit: cfg.integral_limit,
            max_torque: cfg.max_torque,
            dt: a.dt,
            vel_alpha: a.vel_alpha,
        }
    }
}

/// What the law keeps between steps.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct LawState {
    pub integral: f32,
    /// The previous error (none: the first step after enabling).
    pub last_e: Option<f32>,
    /// Filtered error derivative (m/s).
    pub ev: f32,
    /// The previous step's feedforward, and whether it was on.
    pub last_ff: f32,
    pub ff_active: bool,
}

/// One step's result.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// Torque command within ± max_torque (N·m), before the motor's direction.
    pub torque: f32,
    /// Reference − measured position (m).
    pub error: f32,
}

/// Smoothed Coulomb and viscous friction force of a slider at speed `v`
/// (N): `coulomb · tanh(v · FRICTION_SMOOTHING) + viscous · v`.
pub fn friction(v: f32, coulomb: f32, viscous: f32) -> f32 {
    let x = (v * FRICTION_SMOOTHING).clamp(-FRICTION_SATURATION, FRICTION_SATURATION);
    let e2 = libm::expf(2.0 * x);
    let sign = (e2 - 1.0) / (e2 + 1.0);
    coulomb * sign + viscous * v
}

/// The motor torque that makes axis `axis` follow `motion` (N·m): the
/// inverse dynamics row of the robot plus the friction of its slider,
/// through the gear ratio. `None`: the pose is outside the workspace.
pub fn feedforward(
    model: &Model<f32>,
    cfg: &DriveConfig,
    motion: &JointMotion<f32>,
    axis: usize,
) -> Option<f32> {
    let i = axis.min(2);
    let t: Vector3<f32> = dynamics::torque(model, &motion.q, &motion.qd, &motion.qdd).ok()?;
    let f = friction(motion.qd[i], cfg.friction_coulomb, cfg.friction_viscous);
    Some(t[i] + f * model.inv_ratio)
}

/// One step of the position loop: reference position `r`, measured `q`
/// (m), feedforward `ff` (N·m, 0 when off).
pub fn step(s: &mut LawState, g: &Gains, r: f32, q: f32, ff: f32) -> Step {
    // Bumpless transfer: when the feedforward appears or vanishes (hold
    // pose known, arm), move the step into the integral instead of the motor.
    let lim = g.integral_limit;
    if s.ff_active != (ff != 0.0) {
        s.integral = limit(s.integral + s.last_ff - ff, lim);
        s.ff_active = ff != 0.0;
    }
    s.last_ff = ff;
    let e = r - q;
    // Derivative of the error, through the same backward difference and
    // filter as the measured velocity, so the filter's lag does not turn
    // into a torque error when tracking is perfect.
    let raw_ev = match s.last_e {
        Some(l) => (e - l) / g.dt,
        None => 0.0,
    };
    s.last_e = Some(e);
    s.ev += g.vel_alpha * (raw_ev - s.ev);
    s.integral = limit(s.integral + g.ki * e * g.dt, lim);
    let torque = limit(ff + g.kp * e + g.kd * s.ev + s.integral, g.max_torque);
    Step { torque, error: e }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use super::*;

    fn gains() -> Gains {
        Gains {
            kp: 2000.0,
            ki: 20_000.0,
            kd: 40.0,
            integral_limit: 1.5,
            max_torque: 3.0,
            dt: 1e-3,
            vel_alpha: 0.3,
        }
    }

    /// A unit inertia on a pure torque, one step per tick.
    fn simulate(g: &Gains, r: f32, ticks: usize) -> (Vec<f32>, LawState) {
        let (mut q, mut v) = (0.0f32, 0.0f32);
        let mut s = LawState::default();
        let mut out = Vec::new();
        for _ in 0..ticks {
            let st = step(&mut s, g, r, q, 0.0);
            v += st.torque / 0.2 * g.dt;
            q += v * g.dt;
            out.push(q);
        }
        (out, s)
    }

    #[test]
    fn a_step_reference_is_reached_without_steady_error() {
        let g = gains();
        let (q, s) = simulate(&g, 1e-3, 2000);
        let end = *q.last().unwrap();
        assert!((end - 1e-3).abs() < 1e-6, "end {end}");
        let peak = q.iter().cloned().fold(0.0, f32::max);
        assert!(peak < 1.6e-3, "overshoot: peak {peak}");
        // At rest on target the integral holds nothing (no load).
        assert!(s.integral.abs() < 1e-3, "{s:?}");
    }

    #[test]
    fn the_derivative_starts_from_zero_and_follows_the_error() {
        let g = gains();
        let mut s = LawState::default();
        let first = step(&mut s, &g, 1e-3, 0.0, 0.0);
        // First step: no derivative kick, proportional + one integral step.
        let want = g.kp * 1e-3 + g.ki * 1e-3 * g.dt;
        assert!((first.torque - want).abs() < 1e-6, "{first:?}");
        assert_eq!(first.error, 1e-3);
        let second = step(&mut s, &g, 2e-3, 0.0, 0.0);
        assert!(s.ev > 0.0 && second.torque > first.torque);
    }

    #[test]
    fn the_torque_and_the_integral_saturate() {
        let g = gains();
        let mut s = LawState::default();
        for _ in 0..10_000 {
            let st = step(&mut s, &g, 1.0, 0.0, 0.0);
            assert!(st.torque.abs() <= g.max_torque);
        }
        assert_eq!(s.integral, g.integral_limit);
        let st = step(&mut s, &g, -1.0, 0.0, 0.0);
        assert_eq!(st.torque, -g.max_torque);
    }

    #[test]
    fn feedforward_switching_on_or_off_is_bumpless() {
        let g = gains();
        // Settled on target, no feedforward: the integral carries the load.
        let mut s = LawState {
            integral: 0.8,
            ..LawState::default()
        };
        let before = step(&mut s, &g, 0.0, 0.0, 0.0).torque;
        // The feedforward appears (0.5 N·m): the command does not jump.
        let on = step(&mut s, &g, 0.0, 0.0, 0.5).torque;
        assert!((on - before).abs() < 1e-6, "{before} -> {on}");
        assert!((s.integral - 0.3).abs() < 1e-6, "{s:?}");
        // Changing while on is not a transfer: it reaches the motor.
        let more = step(&mut s, &g, 0.0, 0.0, 0.7).torque;
        assert!((more - on - 0.2).abs() < 1e-6);
        // It vanishes: the integral takes it back.
        let off = step(&mut s, &g, 0.0, 0.0, 0.0).torque;
        assert!((off - more).abs() < 1e-6, "{more} -> {off}");
    }

    #[test]
    fn friction_is_odd_smooth_through_zero_and_viscous_beyond() {
        let (c, b) = (2.0, 10.0);
        assert_eq!(friction(0.0, c, b), 0.0);
        for v in [1e-5f32, 1e-4, 1e-3, 0.01, 0.5] {
            assert!((friction(v, c, b) + friction(-v, c, b)).abs() < 1e-6, "{v}");
        }
        // Small speed: the smoothed sign, far below the Coulomb level.
        assert!(friction(1e-5, c, b) < 0.05 * c);
        // Beyond the smoothing: Coulomb plus viscous.
        let v = 0.2;
        assert!((friction(v, c, b) - (c + b * v)).abs() < 1e-5);
        // Huge speeds stay finite.
        assert!(friction(1e6, c, b).is_finite());
        assert!(friction(f32::MAX, c, 0.0) == c);
    }
}
