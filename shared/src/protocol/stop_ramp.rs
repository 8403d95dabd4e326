//! The stop ramp T_s: how long the drives' time-scaling transitions take
//! (stop, hold, resume, override change), sized by the host so that the
//! joint jerk of every transition stays within the stop budget
//! (docs/protocol.md, "Stop ramp").
//!
//! A transition of the drives (`firmware/src/scaling.rs`) from a constant σ₀
//! to a constant k, both in [0, cap], is σ(u) = k + (σ₀ − k)(1 − S(u)),
//! S = 10u³ − 15u⁴ + 6u⁵, over T_s·ρ with ρ ≥ max(√Δσ, Δσ), Δσ = |k − σ₀|:
//! so |σ̇| ≤ S'(u)·min(√Δσ, 1)/T_s and |σ̈| ≤ |S''(u)|·min(1, 1/Δσ)/T_s².
//! With the plan's maxima v, a, j of |q′|, |q″|, |q‴| the joint jerk
//! q‴σ³ + 3q″σσ̇ + q′σ̈ is at most
//!   F(Δσ, u) = j·σ(u)³ + 3a·σ(u)·|σ̇(u)| + v·|σ̈(u)|,
//! where σ(u) is largest when the transition ends or starts at the cap
//! (σ = cap − Δσ·S(u) for a slowdown; a speed-up is its mirror in u, with
//! the same |σ̇| and |σ̈|). T_s is the shortest ramp with F ≤ the budget
//! max(J, j·cap³ + J/2) over all Δσ and u: each term is bounded on every
//! cell of a grid over (Δσ, u) by its monotonicity there, so the bound
//! holds between the grid's points, and each cell gives T_s in closed form
//! (F = A + B/T + C/T² is decreasing in T).
//!
//! Unlike a bound that takes every peak at once (3a·1.875/T + v·5.774/T²
//! over and above j), this uses that σ̇ peaks where σ is already lower and
//! that the plan's own jerk term shrinks with σ³.

use super::config::{SMOOTHSTEP_MAX_D1, SMOOTHSTEP_MAX_D2};

/// Cells of the grid over u ∈ [0, 1] and over Δσ ∈ (0, cap].
const U_CELLS: usize = 200;
const DS_CELLS: usize = 200;
/// The drives accept a transition length ρ with Δσ ≤ 1.0001·ρ and
/// Δσ ≤ 1.0001·ρ², and round T_s·ρ in f32: their peaks may exceed the
/// nominal ones by this factor.
const RHO_SLACK: f64 = 1.001;
/// The shortest ramp (s).
const MIN_RAMP_S: f64 = 0.05;

fn s(u: f64) -> f64 {
    u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
}

fn s1(u: f64) -> f64 {
    30.0 * u * u * (1.0 - u) * (1.0 - u)
}

fn s2(u: f64) -> f64 {
    (60.0 * u * (1.0 - u) * (1.0 - 2.0 * u)).abs()
}

/// Largest S' on [u0, u1] (S' rises up to 1/2, then falls).
fn s1_max(u0: f64, u1: f64) -> f64 {
    s1(0.5f64.clamp(u0, u1))
}

/// Largest |S''| on [u0, u1]: at an end or at a peak 1/2 ± 1/(2√3) inside.
fn s2_max(u0: f64, u1: f64) -> f64 {
    let r = 0.5 / libm::sqrt(3.0);
    let mut m = s2(u0).max(s2(u1));
    for p in [0.5 - r, 0.5 + r] {
        if (u0..=u1).contains(&p) {
            m = m.max(s2(p));
        }
    }
    m
}

/// The stop ramp T_s (s) for a plan whose largest joint |q′|, |q″|, |q‴|
/// are `v`, `a`, `j`, run at σ up to `cap` (≥ 1), so that every transition
/// from a constant σ keeps the joint jerk within max(`jerk_limit`,
/// j·cap³ + `jerk_limit`/2). At least 50 ms.
pub fn stop_time(v: f64, a: f64, j: f64, jerk_limit: f64, cap: f64) -> f64 {
    let cap = if cap.is_finite() { cap.max(1.0) } else { 1.0 };
    let jc = j * cap * cap * cap;
    let budget = jerk_limit.max(jc + 0.5 * jerk_limit).max(1e-9);
    let mut t = MIN_RAMP_S;
    for i in 0..DS_CELLS {
        let d0 = cap * i as f64 / DS_CELLS as f64;
        let d1 = cap * (i + 1) as f64 / DS_CELLS as f64;
        // |σ̇|·T ≤ S'·m1, |σ̈|·T² ≤ |S''|·m2 (m1 grows with Δσ, m2 falls).
        let m1 = RHO_SLACK * libm::sqrt(d1).min(1.0);
        let m2 = RHO_SLACK * if d0 > 1.0 { 1.0 / d0 } else { 1.0 };
        for k in 0..U_CELLS {
            let u0 = k as f64 / U_CELLS as f64;
            let u1 = (k + 1) as f64 / U_CELLS as f64;
            // σ is largest at the cell's smallest Δσ and S.
            let sigma = cap - d0 * s(u0);
            let fixed = j * sigma * sigma * sigma;
            let b = 3.0 * a * sigma * s1_max(u0, u1) * m1;
            let c = v * s2_max(u0, u1) * m2;
            // fixed + b/T + c/T² ≤ budget (fixed < budget: σ ≤ cap).
            let room = (budget - fixed).max(1e-12);
            let cell = (b + libm::sqrt(b * b + 4.0 * room * c)) / (2.0 * room);
            t = t.max(cell);
        }
    }
    t
}

/// The stop ramp by the bound that takes every peak at once: the joint
/// jerk j·cap³ + 3a·cap·1.875/T + v·5.774/T² within the same budget (the
/// rule before [`stop_time`]; kept to report the difference).
pub fn stop_time_separate_peaks(v: f64, a: f64, j: f64, jerk_limit: f64, cap: f64) -> f64 {
    let cap = if cap.is_finite() { cap.max(1.0) } else { 1.0 };
    let jc = j * cap * cap * cap;
    let budget = (jerk_limit - jc).max(0.5 * jerk_limit).max(1e-9);
    let b = 3.0 * SMOOTHSTEP_MAX_D1 * a * cap;
    let c = SMOOTHSTEP_MAX_D2 * v;
    let t = (b + libm::sqrt(b * b + 4.0 * budget * c)) / (2.0 * budget);
    t.max(MIN_RAMP_S)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The largest F over the transitions a drive may run from a constant
    /// σ at ramp `t`, sampled densely, each with the shortest ρ the drive
    /// accepts (√Δσ below 1, else Δσ).
    fn worst_jerk(v: f64, a: f64, j: f64, cap: f64, t: f64) -> f64 {
        let mut worst = 0.0f64;
        for i in 1..=400 {
            let ds = cap * i as f64 / 400.0;
            // The drive's ρ: the smallest of its candidates, at most this.
            let rho = if ds >= 1.0 { ds } else { libm::sqrt(ds) };
            let tt = t * rho;
            for k in 0..=2000 {
                let u = k as f64 / 2000.0;
                let sigma = cap - ds * s(u);
                let sd = ds * s1(u) / tt;
                let sdd = ds * s2(u) / (tt * tt);
                worst = worst.max(j * sigma.powi(3) + 3.0 * a * sigma * sd + v * sdd);
            }
        }
        worst
    }

    #[test]
    fn ramp_keeps_every_transition_within_the_budget_and_is_tight() {
        for (v, a, j, lim, cap) in [
            (0.5, 1.2, 5.0, 5.0, 1.0),
            (0.2, 0.8, 1.5, 5.0, 1.0),
            (0.3, 0.77, 2.5, 5.0, 1.248),
            (0.05, 0.1, 0.2, 5.0, 4.0),
            (0.5, 1.2, 0.0, 15.0, 1.0),
        ] {
            let t = stop_time(v, a, j, lim, cap);
            let budget = lim.max(j * cap.powi(3) + 0.5 * lim);
            let w = worst_jerk(v, a, j, cap, t);
            assert!(
                w <= budget * (1.0 + 1e-9),
                "{v} {a} {j} {cap}: {w} > {budget}"
            );
            if t > MIN_RAMP_S {
                let w = worst_jerk(v, a, j, cap, 0.97 * t);
                assert!(w > budget, "{v} {a} {j} {cap}: not tight ({w} ≤ {budget})");
            }
            // Never longer than taking every peak at once.
            assert!(t <= stop_time_separate_peaks(v, a, j, lim, cap) * (1.0 + 1e-12));
        }
    }

    #[test]
    fn full_jerk_move_stops_in_about_half_the_time() {
        let new = stop_time(0.5, 1.2, 5.0, 5.0, 1.0);
        let old = stop_time_separate_peaks(0.5, 1.2, 5.0, 5.0, 1.0);
        assert!((old - 3.08).abs() < 0.01, "{old}");
        assert!(new < 0.7 * old, "{new} vs {old}");
    }

    #[test]
    fn bad_numbers_give_a_finite_ramp() {
        for cap in [f64::NAN, 0.0, -1.0, f64::INFINITY] {
            let t = stop_time(0.5, 1.2, 5.0, 5.0, cap);
            assert!(t.is_finite() && t >= MIN_RAMP_S);
        }
    }

    #[test]
    fn smoothstep_peaks_are_its_derivatives_maxima() {
        let mut m = (0.0f64, 0.0f64);
        for k in 0..=100_000 {
            let u = k as f64 / 100_000.0;
            m = (m.0.max(s1(u)), m.1.max(s2(u)));
        }
        assert!((m.0 - SMOOTHSTEP_MAX_D1).abs() < 1e-9);
        assert!((m.1 - SMOOTHSTEP_MAX_D2).abs() < 1e-6);
        assert!((s(1.0) - 1.0).abs() < 1e-15);
    }
}
