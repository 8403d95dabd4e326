//! The enable check: for a short window after the power stage comes on
//! (the brake releases), does the axis move the way it is told? Gravity
//! pulls the axis down and the loop answers with torque; the check fits
//! the measured travel to the model's response, d(t) = G·∬τ − G·b·t²/2
//! (from rest, G the acceleration per motor torque, b the constant load
//! torque), by least squares over the window, and compares G with the
//! model's 1 / (J·2π/p) (J the axis's inertia at the motor). A reversed
//! motor or encoder gives G < 0, a wrong encoder scale G off by that
//! scale. An axis that barely moves (no gravity load, held by friction)
//! gives no verdict: it stays unverified.

use triquint_shared::Model;

/// Length of the check (control ticks at 1 kHz: 80 ms).
pub const WINDOW_S: f32 = 0.080;
/// The measured gain may differ from the model's by this factor either way
/// (the platform's coupling between the axes, friction, the plant's mass).
pub const GAIN_FACTOR: f32 = 4.0;
/// Smallest measured travel (m, in the drive's own scale) that allows a
/// verdict: below it the axis did not move enough to tell.
pub const MIN_TRAVEL_M: f32 = 5.0e-6;
/// The window begins at the axis's first motion (its first count): the
/// platform is free only once every axis's brake is off, so a drive
/// enabled before its peers sees its axis held first. Longest wait for
/// that first motion (s): beyond it, no verdict.
pub const START_TIMEOUT_S: f32 = 0.5;

/// The check's verdict.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Verdict {
    /// The axis moves as the model says.
    Pass,
    /// It accelerates against its torque.
    WrongDirection,
    /// Right sign, gain outside [1/GAIN_FACTOR, GAIN_FACTOR] × the model's.
    WrongScale,
    /// It did not move enough to tell.
    Inconclusive,
}

/// The check in progress: the running sums of the least-squares fit.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnableCheck {
    ticks: u32,
    window: u32,
    /// Ticks waited for the first motion.
    waited: u32,
    /// The first measurement while held (`None` before the first tick).
    rest: Option<f32>,
    q0: f32,
    /// ∫τ dt and ∬τ dt² of the acting torque (N·m·s, N·m·s²).
    tau_int: f32,
    tau_int2: f32,
    /// The torques commanded one and two ticks ago: a command acts from
    /// the next tick on, for one tick (as the feedforward's look-ahead
    /// assumes), so the one of two ticks ago acted over the tick just past.
    pending: f32,
    acting: f32,
    s11: f32,
    s12: f32,
    s22: f32,
    s1d: f32,
    s2d: f32,
    max_travel: f32,
}

/// What the model expects of the axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Expected {
    /// Joint acceleration per motor torque (m/s² per N·m).
    pub gain: f32,
    /// The motor torque that holds the axis against gravity (N·m).
    pub load: f32,
}

impl Expected {
    /// From the model, for the axis's share: the rotor through the screw
    /// plus its slider, half its strut and a third of the platform.
    pub fn of(m: &Model<f32>) -> Self {
        let mass = m.slider_mass + 0.5 * m.strut_mass + m.platform_mass / 3.0;
        let j = m.rotor_inertia * m.ratio + mass * m.inv_ratio;
        Self {
            gain: if j > 0.0 { 1.0 / j } else { 0.0 },
            load: mass * m.gravity * m.inv_ratio,
        }
    }
}

impl EnableCheck {
    /// A check with control period `dt` (s), from its first measurement on.
    pub fn new(dt: f32) -> Self {
        let window = if dt > 0.0 { (WINDOW_S / dt) as u32 } else { 0 };
        Self {
            window: window.max(1),
            ..Self::default()
        }
    }

    /// One tick: measured position `q` (m), the torque commanded now
    /// (N·m, before the motor's direction), period `dt` (s). The verdict
    /// once the window is over.
    pub fn step(&mut self, q: f32, torque: f32, dt: f32, model: &Expected) -> Option<Verdict> {
        // The window starts at the last tick at rest before the first
        // motion: there, from rest, no torque has acted yet (a held axis
        // has no error, so the loop commands none).
        if self.ticks == 0 {
            let q_rest = *self.rest.get_or_insert(q);
            if q == q_rest {
                self.waited += 1;
                return (self.waited as f32 * dt > START_TIMEOUT_S)
                    .then_some(Verdict::Inconclusive);
            }
            self.q0 = q_rest;
            self.ticks = 1;
        }
        let t = self.ticks as f32 * dt;
        self.ticks += 1;
        if self.ticks > 1 {
            self.tau_int2 += (self.tau_int + 0.5 * self.acting * dt) * dt;
            self.tau_int += self.acting * dt;
        }
        self.acting = self.pending;
        self.pending = torque;
        let d = q - self.q0;
        let (f1, f2) = (self.tau_int2, -0.5 * t * t);
        self.s11 += f1 * f1;
        self.s12 += f1 * f2;
        self.s22 += f2 * f2;
        self.s1d += f1 * d;
        self.s2d += f2 * d;
        self.max_travel = self.max_travel.max(d.abs());
        (self.ticks >= self.window).then(|| self.verdict(model))
    }

    /// The fit's (G, G·b); None when it is singular.
    fn fit(&self) -> Option<(f32, f32)> {
        let det = self.s11 * self.s22 - self.s12 * self.s12;
        if det.abs() <= f32::EPSILON * self.s11 * self.s22 || det == 0.0 {
            return None;
        }
        let g = (self.s1d * self.s22 - self.s2d * self.s12) / det;
        let gb = (self.s11 * self.s2d - self.s12 * self.s1d) / det;
        Some((g, gb))
    }

    /// The fitted gain G (m/s² per N·m); 0 when the fit is singular.
    pub fn gain(&self) -> f32 {
        self.fit().map_or(0.0, |f| f.0)
    }

    /// The fitted load torque b (N·m, in the drive's torque sign): the
    /// torque that holds the axis still. The encoder's scale cancels in
    /// it (G and G·b both carry it). None when the fit is singular.
    pub fn load(&self) -> Option<f32> {
        self.fit().and_then(|(g, gb)| (g != 0.0).then(|| gb / g))
    }

    fn verdict(&self, model: &Expected) -> Verdict {
        let model_gain = model.gain;
        let g = self.gain();
        // Holding against gravity takes a lifting (positive) torque: a
        // load of the other sign is an axis whose up is the drive's down
        // (direction and encoder both flipped: the loop is sound, the
        // motion mirrored).
        let load_reversed = self
            .load()
            .is_some_and(|b| b * model.load < -0.25 * model.load * model.load);
        if self.max_travel < MIN_TRAVEL_M || model_gain <= 0.0 {
            Verdict::Inconclusive
        } else if g <= 0.0 || load_reversed {
            Verdict::WrongDirection
        } else if g * GAIN_FACTOR < model_gain || g > model_gain * GAIN_FACTOR {
            Verdict::WrongScale
        } else {
            Verdict::Pass
        }
    }
}
