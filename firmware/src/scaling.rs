//! Along-path time-scaling: plan time s advances at rate σ(t). A stop uses
//! σ = 1 − S(u), u = (t − t₀)/T, S(u) = 10u³ − 15u⁴ + 6u⁵, in closed form, so
//! every node computes the same s from the same host time with no drift:
//! s = s₀ + T·(u − 2.5u⁴ + 3u⁵ − u⁶), at rest after T/2 of plan time.
//! Resume uses σ = S(u): s = s₀ + T·(2.5u⁴ − 3u⁵ + u⁶).

use crate::ns::{to_f32, to_i64};

/// Phase of the time-scaling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// σ = 1: s = s₀ + (t − t₀).
    Nominal,
    /// σ falls from 1 to 0 over T.
    Decel,
    /// σ = 0.
    Rest,
    /// σ rises from 0 to 1 over T.
    Accel,
}

/// Plan time and its first two time derivatives of σ at one instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Scaled {
    /// Plan time (ns).
    pub s_ns: i64,
    pub sigma: f32,
    /// dσ/dt (1/s).
    pub sigma_d: f32,
    /// d²σ/dt² (1/s²).
    pub sigma_dd: f32,
}

/// Time-scaling state, anchored at host time t₀ and plan time s₀.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeScaling {
    pub phase: Phase,
    pub t0_ns: i64,
    pub s0_ns: i64,
    /// Ramp duration T (ns).
    pub ramp_ns: i64,
}

fn smooth(u: f32) -> (f32, f32, f32) {
    // S, S', S''
    let u2 = u * u;
    let s = u2 * u * (10.0 + u * (-15.0 + 6.0 * u));
    let d1 = 30.0 * u2 * (1.0 + u * (-2.0 + u));
    let d2 = 60.0 * u * (1.0 + u * (-3.0 + 2.0 * u));
    (s, d1, d2)
}

/// T·∫₀ˣ S = T·(2.5x⁴ − 3x⁵ + x⁶) for the ramp fraction x = x_ns/T ≤ 1/2 (ns).
/// Only this correction (≤ 0.08 T) is in f32; the rest of the plan time is
/// integer, so s keeps ns resolution over seconds and the tick uses no f64.
fn correction(x_ns: i64, ramp: i64) -> i64 {
    let x = to_f32(x_ns) / to_f32(ramp);
    let x2 = x * x;
    to_i64(to_f32(ramp) * (x2 * x2 * (2.5 + x * (-3.0 + x))))
}

/// Plan time covered after `dt` of a ramp of length `ramp` (both ns), for
/// σ = 1 − S (decelerating) or σ = S. Past the middle it uses the symmetry
/// ∫₀ᵘ S = 1/2 − v + ∫₀ᵛ S with v = 1 − u, so the f32 part stays small.
fn ramp_distance(dt: i64, ramp: i64, decel: bool) -> i64 {
    let dt = dt.max(0).min(ramp);
    let rest = ramp - dt;
    match (decel, dt <= rest) {
        (true, true) => dt - correction(dt, ramp),
        (true, false) => ramp / 2 - correction(rest, ramp),
        (false, true) => correction(dt, ramp),
        (false, false) => dt - ramp / 2 + correction(rest, ramp),
    }
}

fn fraction(dt: i64, ramp: i64) -> f32 {
    to_f32(dt.max(0).min(ramp)) / to_f32(ramp)
}

impl TimeScaling {
    /// σ = 1 from host time `t0_ns`, plan time `s0_ns`.
    pub fn nominal(t0_ns: i64, s0_ns: i64) -> Self {
        Self {
            phase: Phase::Nominal,
            t0_ns,
            s0_ns,
            ramp_ns: 1,
        }
    }

    /// Evaluates at host time `t_ns`, advancing phases that ended.
    pub fn at(&mut self, t_ns: i64) -> Scaled {
        let dt = t_ns - self.t0_ns;
        let ramp = self.ramp_ns.max(1);
        let t_s = to_f32(ramp) * 1e-9;
        match self.phase {
            Phase::Nominal => Scaled {
                s_ns: self.s0_ns + dt.max(0),
                sigma: 1.0,
                sigma_d: 0.0,
                sigma_dd: 0.0,
            },
            Phase::Decel if dt < ramp => {
                let (s, d1, d2) = smooth(fraction(dt, ramp));
                let ds = ramp_distance(dt, ramp, true);
                Scaled {
                    s_ns: self.s0_ns + ds,
                    sigma: 1.0 - s,
                    sigma_d: -d1 / t_s,
                    sigma_dd: -d2 / (t_s * t_s),
                }
            }
            Phase::Decel => {
                // At rest after T/2 of plan time.
                self.phase = Phase::Rest;
                self.s0_ns += ramp / 2;
                self.t0_ns += ramp;
                self.at(t_ns)
            }
            Phase::Rest => Scaled {
                s_ns: self.s0_ns,
                sigma: 0.0,
                sigma_d: 0.0,
                sigma_dd: 0.0,
            },
            Phase::Accel if dt < ramp => {
                let (s, d1, d2) = smooth(fraction(dt, ramp));
                let ds = ramp_distance(dt, ramp, false);
                Scaled {
                    s_ns: self.s0_ns + ds,
                    sigma: s,
                    sigma_d: d1 / t_s,
                    sigma_dd: d2 / (t_s * t_s),
                }
            }
            Phase::Accel => {
                self.phase = Phase::Nominal;
                self.s0_ns += ramp / 2;
                self.t0_ns += ramp;
                self.at(t_ns)
            }
        }
    }

    /// Starts slowing down at host time `t_ns` (from Nominal or Accel) over `ramp_ns`.
    /// From Accel the current plan time is kept and the ramp restarts at σ = 1
    /// only if σ is close to 1; otherwise it rests at once on the next call.
    pub fn begin_decel(&mut self, t_ns: i64, ramp_ns: i64) {
        let now = self.at(t_ns);
        match self.phase {
            Phase::Nominal | Phase::Accel => {
                self.phase = Phase::Decel;
                self.t0_ns = t_ns;
                self.s0_ns = now.s_ns;
                self.ramp_ns = ramp_ns.max(1);
            }
            Phase::Decel | Phase::Rest => {}
        }
    }

    /// Starts accelerating from rest at host time `t_ns`.
    pub fn begin_accel(&mut self, t_ns: i64, ramp_ns: i64) {
        let now = self.at(t_ns);
        if self.phase == Phase::Rest {
            self.phase = Phase::Accel;
            self.t0_ns = t_ns;
            self.s0_ns = now.s_ns;
            self.ramp_ns = ramp_ns.max(1);
        }
    }

    /// Plan time still to be covered by a stop begun now (ns): T/2 from Nominal.
    pub fn stop_distance_ns(ramp_ns: i64) -> i64 {
        ramp_ns / 2
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decel_reaches_rest_after_half_the_ramp() {
        let mut ts = TimeScaling::nominal(0, 0);
        let t = 1_000_000_000;
        ts.begin_decel(500_000_000, t);
        let a = ts.at(500_000_000);
        assert_eq!(a.s_ns, 500_000_000);
        assert_eq!(a.sigma, 1.0);
        let b = ts.at(1_000_000_000);
        assert!((b.sigma - 0.5).abs() < 1e-6);
        let c = ts.at(1_500_000_000 + 1);
        assert_eq!(ts.phase, Phase::Rest);
        assert_eq!(c.s_ns, 1_000_000_000);
        // Monotone and continuous plan time through the ramp.
        let mut ts = TimeScaling::nominal(0, 0);
        ts.begin_decel(0, t);
        let mut last = -1;
        for k in 0..=1000 {
            let s = ts.at(k * 1_000_000).s_ns;
            assert!(s >= last);
            assert!(s - last.max(0) <= 1_000_001);
            last = s;
        }
        assert!((last - 500_000_000).abs() < 100);
    }

    #[test]
    fn accel_after_rest_returns_to_nominal() {
        let mut ts = TimeScaling::nominal(0, 0);
        ts.begin_decel(0, 400_000_000);
        ts.at(400_000_001);
        ts.begin_accel(1_000_000_000, 400_000_000);
        let mid = ts.at(1_200_000_000);
        assert!((mid.sigma - 0.5).abs() < 1e-6);
        let end = ts.at(2_000_000_000);
        assert_eq!(ts.phase, Phase::Nominal);
        // 200 ms (decel) + 200 ms (accel) of plan time + 600 ms at σ = 1.
        assert!((end.s_ns - 1_000_000_000).abs() < 100, "{}", end.s_ns);
    }

    #[test]
    fn plan_time_is_monotone_and_exact_at_10_khz() {
        for ramp in [1_000_000i64, 200_000_001, 2_000_000_000] {
            for decel in [true, false] {
                let mut last = 0;
                for k in 0..=ramp / 100_000 + 1 {
                    let s = ramp_distance(k * 100_000, ramp, decel);
                    assert!(
                        s >= last,
                        "ramp {ramp} decel {decel} tick {k}: {s} < {last}"
                    );
                    last = s;
                }
                assert!((last - ramp / 2).abs() <= 1, "ramp {ramp}: ends at {last}");
            }
            // Decelerating and accelerating distances add up to the time elapsed.
            for k in 0..=100 {
                let dt = ramp * k / 100;
                let sum = ramp_distance(dt, ramp, true) + ramp_distance(dt, ramp, false);
                assert!(
                    (sum - dt).abs() <= 1 + ramp / 1_000_000_000 * 16,
                    "{sum} vs {dt}"
                );
            }
        }
    }
}
