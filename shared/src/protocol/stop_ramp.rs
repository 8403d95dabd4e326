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
//!
//! The drives' f32 rule ([`pieces_ramp`]) takes one such triple per joint
//! and piece of a segment: each instant a stop passes through is within
//! its piece's triple, and F grows with each of v, a and j. The same pass
//! sizes each segment's ramp for a stop along the path from σ ≤ 1, whose
//! shape is σ̈ bang-bang ([`pieces_ramp_and_at_unit`]).

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
    stop_time_for_budget(v, a, j, jerk_limit.max(jc + 0.5 * jerk_limit), cap)
}

/// [`stop_time`] for the budget `budget` (m/s³) rather than the one a jerk
/// limit gives.
pub fn stop_time_for_budget(v: f64, a: f64, j: f64, budget: f64, cap: f64) -> f64 {
    grid_bound(v, a, j, budget, cap, DS_CELLS, U_CELLS)
}

/// [`stop_time_for_budget`] on a grid of `ds_cells` × `u_cells`.
fn grid_bound(
    v: f64,
    a: f64,
    j: f64,
    budget: f64,
    cap: f64,
    ds_cells: usize,
    u_cells: usize,
) -> f64 {
    let cap = if cap.is_finite() { cap.max(1.0) } else { 1.0 };
    let budget = budget.max(1e-9);
    let mut t = MIN_RAMP_S;
    for i in 0..ds_cells {
        let d0 = cap * i as f64 / ds_cells as f64;
        let d1 = cap * (i + 1) as f64 / ds_cells as f64;
        // |σ̇|·T ≤ S'·m1, |σ̈|·T² ≤ |S''|·m2 (m1 grows with Δσ, m2 falls).
        let m1 = RHO_SLACK * libm::sqrt(d1).min(1.0);
        let m2 = RHO_SLACK * if d0 > 1.0 { 1.0 / d0 } else { 1.0 };
        for k in 0..u_cells {
            let u0 = k as f64 / u_cells as f64;
            let u1 = (k + 1) as f64 / u_cells as f64;
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

/// Bands of the grid the drives size their own ramps on over Δσ (each
/// term bounded by its monotonicity on a band), and its cells over u.
const COARSE_DS_CELLS: usize = 8;
const COARSE_U_CELLS: usize = 24;
/// h²/8 for the u-cells' width h: a C² function on a cell exceeds the
/// larger of its end values by at most h²/8 times its largest |f″| there
/// (linear interpolation's error).
const INTERPOLATION: f32 = 1.0 / (8.0 * (COARSE_U_CELLS * COARSE_U_CELLS) as f32);
/// Largest S′ (15/8) and |S″| (10/√3), rounded up.
const S1_MAX: f32 = 1.875_001;
const S2_MAX: f32 = 5.773_51;
/// Largest |S′S″|, |S‴| and |S⁗| on [0, 1], rounded up.
const S1S2_MAX: f32 = 6.7;
const S3_MAX: f32 = 60.0;
const S4_MAX: f32 = 360.0;
/// f32 rounding of the cell arithmetic, added to the ramp.
const F32_SLACK: f32 = 1.0e-4;
/// The longest ramp a drive runs (s): a segment that needs more is refused.
pub const MAX_RAMP_S: f32 = 4.0;

/// Nodes u = k/24 up to ½: past it each node's terms are at most its
/// mirror's (σ lower, S′ and |S″| the same), so the mirror bounds it.
const HALF_NODES: usize = COARSE_U_CELLS / 2 + 1;

/// S at the nodes u = k/24 up to ½, and S′ and |S″| there, each the
/// larger of its values at u and 1 − u, rounded up: computed once at
/// compile time. |S″| has kinks only at 0, ½ and 1, all nodes: each
/// cell's terms are C² on it.
const U_NODES: [[f32; 3]; HALF_NODES] = u_nodes();

const fn max_f32(x: f32, y: f32) -> f32 {
    if x > y { x } else { y }
}

const fn u_nodes() -> [[f32; 3]; HALF_NODES] {
    let mut t = [[0.0f32; 3]; HALF_NODES];
    let mut k = 0;
    while k < HALF_NODES {
        let n = COARSE_U_CELLS as f32;
        let (u, m) = (k as f32 / n, (COARSE_U_CELLS - k) as f32 / n);
        t[k] = [
            s_f32(u),
            max_f32(s1_f32(u), s1_f32(m)) * (1.0 + F32_SLACK),
            max_f32(s2_f32(u), s2_f32(m)) * (1.0 + F32_SLACK),
        ];
        k += 1;
    }
    t
}

/// √x (x ≥ 0) as x/√x by Newton's method for 1/√x from a bit-level
/// guess, in plain f32 multiplications: the same bits on the drives and
/// the host, and a few instructions where the drives' libm has no hardware
/// square root (within f32 rounding; the ramp's slack covers it).
fn sqrt_f32(x: f32) -> f32 {
    if x <= 0.0 || !x.is_finite() {
        return if x.is_nan() { x } else { x.max(0.0) };
    }
    let mut y = f32::from_bits(0x5f37_59df - (x.to_bits() >> 1));
    for _ in 0..3 {
        y *= 1.5 - 0.5 * x * y * y;
    }
    x * y
}

const fn s_f32(u: f32) -> f32 {
    u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
}

const fn s1_f32(u: f32) -> f32 {
    30.0 * u * u * (1.0 - u) * (1.0 - u)
}

const fn s2_f32(u: f32) -> f32 {
    (60.0 * u * (1.0 - u) * (1.0 - 2.0 * u)).abs()
}

/// The stop budgets (controlled, quick) of a segment whose largest joint
/// |q‴| is `j`, run at σ up to `cap`, on a drive with jerk limit
/// `jerk_limit` and jerk ceiling `ceiling` (m/s³): the controlled one
/// max(J, j·cap³ + J/2) and the quick one j·cap³ + 3J, J the limit held
/// to the ceiling, each at most the ceiling.
pub fn budgets(j: f32, jerk_limit: f32, ceiling: f32, cap: f32) -> [f32; 2] {
    let jl = jerk_limit.min(ceiling);
    let jc = j * cap * cap * cap;
    [
        ceiling.min(jl.max(jc + 0.5 * jl)),
        ceiling.min(jc + 3.0 * jl),
    ]
}

/// A group of consecutive nodes screened together: from, to, and S at
/// its first node with the largest S′ and |S″| over it.
type Group = (usize, usize, [f32; 3]);

/// The groups, the middle ones first: they hold the nodes that bind.
const GROUPS: [Group; 4] = groups([(4, 7), (0, 4), (7, 10), (10, HALF_NODES)]);

const fn groups<const G: usize>(ranges: [(usize, usize); G]) -> [Group; G] {
    let mut out = [(0, 0, [0.0; 3]); G];
    let mut g = 0;
    while g < G {
        let (from, to) = ranges[g];
        let mut k = from;
        let (mut s1, mut s2) = (0.0f32, 0.0f32);
        while k < to {
            s1 = max_f32(s1, U_NODES[k][1]);
            s2 = max_f32(s2, U_NODES[k][2]);
            k += 1;
        }
        out[g] = (from, to, [U_NODES[from][0], s1, s2]);
        g += 1;
    }
    out
}

/// Cells of u ∈ [0, ½] on which a stop along the path is sized.
const BANG_CELLS: usize = 12;
/// Where (1 − 2u²)·4u peaks: u = 1/√6.
const BANG_PEAK_U: f32 = 0.408_248_3;

/// A stop along the path from σ ≤ 1, σ = σ₀(1 − S(u)) with σ̈ bang-bang
/// (S = 2u² up to u = ½, then 1 − 2(1 − u)²; `firmware/src/scaling.rs`):
/// on each cell of u ∈ [0, ½] the coefficients of j, a/T and v/T² in F,
/// each term at its largest on the cell by its monotonicity there: σ³ = (1 − 2u²)³
/// at the cell's start, 3·σ·S′ = 3(1 − 2u²)·4u where it peaks on the
/// cell, and |S″| = 4 (times the drives' slack on ρ for σ̇ and σ̈). Past
/// ½ each term is at most its mirror's (σ lower, S′ and |S″| the same).
const BANG_NODES: [[f32; 3]; BANG_CELLS] = bang_nodes();
/// Each coefficient's largest over the cells: a triple within the budget
/// with these is within it on every cell.
const BANG_TOP: [f32; 3] = bang_top();

/// The same cells for the joint acceleration q″σ² + q′σ̇ of a stop along
/// the path: σ² at the cell's start and S′ = 4u at the cell's end (times
/// the drives' slack on ρ), so it is at most a·c₀ + v·c₁/T there.
const BANG_ACCEL: [[f32; 2]; BANG_CELLS] = bang_accel();

const fn bang_accel() -> [[f32; 2]; BANG_CELLS] {
    let mut t = [[0.0f32; 2]; BANG_CELLS];
    let mut k = 0;
    while k < BANG_CELLS {
        let (_, u1, g) = bang_cell(k);
        t[k] = [g * g * (1.0 + F32_SLACK), 4.0 * u1 * BANG_SLACK];
        k += 1;
    }
    t
}

/// The drives' slack on ρ (for σ̇ and σ̈) with the f32 slack.
const BANG_SLACK: f32 = (RHO_SLACK as f32) * (1.0 + F32_SLACK);

/// Cell `k` of u ∈ [0, ½]: its start u₀, its end u₁, and σ = 1 − 2u₀² at
/// its start (the largest on it).
const fn bang_cell(k: usize) -> (f32, f32, f32) {
    let n = (2 * BANG_CELLS) as f32;
    let (u0, u1) = (k as f32 / n, (k + 1) as f32 / n);
    (u0, u1, 1.0 - 2.0 * u0 * u0)
}

const fn bang_top() -> [f32; 3] {
    let mut top = [0.0f32; 3];
    let mut k = 0;
    while k < BANG_CELLS {
        let mut i = 0;
        while i < 3 {
            top[i] = max_f32(top[i], BANG_NODES[k][i]);
            i += 1;
        }
        k += 1;
    }
    top
}

const fn bang_nodes() -> [[f32; 3]; BANG_CELLS] {
    let mut t = [[0.0f32; 3]; BANG_CELLS];
    let mut k = 0;
    while k < BANG_CELLS {
        let (u0, u1, g) = bang_cell(k);
        let um = if BANG_PEAK_U < u0 {
            u0
        } else if BANG_PEAK_U > u1 {
            u1
        } else {
            BANG_PEAK_U
        };
        t[k] = [
            g * g * g * (1.0 + F32_SLACK),
            3.0 * (1.0 - 2.0 * um * um) * 4.0 * um * BANG_SLACK,
            4.0 * BANG_SLACK,
        ];
        k += 1;
    }
    t
}

/// At most this many triples (v, a, j) are sized apart; more are merged
/// into the last (their largest of each, as sound).
pub const MAX_TRIPLES: usize = 12;

/// Whether every number of `xs` is finite and at least 0 (not NaN).
#[inline(never)]
fn finite_and_positive(xs: &[f32]) -> bool {
    for x in xs {
        if !(*x >= 0.0 && *x < f32::INFINITY) {
            return false;
        }
    }
    true
}

/// Whether `x` is at most `y` in each of v, a and j.
#[inline(always)]
fn dominated(x: &[f32; 3], y: &[f32; 3]) -> bool {
    x[0] <= y[0] && x[1] <= y[1] && x[2] <= y[2]
}

/// The triples of `triples` no other one dominates (F grows with each of
/// v, a and j, so a dominated triple never needs the longer ramp), in the
/// first slots, and how many.
#[inline(never)]
fn frontier(triples: &[[f32; 3]]) -> ([[f32; 3]; MAX_TRIPLES], usize) {
    let mut kept = [[0.0f32; 3]; MAX_TRIPLES];
    let mut n = 0;
    for t in triples {
        let Some(front) = kept.get_mut(..n) else {
            break;
        };
        if front.iter().any(|k| dominated(t, k)) {
            continue;
        }
        // Those `t` dominates make room, in order.
        let mut m = 0;
        for i in 0..n {
            if let Some(&k) = kept.get(i)
                && !dominated(&k, t)
            {
                if let Some(slot) = kept.get_mut(m) {
                    *slot = k;
                }
                m += 1;
            }
        }
        n = m;
        if let Some(slot) = kept.get_mut(n) {
            *slot = *t;
            n += 1;
        } else if let Some(k) = kept.last_mut() {
            *k = [k[0].max(t[0]), k[1].max(t[1]), k[2].max(t[2])];
        }
    }
    (kept, n)
}

/// The ramps (s) with which every transition from a constant σ ≤ `cap`
/// keeps the joint jerk within each of `budgets` (controlled, quick) for
/// each triple of `triples` (a joint's largest |q′|, |q″|, |q‴| over a
/// piece of a segment, or the segment's over its joints): [`stop_time`]'s
/// rule in f32, the one function both the drives (for each segment they
/// accept) and the host (over the plan) run.
///
/// On each of 8 bands of Δσ, F is bounded by the smooth function of u
/// with σ at the band's smallest Δσ, σ̇'s factor at its largest and σ̈'s at
/// its smallest; that function is bounded by its values at the nodes
/// u = k/24 plus h²/8 times a bound on its second derivative (so the
/// bound is tight to second order in h, where one that takes each term's
/// largest value on a cell loses to first order). A triple another
/// dominates is skipped: the ramp is the same as over every triple.
/// `None` when no ramp up to [`MAX_RAMP_S`] does (a triple's own jerk at
/// the cap leaves no room) or an input is not a finite number ≥ 0.
pub fn pieces_ramp(triples: &[[f32; 3]], budgets: [f32; 2], cap: f32) -> Option<[f32; 2]> {
    pieces_ramp_and_at_unit(triples, budgets, cap, f32::INFINITY).map(|[full, _]| full)
}

/// [`pieces_ramp`] and the ramps with which a stop along the path (to
/// σ = 0, σ̈ bang-bang) from a constant σ ≤ 1 keeps the joint jerk within
/// each of `budgets` for each triple: the bound on `BANG_NODES` from
/// σ = 1, which bounds every such stop from σ₀ ≤ 1 term by term (σ ≤
/// 1 − S, |σ̇| ≤ S′/T and |σ̈| = |S″|/T² at ρ ≥ √σ₀), and its joint
/// acceleration within `accel_ceiling` (`BANG_ACCEL`; infinite where
/// no ramp keeps it there). It is not bounded by the full ramp
/// (the quintic's): where it is longer the drives run the full ramp
/// instead. `[full, at_unit]`.
pub fn pieces_ramp_and_at_unit(
    triples: &[[f32; 3]],
    budgets: [f32; 2],
    cap: f32,
    accel_ceiling: f32,
) -> Option<[[f32; 2]; 2]> {
    let (kept, n) = checked_frontier(triples, budgets, cap)?;
    let kept = kept.get(..n).unwrap_or(&[]);
    // Stops along the path from σ ≤ 1 (σ̈ bang-bang) first.
    let at_unit = unit_ramp(kept, budgets, accel_ceiling)?;
    Some([full_ramp(kept, budgets, cap)?, at_unit])
}

/// [`pieces_ramp`] with each group of `triples`' own ramps for a stop
/// along the path from σ ≤ 1 ([`unit_ramp`]): `group(i)` lists the triples
/// of group i (a piece of a segment: its three joints). `(full, by group)`.
pub fn pieces_ramp_and_units<const N: usize>(
    triples: &[[f32; 3]],
    group: impl Fn(usize) -> [[f32; 3]; 3],
    budgets: [f32; 2],
    cap: f32,
    accel_ceiling: f32,
) -> Option<([f32; 2], [[f32; 2]; N])> {
    let (kept, n) = checked_frontier(triples, budgets, cap)?;
    let kept = kept.get(..n).unwrap_or(&[]);
    let mut units = [[0.0f32; 2]; N];
    for (i, u) in units.iter_mut().enumerate() {
        *u = unit_ramp(&group(i), budgets, accel_ceiling)?;
    }
    Some((full_ramp(kept, budgets, cap)?, units))
}

/// The triples no other one dominates, if every input is a finite
/// number ≥ 0 and the cap at least 1.
fn checked_frontier(
    triples: &[[f32; 3]],
    budgets: [f32; 2],
    cap: f32,
) -> Option<([[f32; 3]; MAX_TRIPLES], usize)> {
    (finite_and_positive(triples.as_flattened())
        && finite_and_positive(&budgets)
        && finite_and_positive(&[cap])
        && cap >= 1.0)
        .then(|| frontier(triples))
}

/// The full ramps (controlled, quick) of the triples `kept`: every
/// transition from a constant σ ≤ `cap` within `budgets`.
fn full_ramp(kept: &[[f32; 3]], budgets: [f32; 2], cap: f32) -> Option<[f32; 2]> {
    let t0 = MIN_RAMP_S as f32;
    // Each ramp so far, with 1/T and 1/T².
    let mut t = [[t0, 1.0 / t0, 1.0 / (t0 * t0)]; 2];
    let mut band = Band::default();
    // The full stops first: they need the longest ramps, so later bands
    // seldom raise it (a raise costs a division and a square root).
    for i in (0..COARSE_DS_CELLS).rev() {
        let ds_n = COARSE_DS_CELLS as f32;
        band.set(cap, cap * i as f32 / ds_n, cap * (i + 1) as f32 / ds_n);
        for (tk, b) in t.iter_mut().zip(budgets) {
            band.size(kept, b, tk)?;
        }
    }
    let full = t.map(|tk| tk[0] * (1.0 + F32_SLACK));
    full.iter().all(|x| *x <= MAX_RAMP_S).then_some(full)
}

/// The ramps (controlled, quick: one for each of `budgets`) with which a
/// stop along the path from a constant σ ≤ 1 keeps the joint jerk of
/// every triple of `triples` within the budget and its joint acceleration
/// within `accel_ceiling`: [`pieces_ramp_and_at_unit`]'s `at_unit` without
/// the full ramp, for the triples of one piece of a segment. Inputs are
/// taken as checked; `None` when a triple's own jerk leaves no room.
#[inline(never)]
pub fn unit_ramp(triples: &[[f32; 3]], budgets: [f32; 2], accel_ceiling: f32) -> Option<[f32; 2]> {
    let t0 = MIN_RAMP_S as f32;
    let mut unit = [[t0, 1.0 / t0, 1.0 / (t0 * t0)]; 2];
    for (tk, b) in unit.iter_mut().zip(budgets) {
        for &triple in triples {
            if jerk(&BANG_TOP, triple[2], triple[1] * tk[1], triple[0] * tk[2]) <= b {
                continue;
            }
            for p in &BANG_NODES {
                if jerk(p, triple[2], triple[1] * tk[1], triple[0] * tk[2]) > b {
                    raise(p, &triple, b, tk)?;
                }
            }
        }
    }
    Some(unit.map(|tk| unit_within_acceleration(triples, accel_ceiling, tk[0])))
}

// The helpers below are out of line (`inline(never)`): unrolled, they
// would not fit the drives' flash.

/// One band of Δσ: its nodes' coefficients of j, a/T and v/T², and the
/// screens' (each group's at least every node's in it, the band's at
/// least every group's).
#[derive(Default)]
struct Band {
    c: Coefficients,
    tops: [[f32; 3]; GROUPS.len()],
    top: [f32; 3],
    /// The nodes, computed for a group when a triple first needs them.
    nodes: [[f32; 3]; HALF_NODES],
    ready: u8,
}

impl Band {
    /// The band Δσ ∈ [d0, d1] of transitions from σ ≤ `cap`, its nodes
    /// not computed yet.
    #[inline(never)]
    fn set(&mut self, cap: f32, d0: f32, d1: f32) {
        let slack = RHO_SLACK as f32;
        // |σ̇|·T ≤ S′·m1/3, |σ̈|·T² ≤ |S″|·m2 (m1 grows with Δσ, m2 falls).
        let m1 = 3.0 * slack * sqrt_f32(d1).min(1.0);
        let m2 = slack * if d0 > 1.0 { 1.0 / d0 } else { 1.0 };
        // On this band F ≤ j·g³ + a·m1·g·S′/T + v·m2·|S″|/T², g = cap − d0·S
        // (0 ≤ g ≤ cap). Its second derivatives in u, term by term:
        // (g³)″ = 6g·g′² + 3g²·g″, (g·S′)″ = g·S‴ − 3·d0·S′S″, |S″|″ = ±S⁗.
        let r = [
            6.0 * cap * d0 * d0 * S1_MAX * S1_MAX + 3.0 * cap * cap * d0 * S2_MAX,
            m1 * (cap * S3_MAX + 3.0 * d0 * S1S2_MAX),
            m2 * S4_MAX,
        ]
        .map(|x| x * INTERPOLATION);
        self.c = Coefficients { cap, d0, m1, m2, r };
        self.ready = 0;
        self.top = [0.0; 3];
        // σ is largest at a group's first node.
        for (top, (_, _, u)) in self.tops.iter_mut().zip(GROUPS) {
            *top = self.c.node(u);
            for (m, x) in self.top.iter_mut().zip(top.iter()) {
                if *x > *m {
                    *m = *x;
                }
            }
        }
    }

    /// Raises the ramp `tk` (with 1/T, 1/T²) until every triple of `kept`
    /// is within `budget` at every node of this band; `None` when one's
    /// own jerk leaves no room.
    #[inline(never)]
    fn size(&mut self, kept: &[[f32; 3]], budget: f32, tk: &mut [f32; 3]) -> Option<()> {
        for &[v, a, j] in kept {
            let (mut ax, mut vx) = (a * tk[1], v * tk[2]);
            if jerk(&self.top, j, ax, vx) <= budget {
                continue;
            }
            for g in 0..GROUPS.len() {
                let (Some(top), Some(&(from, to, _))) = (self.tops.get(g), GROUPS.get(g)) else {
                    break;
                };
                if jerk(top, j, ax, vx) <= budget {
                    continue;
                }
                let (Some(ps), Some(us)) = (self.nodes.get_mut(from..to), U_NODES.get(from..to))
                else {
                    continue;
                };
                if self.ready & (1 << g) == 0 {
                    for (p, u) in ps.iter_mut().zip(us) {
                        *p = self.c.node(*u);
                    }
                    self.ready |= 1 << g;
                }
                for p in ps.iter() {
                    if jerk(p, j, ax, vx) > budget {
                        raise(p, &[v, a, j], budget, tk)?;
                        (ax, vx) = (a * tk[1], v * tk[2]);
                    }
                }
            }
        }
        Some(())
    }
}

/// A band's factors: the cap, its smallest Δσ, σ̇'s and σ̈'s factors and
/// the interpolation margins of the three terms.
#[derive(Default)]
struct Coefficients {
    cap: f32,
    d0: f32,
    m1: f32,
    m2: f32,
    r: [f32; 3],
}

impl Coefficients {
    /// The coefficients of j, a/T and v/T² at a node of S, S′, |S″| `u`.
    #[inline(never)]
    fn node(&self, [s, s1, s2]: [f32; 3]) -> [f32; 3] {
        let sigma = self.cap - self.d0 * s;
        let r = self.r;
        [
            sigma * sigma * sigma + r[0],
            self.m1 * sigma * s1 + r[1],
            self.m2 * s2 + r[2],
        ]
    }
}

/// F with the coefficients `p` for j, a/T (`ax`) and v/T² (`vx`).
#[inline(always)]
fn jerk(p: &[f32; 3], j: f32, ax: f32, vx: f32) -> f32 {
    j * p[0] + ax * p[1] + vx * p[2]
}

/// Raises `tk` (the ramp with 1/T, 1/T²) to the shortest T with
/// j·p₀ + a·p₁/T + v·p₂/T² within `budget` for the triple (v, a, j);
/// `None` when j·p₀ leaves no room.
#[inline(never)]
fn raise(p: &[f32; 3], [v, a, j]: &[f32; 3], budget: f32, tk: &mut [f32; 3]) -> Option<()> {
    let room = budget - j * p[0];
    if room <= 0.0 {
        return None;
    }
    let (b, c) = (a * p[1], v * p[2]);
    let cell = (b + sqrt_f32(b * b + 4.0 * room * c)) / (2.0 * room);
    if cell > tk[0] {
        let x = 1.0 / cell;
        *tk = [cell, x, x * x];
    }
    Some(())
}

/// The ramp `t` of a stop along the path, raised until its joint
/// acceleration a·σ² + v·|σ̇| stays within `ceiling` for every triple of
/// `kept`, with the f32 slack; infinite (never run: no full ramp is
/// longer) where a triple's own acceleration leaves no room or the
/// ceiling is not a number above 0.
#[inline(never)]
fn unit_within_acceleration(kept: &[[f32; 3]], ceiling: f32, mut t: f32) -> f32 {
    if ceiling.is_nan() || ceiling <= 0.0 {
        return f32::INFINITY;
    }
    // c₀ is largest on the first cell, c₁ on the last.
    let top = [BANG_ACCEL[0][0], BANG_ACCEL[BANG_CELLS - 1][1]];
    for &[v, a, _] in kept {
        if a * top[0] + v * top[1] / t <= ceiling {
            continue;
        }
        for [c0, c1] in BANG_ACCEL {
            let room = ceiling - a * c0;
            if room <= 0.0 {
                return f32::INFINITY;
            }
            let need = v * c1 / room;
            if need > t {
                t = need;
            }
        }
    }
    t * (1.0 + F32_SLACK)
}

/// [`pieces_ramp`] for one triple: a segment's maxima `v`, `a`, `j` over
/// its joints.
pub fn segment_ramp(v: f32, a: f32, j: f32, budgets: [f32; 2], cap: f32) -> Option<[f32; 2]> {
    pieces_ramp(&[[v, a, j]], budgets, cap)
}

/// The controlled and quick stop ramps (s) of a segment with maxima `v`,
/// `a`, `j` on a drive with jerk limit `jerk_limit`, ceiling `ceiling` and
/// override cap `cap` ([`budgets`], [`segment_ramp`]).
pub fn segment_ramps(
    v: f32,
    a: f32,
    j: f32,
    jerk_limit: f32,
    ceiling: f32,
    cap: f32,
) -> Option<(f32, f32)> {
    let [s, q] = segment_ramp(v, a, j, budgets(j, jerk_limit, ceiling, cap), cap)?;
    Some((s, q))
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

    /// The largest F over transitions from a constant σ at ramp `t`, each
    /// `[σ₀, Δσ, ρ]` (to σ₀ − Δσ over t·ρ), sampled on 2 001 points.
    fn worst_of(v: f64, a: f64, j: f64, t: f64, runs: impl Iterator<Item = [f64; 3]>) -> f64 {
        let mut worst = 0.0f64;
        for [s0, ds, rho] in runs {
            let tt = t * rho;
            for k in 0..=2000 {
                let u = k as f64 / 2000.0;
                let sigma = s0 - ds * s(u);
                let sd = ds * s1(u) / tt;
                let sdd = ds * s2(u) / (tt * tt);
                worst = worst.max(j * sigma.powi(3) + 3.0 * a * sigma * sd + v * sdd);
            }
        }
        worst
    }

    /// The largest F over the transitions a drive may run from a constant
    /// σ at ramp `t`, sampled densely, each with the shortest ρ the drive
    /// accepts (√Δσ below 1, else Δσ).
    fn worst_jerk(v: f64, a: f64, j: f64, cap: f64, t: f64) -> f64 {
        let runs = (1..=400).map(|i| {
            let ds = cap * i as f64 / 400.0;
            // The drive's ρ: the smallest of its candidates, at most this.
            [cap, ds, if ds >= 1.0 { ds } else { libm::sqrt(ds) }]
        });
        worst_of(v, a, j, t, runs)
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

    /// The drives' coarse f32 ramp keeps every transition within its
    /// budget, and the budget never exceeds the ceiling.
    #[test]
    fn segment_ramp_is_a_bound_and_held_to_the_ceiling() {
        // (v, a, j, jerk limit, ceiling, cap)
        for (v, a, j, lim, ceil, cap) in [
            (0.5, 1.2, 5.0, 5.0, 1e6, 1.0),
            (0.5, 1.2, 5.0, 5.0, 6.0, 1.0),
            (0.2, 0.8, 1.5, 5.0, 7.5, 1.585),
            (0.3, 0.77, 2.5, 5.0, 7.5, 1.177),
            (0.1, 0.5, 0.3, 5.0, 10.0, 2.955),
            (0.5, 1.2, 0.0, 15.0, 20.0, 1.0),
        ] {
            let bs = budgets(j as f32, lim as f32, ceil as f32, cap as f32);
            let [ts, tq] = segment_ramp(v as f32, a as f32, j as f32, bs, cap as f32)
                .unwrap_or_else(|| {
                    panic!(
                        "{v} {a} {j} {ceil} {cap}: {}",
                        stop_time_for_budget(v, a, j, bs[0] as f64, cap)
                    )
                });
            for (t, b) in [(ts, bs[0]), (tq, bs[1])] {
                let (t, b) = (t as f64, b as f64);
                assert!(b <= ceil, "budget {b} above the ceiling {ceil}");
                let w = worst_jerk(v, a, j, cap, t);
                assert!(w <= b * (1.0 + 1e-6), "{v} {a} {j} {cap}: {w} > {b}");
                // Never shorter than the fine f64 bound for the same budget.
                let fine = stop_time_for_budget(v, a, j, b, cap);
                assert!(t >= fine, "{t} < {fine}");
                assert!(t <= 1.35 * fine.max(MIN_RAMP_S), "{t} ≫ {fine}");
                // Never longer than taking each term's largest value on
                // every cell of the same 8 × 24 grid (the rule before).
                let cells = grid_bound(v, a, j, b, cap, COARSE_DS_CELLS, COARSE_U_CELLS);
                assert!(t <= cells * (1.0 + 1e-3), "{t} > {cells}");
            }
        }
    }

    /// The same over a sweep of maxima, caps and ceilings: the node bound
    /// with its second-derivative margin holds between the nodes.
    #[test]
    fn segment_ramp_is_a_bound_over_a_sweep() {
        let mut checked = 0;
        for v in [0.02, 0.5, 2.0] {
            for a in [0.1, 1.2, 6.0] {
                for j in [0.0, 1.0, 4.0] {
                    for cap in [1.0, 1.4, 3.0] {
                        for ceil in [6.0, 40.0] {
                            let bs = budgets(j as f32, 5.0, ceil as f32, cap as f32);
                            let Some(r) =
                                segment_ramp(v as f32, a as f32, j as f32, bs, cap as f32)
                            else {
                                continue;
                            };
                            for (t, b) in r.iter().zip(bs) {
                                let w = worst_jerk(v, a, j, cap, *t as f64);
                                assert!(
                                    w <= b as f64 * (1.0 + 1e-6),
                                    "{v} {a} {j} {cap} {ceil}: {w} > {b}"
                                );
                                checked += 1;
                            }
                        }
                    }
                }
            }
        }
        assert!(checked > 150, "{checked}");
    }

    /// σ, |σ̇| and |σ̈| of the stops along the path (to σ = 0, σ̈
    /// bang-bang) a drive may run from a constant σ₀ = 0.01 … 1 at ramp `t`
    /// (over t·ρ, ρ = √σ₀), on 2 001 points each.
    fn bang_stop_states(t: f64) -> impl Iterator<Item = [f64; 3]> {
        (1..=100).flat_map(move |i| {
            let s0 = i as f64 / 100.0;
            let tt = t * libm::sqrt(s0);
            (0..=2000).map(move |k| {
                let u = k as f64 / 2000.0;
                let (s, s1) = if u < 0.5 {
                    (2.0 * u * u, 4.0 * u)
                } else {
                    (1.0 - 2.0 * (1.0 - u) * (1.0 - u), 4.0 * (1.0 - u))
                };
                [s0 * (1.0 - s), s0 * s1 / tt, s0 * 4.0 / (tt * tt)]
            })
        })
    }

    /// The largest F over the stops along the path at ramp `t`.
    fn worst_stop_jerk_at_most_unit(v: f64, a: f64, j: f64, t: f64) -> f64 {
        bang_stop_states(t)
            .map(|[sigma, sd, sdd]| j * sigma.powi(3) + 3.0 * a * sigma * sd + v * sdd)
            .fold(0.0, f64::max)
    }

    /// The ramp for stops along the path from σ ≤ 1 keeps each within the
    /// budget, and is shorter than the ramp for every transition where
    /// the velocity term binds (|S″| 4 against the quintic's 5.77) or the
    /// cap is above 1.
    #[test]
    fn the_stop_ramp_at_unit_is_a_bound_and_shorter_where_velocity_binds() {
        let (mut checked, mut shorter, mut longer) = (0, 0, 0);
        for v in [0.02, 0.5, 2.0] {
            for a in [0.1, 1.2, 6.0] {
                for j in [0.0, 1.0, 4.0] {
                    for cap in [1.0, 1.4, 3.0] {
                        let bs = budgets(j as f32, 5.0, 40.0, cap as f32);
                        let triple = [[v as f32, a as f32, j as f32]];
                        let Some([full, unit]) =
                            pieces_ramp_and_at_unit(&triple, bs, cap as f32, f32::INFINITY)
                        else {
                            continue;
                        };
                        assert_eq!(pieces_ramp(&triple, bs, cap as f32), Some(full));
                        for ((t, b), f) in unit.iter().zip(bs).zip(full) {
                            let w = worst_stop_jerk_at_most_unit(v, a, j, *t as f64);
                            assert!(w <= b as f64 * (1.0 + 1e-6), "{v} {a} {j} {cap}: {w} > {b}");
                            // Not loose by more than the cells' width.
                            assert!(w >= b as f64 * 0.9, "{v} {a} {j} {cap}: {w} of {b}");
                            if v >= 0.5 && cap == 1.0 {
                                assert!(*t < 0.95 * f, "{v} {a} {j}: {t} against {f}");
                            }
                            shorter += usize::from(*t < 0.99 * f);
                            longer += usize::from(*t > f);
                            checked += 1;
                        }
                    }
                }
            }
        }
        std::eprintln!("{checked} ramps, {shorter} shorter than the full ramp, {longer} longer");
        assert!(
            checked >= 80 && shorter > 60 && longer == 0,
            "{checked} {shorter} {longer}"
        );
    }

    /// The largest joint acceleration a·σ² + v·|σ̇| over the stops along
    /// the path at ramp `t`.
    fn worst_stop_acceleration(v: f64, a: f64, t: f64) -> f64 {
        bang_stop_states(t)
            .map(|[sigma, sd, _]| a * sigma * sigma + v * sd)
            .fold(0.0, f64::max)
    }

    /// A stop along the path keeps the joint acceleration within the
    /// drive's acceleration ceiling: its ramp grows where the jerk's alone
    /// would pass it, and is never offered (infinite) where the segment's
    /// own acceleration leaves no room.
    #[test]
    fn the_stop_ramp_at_unit_holds_the_acceleration_ceiling() {
        let bs = budgets(1.0, 5.0, 40.0, 1.0);
        let mut raised = 0;
        for v in [0.1, 0.5, 2.0] {
            for a in [0.1, 1.2] {
                for ceiling in [1.25, 2.0, 5.0] {
                    let triple = [[v as f32, a as f32, 1.0]];
                    let [_, free] =
                        pieces_ramp_and_at_unit(&triple, bs, 1.0, f32::INFINITY).unwrap();
                    let [_, held] =
                        pieces_ramp_and_at_unit(&triple, bs, 1.0, ceiling as f32).unwrap();
                    for (h, f) in held.iter().zip(free) {
                        assert!(*h >= f, "{v} {a} {ceiling}: {h} {f}");
                        if *h >= MAX_RAMP_S {
                            // Longer than any full ramp: not even that is
                            // well within the ceiling.
                            let w = worst_stop_acceleration(v, a, MAX_RAMP_S as f64);
                            assert!(w > 0.9 * ceiling, "{v} {a} {ceiling}: {w}");
                            continue;
                        }
                        let w = worst_stop_acceleration(v, a, *h as f64);
                        assert!(w <= ceiling * (1.0 + 1e-6), "{v} {a} {ceiling}: {w}");
                        raised += usize::from(*h > f);
                    }
                }
            }
        }
        assert!(raised >= 6, "{raised}");
        // None offered (infinite): the segment's own acceleration is the
        // ceiling, or the ceiling is not a number; so a configured full
        // ramp of any length is shorter.
        for ceiling in [2.0, f32::NAN, 0.0] {
            let none = pieces_ramp_and_at_unit(&[[0.5, 2.0, 1.0]], bs, 1.0, ceiling).unwrap();
            assert_eq!(none[1], [f32::INFINITY; 2], "{ceiling}");
        }
    }

    /// Over sets of triples (a joint's maxima on the pieces of a
    /// segment): the ramps keep every transition within the budget for
    /// each triple, and are the largest of each triple's own (the screens
    /// and the dominated triples skipped change nothing).
    #[test]
    fn pieces_ramp_is_a_bound_for_every_triple_and_the_largest_of_their_own() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(35);
        let mut checked = 0;
        for _ in 0..60 {
            let n = rng.random_range(1..=MAX_TRIPLES);
            let scale = [
                rng.random_range(0.01..1.0f32),
                rng.random_range(0.1..3.0f32),
                rng.random_range(0.0..4.0f32),
            ];
            let triples: std::vec::Vec<[f32; 3]> = (0..n)
                .map(|_| scale.map(|m| m * rng.random_range(0.0..1.0f32)))
                .collect();
            let cap = [1.0f32, 1.3, 2.5][rng.random_range(0..3)];
            let j = triples.iter().fold(0.0f32, |m, t| m.max(t[2]));
            let bs = budgets(j, 5.0, [6.0f32, 40.0][rng.random_range(0..2)], cap);
            let Some(r) = pieces_ramp(&triples, bs, cap) else {
                assert!(
                    triples
                        .iter()
                        .any(|t| segment_ramp(t[0], t[1], t[2], bs, cap).is_none())
                );
                continue;
            };
            for k in 0..2 {
                let own = triples
                    .iter()
                    .map(|t| segment_ramp(t[0], t[1], t[2], bs, cap).unwrap()[k])
                    .fold(0.0f32, f32::max);
                assert!((r[k] - own).abs() <= 1e-5 * own, "{} vs {own}", r[k]);
                for &[v, a, jt] in &triples {
                    let w = worst_jerk(v as f64, a as f64, jt as f64, cap as f64, r[k] as f64);
                    assert!(w <= bs[k] as f64 * (1.0 + 1e-6), "{w} > {}", bs[k]);
                }
                checked += 1;
            }
        }
        assert!(checked > 60, "{checked}");
    }

    /// More triples than are sized apart: the extra ones are merged into
    /// the last, so the ramp is never shorter than each one's own.
    #[test]
    fn more_triples_than_kept_apart_are_merged_soundly() {
        // Mutually undominated: v rises as a falls.
        let triples: std::vec::Vec<[f32; 3]> = (0..20)
            .map(|i| {
                let x = i as f32 / 19.0;
                [0.05 + 0.3 * x, 1.5 - 1.2 * x, 0.5]
            })
            .collect();
        let bs = budgets(0.5, 5.0, 40.0, 1.2);
        let r = pieces_ramp(&triples, bs, 1.2).unwrap();
        for t in &triples {
            let own = segment_ramp(t[0], t[1], t[2], bs, 1.2).unwrap();
            assert!(r[0] >= own[0] && r[1] >= own[1], "{r:?} < {own:?}");
        }
    }

    #[test]
    fn no_room_under_the_ceiling_is_no_ramp() {
        // The segment's own jerk at the cap is the ceiling: nothing left.
        assert_eq!(segment_ramps(0.5, 1.2, 5.0, 5.0, 5.0, 1.0), None);
        // At 80 % of it, a ramp.
        assert!(segment_ramps(0.5, 1.2, 4.0, 5.0, 5.0, 1.0).is_some());
        // Longer than the longest ramp: none.
        assert_eq!(segment_ramps(50.0, 1.2, 4.0, 5.0, 5.0, 1.0), None);
        for bad in [f32::NAN, f32::INFINITY, -1.0] {
            assert_eq!(segment_ramps(bad, 1.2, 4.0, 5.0, 5.0, 1.0), None);
            assert_eq!(segment_ramps(0.5, 1.2, 4.0, 5.0, 5.0, bad), None);
        }
    }

    #[test]
    fn sqrt_f32_is_the_square_root() {
        let mut x = 1e-12f32;
        while x < 1e12 {
            let got = sqrt_f32(x) as f64;
            let want = (x as f64).sqrt();
            assert!((got - want).abs() <= 1e-6 * want, "{x}: {got} vs {want}");
            x *= 1.37;
        }
        assert_eq!(sqrt_f32(0.0), 0.0);
        assert!(sqrt_f32(f32::INFINITY) == f32::INFINITY);
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
