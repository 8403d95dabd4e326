//! Field-oriented current control of the three-phase motor: Clarke and Park
//! transforms, a PI loop on the d and q currents, inverse Park and
//! space-vector modulation (min/max zero-sequence injection). Runs in the
//! PWM-synchronous interrupt at 20 kHz, highest priority.

use core::f32::consts::{FRAC_1_SQRT_2, FRAC_2_PI, FRAC_PI_2};

const INV_SQRT3: f32 = 0.577_350_27;
const SQRT3_2: f32 = 0.866_025_4;

/// α, β from the phase currents a, b (a + b + c = 0).
#[inline]
pub fn clarke(ia: f32, ib: f32) -> (f32, f32) {
    (ia, (ia + 2.0 * ib) * INV_SQRT3)
}

/// (sin θ, cos θ) in single precision only: libm's `sinf`/`cosf` work in
/// f64, which the Cortex-M4F does in software. Quadrant reduction and Taylor
/// polynomials on |x| ≤ π/4; error below 1e-6 for |θ| ≤ 2π.
#[inline]
pub fn sin_cos(theta: f32) -> (f32, f32) {
    let q = libm::roundf(theta * FRAC_2_PI);
    let x = theta - q * FRAC_PI_2;
    let x2 = x * x;
    let s = x * (1.0 - x2 / 6.0 * (1.0 - x2 / 20.0 * (1.0 - x2 / 42.0 * (1.0 - x2 / 72.0))));
    let c = 1.0 - x2 / 2.0 * (1.0 - x2 / 12.0 * (1.0 - x2 / 30.0 * (1.0 - x2 / 56.0)));
    match (q as i32) & 3 {
        0 => (s, c),
        1 => (c, -s),
        2 => (-s, -c),
        _ => (-c, s),
    }
}

/// d, q from α, β at electrical angle (sin θ, cos θ).
#[inline]
pub fn park(alpha: f32, beta: f32, sin: f32, cos: f32) -> (f32, f32) {
    (alpha * cos + beta * sin, beta * cos - alpha * sin)
}

/// α, β from d, q.
#[inline]
pub fn inverse_park(d: f32, q: f32, sin: f32, cos: f32) -> (f32, f32) {
    (d * cos - q * sin, d * sin + q * cos)
}

/// Duty cycles 0..1 of the three half-bridges for a voltage vector (α, β) as a
/// fraction of the bus voltage; the vector is limited to the inscribed circle.
#[inline]
pub fn svpwm(alpha: f32, beta: f32) -> [f32; 3] {
    let mag2 = alpha * alpha + beta * beta;
    let (alpha, beta) = if mag2 > INV_SQRT3 * INV_SQRT3 {
        let k = INV_SQRT3 / libm::sqrtf(mag2);
        (alpha * k, beta * k)
    } else {
        (alpha, beta)
    };
    let va = alpha;
    let vb = -0.5 * alpha + SQRT3_2 * beta;
    let vc = -0.5 * alpha - SQRT3_2 * beta;
    let offset = 0.5 - 0.5 * (va.max(vb).max(vc) + va.min(vb).min(vc));
    [va + offset, vb + offset, vc + offset]
}

/// PI controller with clamping anti-windup (output in bus-voltage fractions).
#[derive(Clone, Copy, Debug, Default)]
pub struct Pi {
    pub kp: f32,
    pub ki_dt: f32,
    pub integral: f32,
}

impl Pi {
    #[inline]
    pub fn step(&mut self, error: f32, limit: f32) -> f32 {
        let u = self.kp * error + self.integral;
        // Integrate only while not saturated in the same direction.
        if u.abs() < limit || u * error < 0.0 {
            self.integral += self.ki_dt * error;
        }
        u.max(-limit).min(limit)
    }
}

/// The current loop: Iq follows the reference, Id is held at 0.
#[derive(Clone, Copy, Debug, Default)]
pub struct CurrentLoop {
    pub d: Pi,
    pub q: Pi,
}

impl CurrentLoop {
    /// Phase currents (A), electrical angle (rad), Iq reference (A) → duties.
    pub fn step(&mut self, ia: f32, ib: f32, theta_e: f32, iq_ref: f32) -> [f32; 3] {
        let (sin, cos) = sin_cos(theta_e);
        let (alpha, beta) = clarke(ia, ib);
        let (id, iq) = park(alpha, beta, sin, cos);
        // Each axis may use the whole circle alone; together ≤ 1/√3 after svpwm.
        let lim = FRAC_1_SQRT_2;
        let vd = self.d.step(-id, lim);
        let vq = self.q.step(iq_ref - iq, lim);
        let (va, vb) = inverse_park(vd, vq, sin, cos);
        svpwm(va, vb)
    }

    pub fn reset(&mut self) {
        self.d.integral = 0.0;
        self.q.integral = 0.0;
    }
}
