//! The feed-override cap of a plan and the stop ramps sized for it.
//!
//! At a constant σ = k the reference is q′k, q″k², q‴k³, and the torque
//! G + k²(τ − G) (inertial and velocity-product terms both scale by k²):
//! the cap is the largest k (at most 32) at which these meet the velocity,
//! acceleration, jerk and torque limits. A transition of the drives'
//! time-scaling (`firmware/src/scaling.rs`) over Δσ lasts
//! T_s·max(√Δσ, Δσ), so |σ̇| ≤ 1.875/T_s and |σ̈| ≤ 5.774/T_s² in every
//! one of them (a hold or stop from the cap, a resume to it, an override
//! change). The stop ramp T_s is sized by `stop_ramp::stop_time` for σ up
//! to k: the joint jerk q‴σ³ + 3q″σσ̇ + q′σ̈ of any transition from a
//! constant σ ≤ k stays within max(J, j·k³ + J/2), the stop budget of
//! docs/protocol.md. The quick stop likewise, at three times the limit.
//! Torque in a transition is checked on a grid of the plan against the
//! limit (or the σ = 1 transitions' own peak if that is above it).

use alloc::vec::Vec;

use nalgebra::Vector3;

use super::Plan;
use crate::Limits;
use crate::dynamics::torque;
use crate::protocol::config::SMOOTHSTEP_MAX_D1;
use crate::protocol::stop_ramp::stop_time;

/// The largest cap the drives accept (configuration range 1–32).
pub const CAP_MAX: f64 = crate::protocol::config::OVERRIDE_CAP_MAX;

/// Torque is checked on this grid of plan time (s).
const TORQUE_STEP_S: f64 = 0.002;

/// Plan maxima over the three joints (m/s, m/s², m/s³).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Maxima {
    pub v: f64,
    pub a: f64,
    pub j: f64,
}

/// The cap and the ramps the drives are configured with.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scaling {
    /// Largest feed override σ, whole per mille, 1–32.
    pub cap: f64,
    /// Controlled stop (and hold, resume, override change) ramp T_s (s).
    pub stop_time_s: f64,
    /// Quick-stop ramp T_q (s).
    pub quick_stop_time_s: f64,
}

/// Stop ramps (T_s, T_q) for a motion of maxima `m` run at σ up to `k`.
pub fn ramps(m: Maxima, limits: &Limits, k: f64) -> (f64, f64) {
    (
        stop_time(m.v, m.a, m.j, limits.jerk, k),
        stop_time(m.v, m.a, 0.0, 3.0 * limits.jerk, k),
    )
}

/// The override cap for `plan` (maxima `m`), never above `max` (the
/// machine's `drive.max_override`), and the stop ramps sized for it.
pub fn override_scaling(plan: &Plan, m: Maxima, max: f64) -> Scaling {
    let max = if max.is_finite() {
        max.clamp(1.0, CAP_MAX)
    } else {
        CAP_MAX
    };
    let l = &plan.limits;
    let tol = 1.0 + 1e-9;
    let kinematic_ok = |k: f64| {
        k * m.v <= l.velocity * tol
            && k * k * m.a <= l.acceleration * tol
            && k * k * k * m.j <= l.jerk * tol
    };
    let k = bisect(1.0, max, kinematic_ok);
    let k = match TorqueGrid::new(plan, m) {
        Some(g) if !g.ok(k) => bisect(1.0, k, |x| g.ok(x)),
        _ => k,
    };
    let cap = (libm::floor(k * 1000.0 + 1e-6) / 1000.0).clamp(1.0, max);
    let (ts, tq) = ramps(m, l, cap);
    Scaling {
        cap,
        stop_time_s: ts,
        quick_stop_time_s: tq,
    }
}

/// Largest x in [lo, hi] with `ok(x)` (`ok(lo)` assumed), to 1e-5.
fn bisect(lo: f64, hi: f64, ok: impl Fn(f64) -> bool) -> f64 {
    if ok(hi) {
        return hi;
    }
    let (mut lo, mut hi) = (lo, hi);
    while hi - lo > 1e-5 {
        let mid = 0.5 * (lo + hi);
        if ok(mid) {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    lo
}

/// The plan sampled for torque: joint states on a grid, and the budget of
/// a transition (the limit, or the σ = 1 transitions' own peak if above).
struct TorqueGrid<'a> {
    plan: &'a Plan,
    m: Maxima,
    states: Vec<[Vector3<f64>; 3]>,
    budget: f64,
}

impl<'a> TorqueGrid<'a> {
    fn new(plan: &'a Plan, m: Maxima) -> Option<Self> {
        let states: Vec<_> = plan
            .sample(TORQUE_STEP_S)
            .ok()?
            .map(|(_, s)| [s.q, s.v, s.a].map(Vector3::from))
            .collect();
        let mut g = Self {
            plan,
            m,
            states,
            budget: f64::INFINITY,
        };
        g.budget = plan.limits.torque.max(g.transition_peak(1.0)?);
        Some(g)
    }

    /// Largest |τ| over the grid at σ ≤ k in a transition of the ramps
    /// for k (|σ̇| up to its bound); `None` if a pose has no dynamics.
    fn transition_peak(&self, k: f64) -> Option<f64> {
        let model = self.plan.robot.model::<f64>();
        let sd = SMOOTHSTEP_MAX_D1 / ramps(self.m, &self.plan.limits, k).0;
        let mut peak = 0.0f64;
        for [q, v, a] in &self.states {
            for s in [k, 0.75 * k, 0.5 * k, 0.25 * k] {
                for sdot in [-sd, sd] {
                    let tau = torque(&model, q, &(v * s), &(a * (s * s) + v * sdot)).ok()?;
                    peak = peak.max(tau.amax());
                }
            }
        }
        Some(peak)
    }

    fn ok(&self, k: f64) -> bool {
        let model = self.plan.robot.model::<f64>();
        let limit = self.plan.limits.torque * (1.0 + 1e-9);
        let constant = self.states.iter().all(|[q, v, a]| {
            torque(&model, q, &(v * k), &(a * (k * k))).is_ok_and(|t| t.amax() <= limit)
        });
        constant
            && self
                .transition_peak(k)
                .is_some_and(|p| p <= self.budget * (1.0 + 1e-9))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn case2() -> Plan {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../testdata/protocol/plans/case2-spline.json"
        ))
        .expect("paper case II plan");
        serde_json::from_str(&text).expect("a plan")
    }

    fn maxima(plan: &Plan) -> Maxima {
        let mx = |x: [f64; 3]| x.iter().fold(0.0f64, |a, b| a.max(*b));
        Maxima {
            v: mx(plan.max_abs.velocity),
            a: mx(plan.max_abs.acceleration),
            j: mx(plan.max_abs.jerk),
        }
    }

    #[test]
    fn a_plan_with_headroom_gets_a_cap_above_one_at_a_limit() {
        let plan = case2();
        let m = maxima(&plan);
        let s = override_scaling(&plan, m, CAP_MAX);
        let (k, l) = (s.cap, &plan.limits);
        assert!(k > 1.0 && k <= CAP_MAX, "cap {k}");
        assert!(k * m.v <= l.velocity && k * k * m.a <= l.acceleration);
        assert!(k.powi(3) * m.j <= l.jerk * (1.0 + 1e-9));
        // At the cap, two per mille more break a limit (here the jerk).
        let k2 = k + 0.002;
        assert!(k2.powi(3) * m.j > l.jerk || k2 * k2 * m.a > l.acceleration);
        assert_eq!((k * 1000.0).round() / 1000.0, k, "whole per mille");
        // The ramps are no shorter than for σ = 1 only, and the jerk of any
        // transition from σ ≤ k stays within the stop budget.
        let (t1, _) = ramps(m, l, 1.0);
        assert!(s.stop_time_s >= t1);
        let t = s.stop_time_s;
        // A stop from the cap, sampled: σ = k(1 − S(u)) over T_s·k.
        let budget = l.jerk.max(k.powi(3) * m.j + 0.5 * l.jerk);
        let worst = (0..=1000)
            .map(|i| {
                let u = i as f64 / 1000.0;
                let s = u.powi(3) * (10.0 - 15.0 * u + 6.0 * u * u);
                let s1 = 30.0 * (u * (1.0 - u)).powi(2);
                let s2 = 60.0 * u * (1.0 - u) * (1.0 - 2.0 * u);
                let sigma = k * (1.0 - s);
                let tt = t * k;
                m.j * sigma.powi(3)
                    + 3.0 * m.a * sigma * k * s1 / tt
                    + m.v * k * s2.abs() / (tt * tt)
            })
            .fold(0.0f64, f64::max);
        assert!(worst <= budget * (1.0 + 1e-9), "{worst} > {budget}");
    }

    #[test]
    fn a_plan_at_its_limits_gets_the_cap_one() {
        let plan = case2();
        let m = Maxima {
            v: plan.limits.velocity,
            a: plan.limits.acceleration,
            j: plan.limits.jerk,
        };
        assert_eq!(override_scaling(&plan, m, CAP_MAX).cap, 1.0);
    }

    #[test]
    fn torque_lowers_the_cap() {
        let mut plan = case2();
        let m = maxima(&plan);
        let free = override_scaling(&plan, m, CAP_MAX).cap;
        // A torque limit just above the plan's own peak: little room.
        let peak = plan.max_abs.torque.iter().fold(0.0f64, |a, b| a.max(*b));
        plan.limits.torque = peak * 1.02;
        let k = override_scaling(&plan, m, CAP_MAX).cap;
        assert!(k < free && k >= 1.0, "{k} vs {free}");
    }
}
