//! Along-path time-scaling: plan time s advances at rate σ(t).
//!
//! σ is either constant (σ = k: 1 nominal, 0 at rest, k a feed override) or
//! in a transition from its value, rate and acceleration at the instant a
//! command applies (σ₀, σ̇₀, σ̈₀) to a new constant k. A transition is the
//! quintic σ(u) = Σ cᵢuⁱ, u = (t − t₀)/T, with σ(0), σ'(0), σ''(0) those of
//! the curve it leaves and σ(1) = k, σ'(1) = σ''(1) = 0: value, first and
//! second derivative of σ (and so position, velocity and acceleration of the
//! reference) are continuous at every change, also in the middle of another
//! transition. From σ = 1 at rest rates to k = 0 it is the smoothstep
//! σ = 1 − S(u), S = 10u³ − 15u⁴ + 6u⁵, over the configured stop time.
//! A stop along the path (a ramp sized for the path it passes through,
//! [`TimeScaling::begin_path_stop`]) from a constant σ₀ has σ̈ bang-bang
//! instead, σ = σ₀(1 − S(u)) with S = 2u² up to u = ½ and 1 − 2(1 − u)²
//! after: σ and σ̇ are continuous, σ̈ steps (docs/protocol.md, "The shape
//! of a stop along the path").
//!
//! Everything is closed form from the anchor (t₀, s₀): every node computes
//! the same s from the same host time with no drift. The plan time of a
//! constant phase is integer (ns); only a transition's distance is f32
//! (≤ T·max σ; its rounding stays below 1 µs of plan time for T ≤ 2 s,
//! under 1 µm of path at 1 m/s).

use crate::f32_cast::{to_f32, to_i64};

/// Phase of the time-scaling.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// σ = k > 0 constant (k = 1 nominal, else an override).
    Nominal,
    /// A transition toward σ = 0 (hold or stop).
    Decel,
    /// σ = 0.
    Rest,
    /// A transition toward σ = k > 0 (resume or override change).
    Accel,
}

/// Plan time and σ with its first two time derivatives at one instant.
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

/// σ = 1 in the fixed-point unit of a constant rate (1/65 536).
pub const UNIT_Q16: u32 = 1 << 16;

/// A rate in per mille (the wire's override and cap) in [`UNIT_Q16`],
/// rounded to nearest.
pub const fn q16_from_permille(pm: u32) -> u32 {
    (pm * UNIT_Q16 + 500) / 1000
}

/// Peak |σ'| of the smoothstep (15/8) and peak |σ''| (10/√3).
const PEAK_D1: f32 = 1.875;
const PEAK_D2: f32 = 5.773_503;
/// Transition durations tried, relative to the one from rest (shortest first).
const CANDIDATES: [f32; 9] = [0.2, 0.3, 0.45, 0.65, 1.0, 1.4, 2.0, 2.8, 4.0];

/// A [`TimeScaling::retarget`] the receive side ran ahead of the tick, on a
/// copy of the time-scaling the tick published (`inbox::TickSnapshot`).
///
/// Why there: from a constant σ a transition is sized in closed form, but
/// in the middle of another one the sampled search costs more than twice
/// the tick's whole instruction budget, while the receive side already
/// spends several times that on a segment. Deferring or
/// spreading the search over ticks would have to date the new transition
/// later, identically on every node; here nothing moves: the tick adopts
/// the result only if its state and the command's instant, target and ramp
/// are exactly those it was computed from, so it is bit for bit what the
/// tick would have computed (same inputs, same code). Otherwise (another
/// command or a stop in between, a fault of the drive itself) the tick
/// computes it, correct but over the budget in that rare tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Retarget {
    pub from: TimeScaling,
    pub t_ns: i64,
    pub target_q16: u32,
    pub full_ns: i64,
    pub to: TimeScaling,
}

impl Retarget {
    /// `from.retarget(t_ns, target_q16, full_ns)` ahead of time; `None` at a
    /// constant σ (closed form, cheap in the tick).
    // Never inlined: the receive side's, never the tick's code.
    #[inline(never)]
    pub fn prepare(from: &TimeScaling, t_ns: i64, target_q16: u32, full_ns: i64) -> Option<Self> {
        if !from.in_transition() {
            return None;
        }
        let mut to = *from;
        to.retarget(t_ns, target_q16, full_ns);
        Some(Self {
            from: *from,
            t_ns,
            target_q16,
            full_ns,
            to,
        })
    }
}

/// Time-scaling state, anchored at host time t₀ and plan time s₀.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeScaling {
    pub phase: Phase,
    pub t0_ns: i64,
    pub s0_ns: i64,
    /// Transition duration T (ns).
    pub ramp_ns: i64,
    /// The nominal ramp the transition was sized against (ns).
    full_ns: i64,
    /// σ(u) = Σ cᵢuⁱ during a transition.
    c: [f32; 6],
    /// σ of the constant phase, or that a transition ends at (1/65 536).
    target_q16: u32,
    /// A retarget deferred to the end of the running transition (target,
    /// nominal ramp): one that would have run σ below 0 from here.
    pending: Option<(u32, i64)>,
    /// The transition is a stop along the path: σ = σ₀(1 − S(u)) with σ̈
    /// bang-bang (σ₀ = c₀), not the quintic.
    bang: bool,
}

impl TimeScaling {
    /// σ = 1 from host time `t0_ns`, plan time `s0_ns`.
    pub const fn nominal(t0_ns: i64, s0_ns: i64) -> Self {
        Self::constant(t0_ns, s0_ns, UNIT_Q16)
    }

    /// σ = `q16`/65 536 from host time `t0_ns`, plan time `s0_ns` (at rest if 0).
    pub const fn constant(t0_ns: i64, s0_ns: i64, q16: u32) -> Self {
        Self {
            phase: if q16 == 0 {
                Phase::Rest
            } else {
                Phase::Nominal
            },
            t0_ns,
            s0_ns,
            ramp_ns: 1,
            full_ns: 1,
            c: [0.0; 6],
            target_q16: q16,
            pending: None,
            bang: false,
        }
    }

    /// σ the scaling is at or heading to (1/65 536).
    pub fn target_q16(&self) -> u32 {
        self.target_q16
    }

    /// In a transition (Decel or Accel)?
    pub fn in_transition(&self) -> bool {
        matches!(self.phase, Phase::Decel | Phase::Accel)
    }

    /// Evaluates at host time `t_ns`, advancing a transition that ended.
    pub fn at(&mut self, t_ns: i64) -> Scaled {
        self.advance::<true>(t_ns)
    }

    /// [`TimeScaling::at`]; a change deferred to the end of a transition
    /// that ended is made only with `PENDING` (which makes it, then
    /// evaluates without): no call cycle, so the ELF's stack bound holds.
    #[inline(always)]
    fn advance<const PENDING: bool>(&mut self, t_ns: i64) -> Scaled {
        let dt = t_ns - self.t0_ns;
        if self.in_transition() {
            let ramp = self.ramp_ns.max(1);
            if dt < ramp {
                return self.transition(dt.max(0), ramp);
            }
            // Ended: constant from its end on (the end's plan time by the
            // same arithmetic as the transition's last instants).
            self.s0_ns = self.transition(ramp, ramp).s_ns;
            self.t0_ns += ramp;
            self.phase = if self.target_q16 == 0 {
                Phase::Rest
            } else {
                Phase::Nominal
            };
            if PENDING && let Some((k, full)) = self.pending.take() {
                return self.deferred(t_ns, k, full);
            }
            return self.constant_at(t_ns - self.t0_ns);
        }
        self.constant_at(dt)
    }

    /// The change deferred to the end of the transition that just ended,
    /// begun from the constant state there, evaluated at `t_ns`: from a
    /// constant state a change is never deferred again.
    #[cold]
    #[inline(never)]
    fn deferred(&mut self, t_ns: i64, k: u32, full_ns: i64) -> Scaled {
        let t0 = self.t0_ns;
        let now = self.constant_at(0);
        self.retarget_from(now, t0, k, full_ns, false);
        self.advance::<false>(t_ns)
    }

    /// [`TimeScaling::at`] where it changes nothing: `None` when a
    /// transition ends by `t_ns` (so a look-ahead need not copy the scaling).
    pub fn peek(&self, t_ns: i64) -> Option<Scaled> {
        let dt = t_ns - self.t0_ns;
        if self.in_transition() {
            let ramp = self.ramp_ns.max(1);
            return (dt < ramp).then(|| self.transition(dt.max(0), ramp));
        }
        Some(self.constant_at(dt))
    }

    /// Plan time (ns) at host time `t_ns`, for a constant phase only (not
    /// advanced past a transition's end: the caller knows there is none).
    pub fn constant_plan_time_ns(&self, t_ns: i64) -> i64 {
        self.constant_at(t_ns - self.t0_ns).s_ns
    }

    /// The host time (ns) at which a constant σ above 0 reaches plan time
    /// `s_ns`; None in a transition, at rest, or before its start.
    pub fn constant_host_time_ns(&self, s_ns: i64) -> Option<i64> {
        let ds = s_ns - self.s0_ns;
        if self.in_transition() || ds < 0 {
            return None;
        }
        match self.target_q16 {
            0 => None,
            UNIT_Q16 => Some(self.t0_ns + ds),
            // checked: no panic path on the receive side.
            k => ds
                .saturating_mul(UNIT_Q16 as i64)
                .checked_div(k as i64)
                .map(|d| self.t0_ns + d),
        }
    }

    fn constant_at(&self, dt: i64) -> Scaled {
        let dt = dt.max(0);
        let (s_ns, sigma) = match self.target_q16 {
            UNIT_Q16 => (self.s0_ns + dt, 1.0),
            0 => (self.s0_ns, 0.0),
            k => (
                self.s0_ns + (dt.saturating_mul(k as i64) >> 16),
                k as f32 * (1.0 / UNIT_Q16 as f32),
            ),
        };
        Scaled {
            s_ns,
            sigma,
            sigma_d: 0.0,
            sigma_dd: 0.0,
        }
    }

    fn transition(&self, dt: i64, ramp: i64) -> Scaled {
        let t = to_f32(ramp);
        let u = to_f32(dt) / t;
        if self.bang {
            return self.bang_at(u, t);
        }
        let c = &self.c;
        let sigma = c[0] + u * (c[1] + u * (c[2] + u * (c[3] + u * (c[4] + u * c[5]))));
        let d1 = c[1] + u * (2.0 * c[2] + u * (3.0 * c[3] + u * (4.0 * c[4] + u * 5.0 * c[5])));
        let d2 = 2.0 * c[2] + u * (6.0 * c[3] + u * (12.0 * c[4] + u * 20.0 * c[5]));
        let integral = u
            * (c[0]
                + u * (c[1] * 0.5
                    + u * (c[2] * (1.0 / 3.0)
                        + u * (c[3] * 0.25 + u * (c[4] * 0.2 + u * c[5] * (1.0 / 6.0))))));
        let inv_t = 1e9 / t;
        Scaled {
            s_ns: self.s0_ns + to_i64(t * integral),
            sigma,
            sigma_d: d1 * inv_t,
            sigma_dd: d2 * inv_t * inv_t,
        }
    }

    /// A stop along the path at u of its length `t` (ns): σ = σ₀(1 − S),
    /// S = 2u² up to u = ½, then 1 − 2(1 − u)² (S′ = 4u or 4(1 − u), S″ =
    /// ±4), the plan time it covers σ₀·t·(u − ∫S).
    // Out of line: only the ticks of such a stop run it.
    #[inline(never)]
    fn bang_at(&self, u: f32, t: f32) -> Scaled {
        let s0 = self.c[0];
        let (s, d1, d2, int_s) = if u < 0.5 {
            (2.0 * u * u, 4.0 * u, 4.0, (2.0 / 3.0) * u * u * u)
        } else {
            let w = 1.0 - u;
            (
                1.0 - 2.0 * w * w,
                4.0 * w,
                -4.0,
                u - 0.5 + (2.0 / 3.0) * w * w * w,
            )
        };
        let inv_t = 1e9 / t;
        Scaled {
            s_ns: self.s0_ns + to_i64(t * s0 * (u - int_s)),
            sigma: s0 * (1.0 - s),
            sigma_d: -s0 * d1 * inv_t,
            sigma_dd: -s0 * d2 * inv_t * inv_t,
        }
    }

    /// From host time `t_ns` on, move σ to `target_q16`/65 536 with the
    /// continuity above. The transition's duration is the shortest of a few
    /// candidates (around the one a move from rest over a nominal ramp of
    /// `full_ns` would take) whose |σ̇| and |σ̈| stay within the
    /// nominal ramp's peaks (1.875/T, 5.77/T²) and that does not cross the
    /// target; if none does (a ramp already at its peak acceleration), the
    /// one with the smallest peaks, σ outside its range counted against them.
    /// Peaks and range are sampled at six points of each candidate. One
    /// that would run σ below 0 (a resume late in a hold ramp) is deferred
    /// to the end of the running transition instead. Already at or heading to the target: no
    /// change, unless `full_ns` is shorter than the running transition's
    /// (a quick stop during a stop).
    pub fn retarget(&mut self, t_ns: i64, target_q16: u32, full_ns: i64) {
        self.retarget_shaped(t_ns, target_q16, full_ns, false);
    }

    /// [`TimeScaling::retarget`]; a stop (`target_q16` 0) from a constant σ
    /// with `bang` is σ̈ bang-bang rather than the quintic (a stop along
    /// the path, sized for that shape).
    fn retarget_shaped(&mut self, t_ns: i64, target_q16: u32, full_ns: i64, bang: bool) {
        let t_ns = t_ns.max(self.t0_ns);
        let now = self.at(t_ns);
        self.retarget_from(now, t_ns, target_q16, full_ns, bang);
    }

    /// [`TimeScaling::retarget_shaped`] from `now`, the scaling at `t_ns`
    /// (at or after the start of its current phase).
    fn retarget_from(&mut self, now: Scaled, t_ns: i64, target_q16: u32, full_ns: i64, bang: bool) {
        self.pending = None;
        let full_ns = full_ns.max(1);
        if target_q16 == self.target_q16 && !(self.in_transition() && full_ns < self.full_ns) {
            return;
        }
        let k = target_q16 as f32 * (1.0 / UNIT_Q16 as f32);
        if !self.in_transition() && now.sigma == k {
            *self = Self::constant(t_ns, now.s_ns, target_q16);
            return;
        }
        let (s0, v0, a0) = (now.sigma, now.sigma_d, now.sigma_dd);
        let tf = to_f32(full_ns) * 1e-9;
        let ad = (k - s0).abs();
        // √1 = 1: a hold from or a resume to full speed needs no root.
        let base = if ad >= 1.0 { ad } else { sqrt(ad) }.max(0.2);
        let mut chosen = None;
        if v0 == 0.0 && a0 == 0.0 {
            // From a constant σ the transition is σ = k + e₀(1 − S(u)),
            // monotone, never crossing k, with exact peaks 1.875|e₀|/T and
            // 5.77|e₀|/T²: the shortest candidate within them, in closed form
            // (this runs in the tick that takes the command, and the
            // sampled search would take it over its budget).
            for f in CANDIDATES {
                let rho = base * f;
                if ad <= 1.0001 * rho && ad <= 1.0001 * rho * rho {
                    chosen = Some(rho);
                    break;
                }
            }
        }
        let prev = self.target_q16 as f32 * (1.0 / UNIT_Q16 as f32);
        let rho = match chosen {
            Some(rho) => rho,
            None => sampled_rho(s0, v0, a0, k, prev, tf, base),
        };
        let ramp_ns = if rho == 1.0 {
            full_ns
        } else {
            to_i64(to_f32(full_ns) * rho).max(1)
        };
        let q = quintic(s0, v0, a0, k, to_f32(ramp_ns) * 1e-9);
        if k > 0.0 && self.in_transition() && (1..24).any(|i| poly3(&q, i as f32 / 24.0).0 < -1e-4)
        {
            // Reversing a ramp near its end (a resume late in a hold) would
            // run the path backwards: let the ramp end, then go on from rest.
            self.pending = Some((target_q16, full_ns));
            return;
        }
        self.c = q;
        self.bang = bang && target_q16 == 0 && chosen.is_some();
        self.phase = if target_q16 == 0 {
            Phase::Decel
        } else {
            Phase::Accel
        };
        self.t0_ns = t_ns;
        self.s0_ns = now.s_ns;
        self.ramp_ns = ramp_ns;
        self.full_ns = full_ns;
        self.target_q16 = target_q16;
    }

    /// [`TimeScaling::retarget`], or the result `ready` the receive side
    /// computed if it was computed from this very state and arguments.
    pub fn retarget_ready(
        &mut self,
        t_ns: i64,
        target_q16: u32,
        full_ns: i64,
        ready: Option<&Retarget>,
    ) {
        match ready {
            Some(r)
                if r.from == *self
                    && (r.t_ns, r.target_q16, r.full_ns) == (t_ns, target_q16, full_ns) =>
            {
                *self = r.to
            }
            _ => self.retarget(t_ns, target_q16, full_ns),
        }
    }

    /// Slow to rest from host time `t_ns` (hold, stop, fault).
    pub fn begin_decel(&mut self, t_ns: i64, ramp_ns: i64) {
        self.retarget(t_ns, 0, ramp_ns);
    }

    /// Slow to rest from host time `t_ns` along the path over a ramp
    /// `ramp_ns` sized for a stop with σ̈ bang-bang (`stop_ramp.rs`, the
    /// ramps for a stop from σ ≤ 1): that shape from a constant σ, the
    /// quintic from within a transition.
    pub fn begin_path_stop(&mut self, t_ns: i64, ramp_ns: i64) {
        self.retarget_shaped(t_ns, 0, ramp_ns, true);
    }

    /// Accelerate to σ = 1 from host time `t_ns`.
    pub fn begin_accel(&mut self, t_ns: i64, ramp_ns: i64) {
        self.retarget(t_ns, UNIT_Q16, ramp_ns);
    }

    /// Plan time still covered by a stop over a nominal ramp `ramp_ns` begun
    /// at constant σ ≤ max(1, `sigma_q16`/65 536) (ns): T·σ/2 with
    /// T = ramp·max(σ, √σ).
    pub fn stop_distance_ns(ramp_ns: i64, sigma_q16: u32) -> i64 {
        let k = sigma_q16.max(UNIT_Q16) as i64;
        // σ ≥ 1: T = ramp·σ, distance ramp·σ²/2 (no overflow below σ = 32).
        (ramp_ns.saturating_mul(k) >> 16).saturating_mul(k) >> 17
    }
}

/// The transition's length (relative to the nominal ramp `tf` s) by the
/// sampled search [`TimeScaling::retarget`] describes, from σ₀, σ̇₀, σ̈₀
/// (`s0`, `v0`, `a0`) to `k`, `prev` the target it had. Out of line: only a
/// change in the middle of another transition gets here.
#[inline(never)]
fn sampled_rho(s0: f32, v0: f32, a0: f32, k: f32, prev: f32, tf: f32, base: f32) -> f32 {
    let e0 = s0 - k;
    let mut best = (f32::INFINITY, base);
    let mut chosen = None;
    // σ stays between the values it has, had as a target and gets.
    let hi = s0.max(k).max(prev) + 1e-3;
    let lo = s0.min(k).min(prev).max(0.0) - 1e-3;
    let (vmax, amax) = (PEAK_D1 / tf, PEAK_D2 / (tf * tf));
    for f in CANDIDATES {
        let rho = base * f;
        let c = tf * rho;
        let inv = 1.0 / c;
        let q = quintic(s0, v0, a0, k, c);
        // Peaks of σ̇ and σ̈ and the range of σ, sampled.
        let (mut vp, mut ap) = (0.0f32, a0.abs());
        let (mut viol, mut back) = (0.0f32, 0.0f32);
        for u in [0.083_333_f32, 0.25, 0.416_667, 0.583_333, 0.75, 0.916_667] {
            let (x, d1, d2) = poly3(&q, u);
            vp = vp.max(d1.abs() * inv);
            ap = ap.max(d2.abs() * inv * inv);
            viol = viol.max(x - hi).max(lo - x);
            back = back.max(-x);
        }
        let r = (vp / vmax).max(ap / amax);
        // A hold or stop never runs σ below 0 (the path backwards).
        let side = k > 0.0 || keeps_side(e0, v0 * c, a0 * c * c);
        if side && viol <= 0.0 && r <= 1.0001 {
            chosen = Some(rho);
            break;
        }
        // Otherwise: trade the peaks against σ leaving its range
        // (1 % of σ outside counts as 40 % more σ̈), never crossing the target.
        let score = r.max(1.0) + 40.0 * viol + 1e3 * back + if side { 0.0 } else { 1e3 };
        if score < best.0 {
            best = (score, rho);
        }
    }
    chosen.unwrap_or(best.1)
}

/// σ(u) over a transition of `t` s from σ₀, σ̇₀, σ̈₀ to k at rest.
fn quintic(s0: f32, v0: f32, a0: f32, k: f32, t: f32) -> [f32; 6] {
    let c1 = v0 * t;
    let c2 = 0.5 * a0 * t * t;
    let d = k - (s0 + c1 + c2);
    let e1 = -(c1 + 2.0 * c2);
    let e2 = -2.0 * c2;
    [
        s0,
        c1,
        c2,
        10.0 * d - 4.0 * e1 + 0.5 * e2,
        -15.0 * d + 7.0 * e1 - e2,
        6.0 * d - 3.0 * e1 + 0.5 * e2,
    ]
}

/// σ, σ' and σ'' (per u) at `u`.
fn poly3(c: &[f32; 6], u: f32) -> (f32, f32, f32) {
    (
        c[0] + u * (c[1] + u * (c[2] + u * (c[3] + u * (c[4] + u * c[5])))),
        c[1] + u * (2.0 * c[2] + u * (3.0 * c[3] + u * (4.0 * c[4] + u * 5.0 * c[5]))),
        2.0 * c[2] + u * (6.0 * c[3] + u * (12.0 * c[4] + u * 20.0 * c[5])),
    )
}

/// Does (1 − u)³·b(u), b(u) = e + (3e + v)u + (6e + 3v + a/2)u², with
/// e = σ₀ − k, v = σ̇₀T, a = σ̈₀T², keep the sign of e on [0, 1] (σ − k of
/// a transition: it never crosses the target, so a hold never runs σ < 0)?
fn keeps_side(e: f32, v: f32, a: f32) -> bool {
    let sign = if e < 0.0 { -1.0 } else { 1.0 };
    let (b0, b1, b2) = (
        e * sign,
        (3.0 * e + v) * sign,
        (6.0 * e + 3.0 * v + 0.5 * a) * sign,
    );
    if b0 + b1 + b2 < 0.0 {
        return false;
    }
    // Interior minimum of a convex b.
    if b2 > 0.0 {
        let u = -b1 / (2.0 * b2);
        if u > 0.0 && u < 1.0 && b0 - b1 * b1 / (4.0 * b2) < 0.0 {
            return false;
        }
    }
    true
}

/// √x for x ≥ 0 without libm (Newton from a bit-level guess; a few
/// instructions, only when a command retargets).
fn sqrt(x: f32) -> f32 {
    if x <= 0.0 {
        return 0.0;
    }
    let mut y = f32::from_bits((x.to_bits() >> 1) + 0x1fbd_1df5);
    for _ in 0..3 {
        y = 0.5 * (y + x / y);
    }
    y
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use rand::{RngExt, SeedableRng};
    use rand_chacha::ChaCha8Rng;
    use std::{eprintln, format};

    const MS: i64 = 1_000_000;
    const TICK: i64 = 100_000;

    /// The host time a constant σ reaches a plan time is the inverse of
    /// the plan time it gives, to a nanosecond of plan time; none at rest,
    /// before the start, or in a transition.
    #[test]
    fn constant_host_time_inverts_constant_plan_time() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        for q16 in [UNIT_Q16, UNIT_Q16 / 2, 3 * UNIT_Q16 / 2, 977] {
            let sc = TimeScaling::constant(5 * MS, 2 * MS, q16);
            for _ in 0..200 {
                let t = 5 * MS + rng.random_range(0..10_000 * MS);
                let s = sc.constant_plan_time_ns(t);
                let back = sc.constant_host_time_ns(s).unwrap();
                assert!(
                    (sc.constant_plan_time_ns(back) - s).abs() <= 1,
                    "{q16}: {t} -> {s} -> {back}"
                );
            }
            assert_eq!(sc.constant_host_time_ns(MS), None);
        }
        assert_eq!(
            TimeScaling::constant(0, 0, 0).constant_host_time_ns(MS),
            None
        );
        let mut sc = TimeScaling::constant(0, 0, UNIT_Q16);
        sc.retarget(10 * MS, 0, 200 * MS);
        sc.at(20 * MS);
        assert_eq!(sc.constant_host_time_ns(30 * MS), None);
    }

    #[test]
    fn decel_from_nominal_is_the_smoothstep_and_rests_after_half_the_ramp() {
        let mut ts = TimeScaling::nominal(0, 0);
        let t = 1_000_000_000;
        ts.begin_decel(500 * MS, t);
        assert_eq!(ts.ramp_ns, t);
        let a = ts.at(500 * MS);
        assert_eq!(a.s_ns, 500 * MS);
        assert_eq!(a.sigma, 1.0);
        let b = ts.at(1000 * MS);
        assert!((b.sigma - 0.5).abs() < 1e-6);
        assert!((b.sigma_d + 1.875).abs() < 1e-4, "{}", b.sigma_d);
        let c = ts.at(1500 * MS + 1);
        assert_eq!(ts.phase, Phase::Rest);
        assert!((c.s_ns - 1000 * MS).abs() < 1000, "{}", c.s_ns);
        let mut ts = TimeScaling::nominal(0, 0);
        ts.begin_decel(0, t);
        let mut last = -1;
        for k in 0..=1000 {
            let s = ts.at(k * MS).s_ns;
            // Monotone and continuous within the f32 rounding (< 1 µs).
            assert!(s >= last - 1000, "tick {k}: {s} < {last}");
            assert!(s - last.max(0) <= MS + 1000);
            last = s;
        }
        assert!((last - 500 * MS).abs() < 1000);
    }

    #[test]
    fn accel_after_rest_returns_to_nominal() {
        let mut ts = TimeScaling::nominal(0, 0);
        ts.begin_decel(0, 400 * MS);
        ts.at(400 * MS + 1);
        ts.begin_accel(1000 * MS, 400 * MS);
        assert_eq!(ts.ramp_ns, 400 * MS);
        let mid = ts.at(1200 * MS);
        assert!((mid.sigma - 0.5).abs() < 1e-6);
        let end = ts.at(2000 * MS);
        assert_eq!(ts.phase, Phase::Nominal);
        // 200 ms (decel) + 200 ms (accel) of plan time + 600 ms at σ = 1.
        assert!((end.s_ns - 1000 * MS).abs() < 1000, "{}", end.s_ns);
    }

    #[test]
    fn override_runs_at_the_fraction_and_back() {
        let mut ts = TimeScaling::nominal(0, 0);
        ts.retarget(0, UNIT_Q16 / 2, 400 * MS);
        ts.at(2000 * MS);
        assert_eq!(ts.phase, Phase::Nominal);
        let a = ts.at(2000 * MS);
        let b = ts.at(3000 * MS);
        assert_eq!(b.sigma, 0.5);
        assert_eq!(b.s_ns - a.s_ns, 500 * MS);
        ts.retarget(3000 * MS, UNIT_Q16, 400 * MS);
        ts.at(5000 * MS);
        let c = ts.at(5000 * MS);
        let d = ts.at(6000 * MS);
        assert_eq!(d.s_ns - c.s_ns, 1000 * MS);
    }

    /// Runs `ts` at 10 kHz from `from` to `to`, checking σ, σ̇ and σ̈ against
    /// their numerical derivatives (continuity: no step anywhere), the plan
    /// time against ∫σ, and returns (peak |σ̇|, peak |σ̈|, min σ, max σ).
    fn run(ts: &mut TimeScaling, from: i64, to: i64, ctx: &str) -> (f32, f32, f32, f32) {
        run_with(ts, from, to, ctx, 20.0)
    }

    /// [`run`] with the largest change of σ̈ in one tick (a bound on σ⃛·dt).
    fn run_with(
        ts: &mut TimeScaling,
        from: i64,
        to: i64,
        ctx: &str,
        dd_step: f32,
    ) -> (f32, f32, f32, f32) {
        let dt = TICK as f32 * 1e-9;
        let mut prev = ts.at(from);
        let mut peaks = (0.0f32, 0.0f32, prev.sigma, prev.sigma);
        let mut t = from + TICK;
        while t <= to {
            let n = ts.at(t);
            let ctx = format!("{ctx} t {} ms", t / MS);
            // ds ≈ (σ + σ')/2·dt within rounding and the curvature.
            let ds = (n.s_ns - prev.s_ns) as f32 * 1e-9;
            let mean = 0.5 * (n.sigma + prev.sigma) * dt;
            // Plan time within its f32 rounding (< 1 µs; see the module doc).
            assert!(
                (ds - mean).abs() < 1e-6 + 0.02 * dt,
                "{ctx}: ds {ds:e} vs {mean:e}"
            );
            // σ moves by about σ̇·dt, σ̇ by about σ̈·dt: no steps.
            let dsig = n.sigma - prev.sigma;
            let md = 0.5 * (n.sigma_d + prev.sigma_d) * dt;
            assert!((dsig - md).abs() < 2e-4, "{ctx}: σ step {dsig} vs {md}");
            let dd = n.sigma_d - prev.sigma_d;
            let mdd = 0.5 * (n.sigma_dd + prev.sigma_dd) * dt;
            assert!((dd - mdd).abs() < 2e-2, "{ctx}: σ̇ step {dd} vs {mdd}");
            assert!(
                (n.sigma_dd - prev.sigma_dd).abs() < dd_step,
                "{ctx}: σ̈ step {} → {}",
                prev.sigma_dd,
                n.sigma_dd
            );
            peaks.0 = peaks.0.max(n.sigma_d.abs());
            peaks.1 = peaks.1.max(n.sigma_dd.abs());
            peaks.2 = peaks.2.min(n.sigma);
            peaks.3 = peaks.3.max(n.sigma);
            prev = n;
            t += TICK;
        }
        peaks
    }

    /// A stop along the path from a constant σ₀ (down to one a hundredth,
    /// where ρ is held at its least): σ and σ̇ continuous, |σ̇| at most
    /// 2σ₀/T and σ̈ ±4σ₀/T² (T the ramp with ρ), stepping only at the
    /// start, the middle and the end; at rest after σ₀·T/2 of plan time.
    /// A quick stop in its middle blends a quintic from where it is.
    #[test]
    fn a_path_stop_is_bang_bang_and_rests_after_half_its_ramp() {
        for k in [UNIT_Q16, UNIT_Q16 / 2, UNIT_Q16 / 100] {
            let s0 = k as f32 / UNIT_Q16 as f32;
            let mut ts = TimeScaling::constant(0, 0, k);
            ts.begin_path_stop(100 * MS, 1000 * MS);
            assert_eq!(ts.phase, Phase::Decel);
            let ramp = ts.ramp_ns;
            let t = ramp as f32 * 1e-9;
            let step = 8.0 * s0 / (t * t) * 1.01;
            let ctx = format!("σ₀ {s0}");
            let (vp, ap, lo, _) =
                run_with(&mut ts, 100 * MS, 100 * MS + ramp + 10 * MS, &ctx, step);
            assert!(vp <= 2.0 * s0 / t * 1.001, "{ctx}: σ̇ {vp}");
            assert!(
                (ap - 4.0 * s0 / (t * t)).abs() <= 1e-3 * ap,
                "{ctx}: σ̈ {ap}"
            );
            assert!(lo >= 0.0, "{ctx}: σ {lo}");
            assert_eq!(ts.phase, Phase::Rest, "{ctx}");
            let end = ts.at(100 * MS + ramp + 20 * MS).s_ns;
            let expected = (100 * MS) as f32 * s0 + 0.5 * s0 * ramp as f32;
            assert!(
                (end as f32 - expected).abs() < 2_000.0,
                "{ctx}: {end} vs {expected}"
            );
        }
        // A quick stop a third of the way in: from σ, σ̇, σ̈ as they are.
        let mut ts = TimeScaling::nominal(0, 0);
        ts.begin_path_stop(0, 1000 * MS);
        let before = ts.at(333 * MS);
        ts.retarget(333 * MS, 0, 300 * MS);
        let after = ts.at(333 * MS);
        assert_eq!((before.s_ns, before.sigma), (after.s_ns, after.sigma));
        assert!((before.sigma_d - after.sigma_d).abs() < 1e-4);
        assert!((before.sigma_dd - after.sigma_dd).abs() < 1e-3);
        let (_, _, lo, _) = run_with(&mut ts, 333 * MS, 2000 * MS, "quick", 1.0);
        assert!(lo >= -1e-3);
        assert_eq!(ts.phase, Phase::Rest);
    }

    /// Commands at random instants (seeded): hold during resume, resume
    /// during hold, override during hold, stop during an override change.
    /// σ reaches each target, stays within [−0.002, max of the targets +
    /// 0.05] (a hold late in a resume ramp overshoots 1 by up to 4.5 %), and
    /// |σ̇|, |σ̈| within the nominal ramp's peaks times the budget (1.0 from
    /// constant σ; 1.05 and 1.8 in the middle of a transition).
    #[test]
    fn any_target_from_any_state_at_random_instants() {
        let full = 400 * MS;
        let tf = 0.4f32;
        let (vmax, amax) = (PEAK_D1 / tf, PEAK_D2 / (tf * tf));
        let mut rng = ChaCha8Rng::seed_from_u64(21);
        let mut worst = (0.0f32, 0.0f32);
        let mut over = 0.0f32;
        let mut under = 0.0f32;
        let cases: [(&str, u32, u32); 4] = [
            ("hold during resume", UNIT_Q16, 0),
            ("resume during hold", 0, UNIT_Q16),
            ("override during hold", 0, UNIT_Q16 / 2),
            ("stop during override change", UNIT_Q16 / 2, 0),
        ];
        for (name, first, second) in cases {
            for trial in 0..200 {
                // Start from the state before the first command.
                let start = if first == 0 { UNIT_Q16 } else { 0 };
                let start = if name.starts_with("stop") {
                    UNIT_Q16
                } else {
                    start
                };
                let mut ts = TimeScaling::constant(0, 0, start);
                ts.retarget(10 * MS, first, full);
                let t1 = ts.ramp_ns;
                let at =
                    10 * MS + rng.random_range(0..=t1 / TICK) * TICK + rng.random_range(0..TICK);
                let ctx = format!("{name} trial {trial} at {} µs", (at - 10 * MS) / 1000);
                let p1 = run(&mut ts, 10 * MS, at - at % TICK, &ctx);
                let before = ts.at(at);
                ts.retarget(at, second, full);
                // Continuous at the command's instant: σ, σ̇, σ̈ and s.
                let after = ts.at(at);
                assert_eq!(before.s_ns, after.s_ns, "{ctx}");
                assert!((before.sigma - after.sigma).abs() < 1e-6, "{ctx}");
                assert!((before.sigma_d - after.sigma_d).abs() < 1e-4, "{ctx}");
                assert!((before.sigma_dd - after.sigma_dd).abs() < 1e-3, "{ctx}");
                let end = at + ts.ramp_ns + 2 * full;
                let p2 = run(&mut ts, at, end, &ctx);
                let k = second as f32 / UNIT_Q16 as f32;
                let fin = ts.at(end);
                assert!(!ts.in_transition(), "{ctx}: still in transition");
                assert_eq!(fin.sigma, k, "{ctx}");
                let hi = [first, second, start].iter().max().copied().unwrap_or(0) as f32
                    / UNIT_Q16 as f32;
                under = under.min(p2.2);
                over = over.max(p2.3 - hi);
                assert!(p2.3 <= hi + 0.05, "{ctx}: σ {} > {hi}", p2.3);
                assert!(p2.2 >= -0.002, "{ctx}: σ {} < 0", p2.2);
                assert!(
                    p1.0 <= vmax * 1.001 && p1.1 <= amax * 1.001,
                    "{ctx}: first {p1:?}"
                );
                let (rv, ra) = (p2.0 / vmax, p2.1 / amax);
                assert!(rv <= 1.05 && ra <= 1.8, "{ctx}: σ̇ ×{rv}, σ̈ ×{ra}");
                worst = (worst.0.max(rv), worst.1.max(ra));
            }
        }
        eprintln!(
            "worst mid-transition |σ̇|, |σ̈| over the nominal ramp's peaks: {worst:?}; σ above the targets by {over}, min σ {under}"
        );
    }

    #[test]
    fn repeated_and_quick_commands() {
        // A hold repeated during its ramp changes nothing.
        let mut a = TimeScaling::nominal(0, 0);
        a.begin_decel(0, 400 * MS);
        let b = a;
        a.begin_decel(100 * MS, 400 * MS);
        assert_eq!(a.ramp_ns, b.ramp_ns);
        assert_eq!(a.t0_ns, b.t0_ns);
        // A quick stop during a stop re-plans shorter, continuously.
        let before = a.at(150 * MS);
        a.retarget(150 * MS, 0, 100 * MS);
        let after = a.at(150 * MS);
        assert_eq!(before.s_ns, after.s_ns);
        assert_eq!(before.sigma, after.sigma);
        assert!((before.sigma_dd - after.sigma_dd).abs() < 1e-3);
        // 100 ms ramp: σ⃛ up to ~60/T³ = 6e4/s³, 6 per tick.
        let (_, _, lo, _) = run_with(&mut a, 150 * MS, 600 * MS, "quick", 8.0);
        assert!(lo >= -1e-4);
        assert_eq!(a.phase, Phase::Rest);
        assert!(a.t0_ns < 400 * MS, "quick stop ended at {}", a.t0_ns);
        // A command dated before the phase began applies at its start.
        let mut c = TimeScaling::nominal(1000 * MS, 5);
        c.begin_decel(0, 400 * MS);
        assert_eq!(c.t0_ns, 1000 * MS);
    }

    #[test]
    fn stop_distance_covers_an_override() {
        assert_eq!(TimeScaling::stop_distance_ns(400 * MS, UNIT_Q16), 200 * MS);
        assert_eq!(
            TimeScaling::stop_distance_ns(400 * MS, UNIT_Q16 / 2),
            200 * MS
        );
        for k in [UNIT_Q16, UNIT_Q16 * 3 / 2, UNIT_Q16 * 2] {
            let mut ts = TimeScaling::constant(0, 0, k);
            ts.begin_decel(0, 400 * MS);
            ts.at(10_000 * MS);
            let d = ts.at(10_000 * MS).s_ns;
            let bound = TimeScaling::stop_distance_ns(400 * MS, k);
            assert!(d <= bound + 1000, "σ {k}: {d} > {bound}");
        }
    }

    #[test]
    fn sqrt_is_accurate() {
        for i in 1..1000 {
            let x = i as f32 * 0.003;
            assert!((sqrt(x) - x.sqrt()).abs() < 1e-6 * x.sqrt().max(1.0));
        }
    }
}
