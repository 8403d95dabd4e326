//! The stop ramp a Stop, QuickStop or FeedHold carries for the path ahead
//! of its instant (docs/protocol.md, "A ramp for the path ahead"): the
//! largest of the drives' own ramps for a stop from σ ≤ 1 (the same f32
//! rule on the same wire segments, `wire_ramps_and_units`) over the
//! pieces of segments a stop from there can pass through. The drives run
//! it only at σ ≤ 1 and only if it covers those ramps of the pieces they
//! hold in that window, so a wrong estimate of where the plan is, or a σ
//! above 1, costs the shorter stop, never a harder one.

use triquint_shared::protocol::segment_maxima::{PIECES, wire_ramps_and_units};
use triquint_shared::protocol::{DriveConfig, WireSegment};

/// Room on each side of the host's estimate of the plan time (µs): its
/// error at σ = 1 with nothing held or overridden is the clocks' sync
/// error, well under this.
const ESTIMATE_MARGIN_US: f64 = 20_000.0;

/// The unit of the command's ramp field (µs).
const UNIT_US: u64 = 100;

#[derive(Clone, Debug)]
pub(crate) struct PathRamps {
    /// Each piece's plan-time span (µs) and its own ramps for a stop from
    /// σ ≤ 1 (µs): controlled, and quick (its segment's: the drives hold a
    /// quick stop to the whole segment's), in plan order.
    pieces: Vec<(f64, f64, [f64; 2])>,
    /// The ramps every transition runs with (µs): the configured ones.
    full_us: [f64; 2],
}

impl PathRamps {
    pub fn new(segments: &[WireSegment], c: &DriveConfig) -> Self {
        let mut start = 0.0;
        let mut full_us = [c.stop_time as f64 * 1e6, c.quick_stop_time as f64 * 1e6];
        let mut rows = Vec::with_capacity(segments.len() * PIECES);
        for w in segments {
            let us = |(s, q): (f32, f32)| [s as f64 * 1e6, q as f64 * 1e6];
            let (ramps, units) = wire_ramps_and_units(
                w,
                c.max_jerk,
                c.ceiling_jerk,
                c.override_cap,
                c.ceiling_acceleration,
            )
            .map_or(
                ([f64::INFINITY; 2], [[f64::INFINITY; 2]; PIECES]),
                |(r, u)| (us(r), u.map(us)),
            );
            // The drives' pieces: equal, in whole ns (w.duration_us × 250).
            let piece = w.duration_us as f64 / PIECES as f64;
            let at = |k: usize| start + piece * k as f64;
            let quick = units.iter().map(|u| u[1]).fold(0.0, f64::max);
            for (k, u) in units.into_iter().enumerate() {
                rows.push((at(k), at(k + 1), [u[0], quick]));
            }
            start = at(PIECES);
            full_us = [full_us[0].max(ramps[0]), full_us[1].max(ramps[1])];
        }
        Self {
            pieces: rows,
            full_us,
        }
    }

    /// The command's ramp field (100 µs units, rounded up) for a stop
    /// (`quick`: the quick stop's) at estimated plan time `plan_us` and σ
    /// ≤ 1: the largest own ramp for such a stop over the pieces a stop
    /// from within [`ESTIMATE_MARGIN_US`] of it can pass through with that
    /// ramp (a stop from σ ≤ 1 covers at most half its ramp of plan time:
    /// the window grows with the ramp); 0 when that is not shorter (the
    /// drives then size their own for a dated Stop or FeedHold, and run
    /// the full ramp otherwise).
    pub fn dated(&self, plan_us: f64, quick: bool) -> u16 {
        let k = usize::from(quick);
        let full = self.full_us[k];
        let lo = plan_us - ESTIMATE_MARGIN_US;
        // 1 µs over: the drives round their own ramp from f32.
        let units = |ahead: f64| ((ahead + 1.0) / UNIT_US as f64).ceil();
        let mut ahead: f64 = 0.0;
        loop {
            let hi = plan_us + ESTIMATE_MARGIN_US + 0.5 * units(ahead) * UNIT_US as f64;
            let next = self
                .pieces
                .iter()
                .filter(|&&(a, b, _)| b > lo && a < hi)
                .map(|s| s.2[k])
                .fold(ahead, f64::max);
            // Past the full ramp the drives run that one anyway.
            if next <= ahead || next >= full {
                ahead = next;
                break;
            }
            ahead = next;
        }
        let units = units(ahead);
        // u16::MAX is no ramp to the drives.
        if ahead > 0.0 && units * (UNIT_US as f64) < full && units < u16::MAX as f64 {
            units as u16
        } else {
            0
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::configs::{DriveConfigs, committed_plan};
    use triquint_shared::protocol::DriveSettings;

    #[test]
    fn never_longer_than_the_full_ramp_and_never_below_the_segment_it_is_in() {
        let p = committed_plan("case2-spline");
        let configs = DriveConfigs::for_plan(&p, &DriveSettings::default()).unwrap();
        let w = p.wire_segments().unwrap();
        let r = PathRamps::new(&w, &configs.nodes[0]);
        let total = r.pieces.last().unwrap().1;
        let mut shorter = 0;
        for i in 0..=100 {
            let t = total * i as f64 / 100.0;
            for quick in [false, true] {
                let d = r.dated(t, quick) as f64 * UNIT_US as f64;
                let k = usize::from(quick);
                if d == 0.0 {
                    continue;
                }
                shorter += 1;
                assert!(d < r.full_us[k], "{t}: {d}");
                for &(a, b, ramps) in &r.pieces {
                    if b > t - ESTIMATE_MARGIN_US && a < t + ESTIMATE_MARGIN_US + 0.5 * d {
                        assert!(ramps[k] <= d, "{t}: segment's {} > {d}", ramps[k]);
                    }
                }
            }
        }
        assert!(shorter > 0);
    }

    /// A committed plan, the first node's configuration for it, its wire
    /// segments and their path ramps.
    fn committed_rig(
        name: &str,
    ) -> (
        triquint_shared::plan::Plan,
        DriveConfig,
        Vec<WireSegment>,
        PathRamps,
    ) {
        let p = committed_plan(name);
        let configs = DriveConfigs::for_plan(&p, &DriveSettings::default()).unwrap();
        let c = configs.nodes[0];
        let w = p.wire_segments().unwrap();
        let r = PathRamps::new(&w, &c);
        (p, c, w, r)
    }

    /// Each wire segment's plan-time span (µs), in plan order.
    fn segment_spans_us(w: &[WireSegment]) -> impl Iterator<Item = (f64, f64)> + '_ {
        w.iter().scan(0.0, |start, s| {
            let a = *start;
            *start += s.duration_us as f64;
            Some((a, *start))
        })
    }

    /// The shortest time in which one joint at speed `v` and acceleration
    /// `a` can come to rest (speed and acceleration 0) with |jerk| ≤ `b`
    /// and no other limit: jerk −b then +b (or the mirror), closed form.
    fn one_joint_stop_s(v: f64, a: f64, b: f64) -> f64 {
        // Jerk −b for t1 then +b for t2: a1 = a − b·t1 ≤ 0 ends it at rest
        // when a1² = (a² + 2bv)/2, t1 = (a − a1)/b and t2 = −a1/b.
        let down = |v: f64, a: f64| {
            let sq = 0.5 * (a * a + 2.0 * b * v);
            let a1 = -sq.max(0.0).sqrt();
            (sq >= 0.0 && a >= a1).then(|| (a - 2.0 * a1) / b)
        };
        let t = [down(v, a), down(-v, -a)];
        t.into_iter().flatten().fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn one_joint_stops_in_closed_form() {
        // From 0.5 m/s at rest acceleration with jerk 5: 2·√(v/b).
        assert!((one_joint_stop_s(0.5, 0.0, 5.0) - 2.0 * 0.1f64.sqrt()).abs() < 1e-12);
        // Already decelerating at the rate that ends at rest: one phase.
        assert!((one_joint_stop_s(0.1, -1.0, 5.0) - 0.2).abs() < 1e-12);
        assert_eq!(one_joint_stop_s(0.0, 0.0, 5.0), 0.0);
        assert!((one_joint_stop_s(-0.5, 0.0, 5.0) - one_joint_stop_s(0.5, 0.0, 5.0)).abs() < 1e-15);
    }

    /// A stop from σ = 1 at plan time `t0` (s) that lasts `t` (s) with the
    /// shape `rate(u)` = (S′(u), S″(u)), σ = 1 − S(u): the largest joint
    /// |jerk| along it, q‴σ³ + 3q″σσ̇ + q′σ̈ with the signs as they are, as
    /// a share of the budget `budget(s)` at plan time s, sampled on 1 000
    /// steps.
    fn stop_peak_jerk(
        p: &triquint_shared::plan::Plan,
        t0: f64,
        t: f64,
        rate: impl Fn(f64) -> (f64, f64),
        budget: &dyn Fn(f64) -> f64,
    ) -> f64 {
        let steps = 1000;
        let dt = t / steps as f64;
        let (mut s, mut sigma, mut peak) = (t0, 1.0f64, 0.0f64);
        for k in 0..=steps {
            let u = k as f64 / steps as f64;
            let (s1, s2) = rate(u);
            let (sd, sdd) = (-s1 / t, -s2 / (t * t));
            let s_now = s.min(p.duration());
            let Some(js) = p.at(s_now) else {
                break;
            };
            let b = budget(s_now);
            for i in 0..3 {
                let j = js.jerk[i] * sigma.powi(3) + 3.0 * js.a[i] * sigma * sd + js.v[i] * sdd;
                peak = peak.max(j.abs() / b);
            }
            // Midpoint rule for σ and the plan time it advances.
            let (s1m, _) = rate((u + 0.5 / steps as f64).min(1.0));
            let sigma_mid = sigma - 0.5 * dt * s1m / t;
            s += sigma_mid * dt;
            sigma = (sigma - dt * s1m / t).max(0.0);
        }
        peak
    }

    /// The shortest stop of a shape within the jerk budget `budget(s)`
    /// from `t0` (bisection on its length; `None` if none up to 4 s).
    fn shortest_of_shape(
        p: &triquint_shared::plan::Plan,
        t0: f64,
        budget: &dyn Fn(f64) -> f64,
        rate: &dyn Fn(f64) -> (f64, f64),
    ) -> Option<f64> {
        let (mut lo, mut hi) = (0.01, 4.0);
        if stop_peak_jerk(p, t0, hi, rate, budget) > 1.0 {
            return None;
        }
        for _ in 0..30 {
            let mid = 0.5 * (lo + hi);
            if stop_peak_jerk(p, t0, mid, rate, budget) > 1.0 {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(hi)
    }

    /// Where the stop's length goes, at 40 instants of each committed plan
    /// (σ = 1, the plan's largest budget b): the ramp for the path ahead;
    /// the drives' shape (σ̈ bang-bang) held to each segment's budget along
    /// the path, from anywhere in the estimate margin (what drives checking
    /// the path could run, never longer than the ramp);
    /// the quintic smoothstep sized for that instant with the jerk's true signs
    /// (the best any sizing of this shape can do); σ̈ bang-bang (−c then
    /// +c′, switching at the best of nine fractions), sized the same way;
    /// and the lower bound on any stop (`--nocapture`).
    #[test]
    fn where_the_stop_length_goes() {
        use triquint_shared::protocol::segment_maxima::{inv_h, maxima};
        use triquint_shared::protocol::stop_ramp::budgets;
        let smooth = |u: f64| Quintic.rate(u);
        let drives = |u: f64| Bang(0.5).rate(u);
        for name in ["case1-spline", "case2-spline", "spiral-spline"] {
            let (p, c, w, r) = committed_rig(name);
            let c = &c;
            // Each segment's plan-time span (s, the ramps' own) and its
            // controlled stop budget.
            let spans: Vec<(f64, f64, f64)> = segment_spans_us(&w)
                .zip(&w)
                .map(|((a, e), s)| {
                    let [_, _, j] = maxima(&s.normalised_f32(), inv_h(s.duration_us));
                    let b = budgets(j, c.max_jerk, c.ceiling_jerk, c.override_cap)[0];
                    (a * 1e-6, e * 1e-6, b as f64)
                })
                .collect();
            let b = spans.iter().map(|x| x.2).fold(0.0, f64::max);
            let budget_at = |s: f64| {
                spans
                    .iter()
                    .find(|x| s <= x.1)
                    .or(spans.last())
                    .map_or(b, |x| x.2)
            };
            let total = p.duration();
            let n = 40;
            let mut sums = [0.0f64; 6];
            let mut counted = 0;
            for i in 1..n {
                let t0 = total * i as f64 / n as f64;
                let js = p.at(t0).unwrap();
                let bound = (0..3)
                    .map(|k| one_joint_stop_s(js.v[k], js.a[k], b))
                    .fold(0.0, f64::max);
                if bound < 1e-3 {
                    continue;
                }
                let dated = match r.dated(t0 * 1e6, false) {
                    0 => r.full_us[0],
                    u => u as f64 * UNIT_US as f64,
                } * 1e-6;
                let best_smooth = shortest_of_shape(&p, t0, &|_| b, &smooth).unwrap();
                // The drives' shape held to each segment's own budget, from
                // anywhere within the host's estimate margin of t0: what a
                // drive that checked the path it holds could run.
                let checked = [-1.0, -0.5, 0.0, 0.5, 1.0]
                    .map(|k| {
                        let from = (t0 + k * ESTIMATE_MARGIN_US * 1e-6).clamp(0.0, total);
                        shortest_of_shape(&p, from, &budget_at, &drives).unwrap()
                    })
                    .into_iter()
                    .fold(0.0, f64::max);
                // A stop of that length passes through no plan time beyond
                // t0 + checked (σ ≤ 1), nor does a shorter one: the largest
                // budget there bounds every such stop's jerk.
                let b_way = spans
                    .iter()
                    .filter(|&&(a, e, _)| e > t0 && a < t0 + checked)
                    .map(|x| x.2)
                    .fold(0.0, f64::max);
                let bound_way = (0..3)
                    .map(|k| one_joint_stop_s(js.v[k], js.a[k], b_way))
                    .fold(0.0, f64::max);
                // The drives' ramp keeps every stop from the window within
                // the segments' budgets, so the shortest that does is no
                // longer; nor is the lower bound longer than that shortest.
                assert!(
                    checked <= dated * 1.001,
                    "{name} at {t0}: {checked} > {dated}"
                );
                assert!(
                    bound <= bound_way && bound_way <= checked * 1.001,
                    "{name} at {t0}"
                );
                let best_bang = (1..10)
                    .filter_map(|k| {
                        let l = k as f64 / 10.0;
                        let bang = move |u: f64| {
                            if u < l {
                                (2.0 * u / l, 2.0 / l)
                            } else {
                                (2.0 * (1.0 - u) / (1.0 - l), -2.0 / (1.0 - l))
                            }
                        };
                        shortest_of_shape(&p, t0, &|_| b, &bang)
                    })
                    .fold(f64::INFINITY, f64::min);
                for (sum, x) in
                    sums.iter_mut()
                        .zip([dated, checked, best_smooth, best_bang, bound, bound_way])
                {
                    *sum += x;
                }
                counted += 1;
            }
            let m = sums.map(|x| x / counted as f64);
            eprintln!(
                "{name} (b {b:.3} m/s³, {counted} instants), mean stop: path-ahead ramp {:.3} s, its shape checked along the path {:.3} s, the quintic smoothstep sized for the instant {:.3} s, bang-bang sized for the instant {:.3} s, lower bound {:.3} s (within the budgets on its way {:.3} s)",
                m[0], m[1], m[2], m[3], m[4], m[5]
            );
        }
    }

    /// A stop shape S(u) on [0, 1] (σ = 1 − S for a stop from σ = 1): its
    /// largest S′ and |S″| on a cell [u0, u1], and S itself.
    trait Shape {
        fn s(&self, u: f64) -> f64;
        fn s1_max(&self, u0: f64, u1: f64) -> f64;
        fn s2_max(&self, u0: f64, u1: f64) -> f64;
        /// ∫σ over the stop, per unit of its length (at σ₀ = 1).
        fn distance(&self) -> f64;
        /// (S′(u), S″(u)).
        fn rate(&self, u: f64) -> (f64, f64);
    }

    /// The drives' transition shape, 10u³ − 15u⁴ + 6u⁵.
    struct Quintic;
    impl Shape for Quintic {
        fn s(&self, u: f64) -> f64 {
            u * u * u * (10.0 + u * (-15.0 + 6.0 * u))
        }
        fn s1_max(&self, u0: f64, u1: f64) -> f64 {
            let u = 0.5f64.clamp(u0, u1);
            30.0 * u * u * (1.0 - u) * (1.0 - u)
        }
        fn s2_max(&self, u0: f64, u1: f64) -> f64 {
            let f = |u: f64| (60.0 * u * (1.0 - u) * (1.0 - 2.0 * u)).abs();
            let r = 0.5 / 3f64.sqrt();
            let mut m = f(u0).max(f(u1));
            for p in [0.5 - r, 0.5 + r] {
                if (u0..=u1).contains(&p) {
                    m = m.max(f(p));
                }
            }
            m
        }
        fn distance(&self) -> f64 {
            0.5
        }
        fn rate(&self, u: f64) -> (f64, f64) {
            (
                30.0 * u * u * (1.0 - u) * (1.0 - u),
                60.0 * u * (1.0 - u) * (1.0 - 2.0 * u),
            )
        }
    }

    /// σ̈ bang-bang: S″ = 2/l up to u = l, then −2/(1 − l).
    struct Bang(f64);
    impl Shape for Bang {
        fn s(&self, u: f64) -> f64 {
            let l = self.0;
            if u < l {
                u * u / l
            } else {
                1.0 - (1.0 - u) * (1.0 - u) / (1.0 - l)
            }
        }
        fn s1_max(&self, u0: f64, u1: f64) -> f64 {
            let l = self.0;
            let u = l.clamp(u0, u1);
            if u < l {
                2.0 * u / l
            } else {
                2.0 * (1.0 - u) / (1.0 - l)
            }
        }
        fn s2_max(&self, u0: f64, u1: f64) -> f64 {
            let l = self.0;
            let mut m: f64 = 0.0;
            if u0 < l {
                m = m.max(2.0 / l);
            }
            if u1 > l {
                m = m.max(2.0 / (1.0 - l));
            }
            m
        }
        fn distance(&self) -> f64 {
            (1.0 + self.0) / 3.0
        }
        fn rate(&self, u: f64) -> (f64, f64) {
            let l = self.0;
            if u < l {
                (2.0 * u / l, 2.0 / l)
            } else {
                (2.0 * (1.0 - u) / (1.0 - l), -2.0 / (1.0 - l))
            }
        }
    }

    /// The shortest length of a transition of `shape` that keeps
    /// j·σ³ + 3a·σ·|σ̇| + v·|σ̈| within `budget` (the drives' rule in f64
    /// on a fine grid): over Δσ ∈ (0, `cap`] from σ = `cap` when `full`,
    /// else only the stop from σ = 1 (Δσ = 1).
    fn shape_ramp(
        shape: &dyn Shape,
        [v, a, j]: [f64; 3],
        budget: f64,
        cap: f64,
        full: bool,
    ) -> f64 {
        let bands: Vec<(f64, f64, f64)> = if full {
            (0..100)
                .map(|i| (cap, cap * i as f64 / 100.0, cap * (i + 1) as f64 / 100.0))
                .collect()
        } else {
            vec![(1.0, 1.0, 1.0)]
        };
        let mut t: f64 = 0.05;
        for (top, d0, d1) in bands {
            let m1 = d1.sqrt().min(1.0);
            let m2 = if d0 > 1.0 { 1.0 / d0 } else { 1.0 };
            for k in 0..400 {
                let (u0, u1) = (k as f64 / 400.0, (k + 1) as f64 / 400.0);
                let sigma = top - d0 * shape.s(u0);
                let room = (budget - j * sigma.powi(3)).max(1e-12);
                let b = 3.0 * a * sigma * shape.s1_max(u0, u1) * m1;
                let c = v * shape.s2_max(u0, u1) * m2;
                t = t.max((b + (b * b + 4.0 * room * c).sqrt()) / (2.0 * room));
            }
        }
        t
    }

    /// Why the drives' stop along the path is σ̈ bang-bang switching at ½
    /// (version 10) rather than the quintic smoothstep (before) or an
    /// earlier switch: each shape sized by the same rule in f64 (each
    /// piece's |q′|, |q″|, |q‴| with the worst signs, the segment's
    /// budget; the largest over the segments a stop from within the
    /// estimate margin passes through): the full ramp T_s, the mean stop
    /// at 40 instants of each committed plan, and every such stop, run
    /// from five starts across the margin, within its budgets
    /// (`--nocapture`).
    #[test]
    fn a_bang_bang_stop_under_the_drives_rule() {
        use triquint_shared::protocol::segment_maxima::{inv_h, overall, piece_maxima};
        use triquint_shared::protocol::stop_ramp::budgets;
        let shapes: [(&str, Box<dyn Shape>); 4] = [
            ("quintic", Box::new(Quintic)),
            ("bang-bang ½", Box::new(Bang(0.5))),
            ("bang-bang 0.4", Box::new(Bang(0.4))),
            ("bang-bang 0.3", Box::new(Bang(0.3))),
        ];
        for name in ["case1-spline", "case2-spline", "spiral-spline"] {
            let (p, c, w, _) = committed_rig(name);
            let c = &c;
            let margin = ESTIMATE_MARGIN_US * 1e-6;
            let total = p.duration();
            let mut line = format!("{name}:");
            let mut quintic_mean = 0.0;
            for (label, shape) in &shapes {
                // Each segment's span (s), budget and own stop ramp.
                let mut full: f64 = 0.0;
                let segs: Vec<(f64, f64, f64, f64)> = segment_spans_us(&w)
                    .zip(&w)
                    .map(|((a, e), s)| {
                        let pieces = piece_maxima(&s.normalised_f32(), inv_h(s.duration_us));
                        let [_, _, j] = overall(&pieces);
                        let b = budgets(j, c.max_jerk, c.ceiling_jerk, c.override_cap)[0] as f64;
                        let own = pieces
                            .iter()
                            .map(|t| shape_ramp(shape.as_ref(), t.map(f64::from), b, 1.0, false))
                            .fold(0.0, f64::max);
                        let whole = pieces
                            .iter()
                            .map(|t| {
                                let cap = c.override_cap as f64;
                                shape_ramp(shape.as_ref(), t.map(f64::from), b, cap, true)
                            })
                            .fold(0.0, f64::max);
                        full = full.max(whole);
                        (a * 1e-6, e * 1e-6, b, own)
                    })
                    .collect();
                let budget_at = |s: f64| {
                    segs.iter()
                        .find(|x| s <= x.1)
                        .or(segs.last())
                        .map_or(0.0, |x| x.2)
                };
                let (mut sum, mut n, mut worst): (f64, usize, f64) = (0.0, 0, 0.0);
                for i in 1..40 {
                    let t0 = total * i as f64 / 40.0;
                    // The largest own ramp over the segments a stop from the
                    // margin passes through; the window grows with it.
                    let mut ramp: f64 = 0.0;
                    loop {
                        let reach = t0 + margin + shape.distance() * ramp;
                        let next = segs
                            .iter()
                            .filter(|x| x.1 > t0 - margin && x.0 < reach)
                            .map(|x| x.3)
                            .fold(ramp, f64::max);
                        if next <= ramp {
                            break;
                        }
                        ramp = next;
                    }
                    let ramp = ramp.min(full);
                    for k in [-1.0, -0.5, 0.0, 0.5, 1.0] {
                        let from = (t0 + k * margin).clamp(0.0, total);
                        let peak = stop_peak_jerk(&p, from, ramp, |u| shape.rate(u), &budget_at);
                        worst = worst.max(peak);
                    }
                    sum += ramp;
                    n += 1;
                }
                let mean = sum / n as f64;
                if *label == "quintic" {
                    quintic_mean = mean;
                }
                line += &format!(
                    " {label}: T_s {full:.3} s, mean stop {mean:.3} s (×{:.2}), worst jerk {worst:.3} of the budget;",
                    mean / quintic_mean
                );
                assert!(worst <= 1.0 + 1e-3, "{name} {label}: {worst}");
                // Its |S″| peaks at 4 against the quintic's 5.77: the
                // velocity term, which dominates these stops, needs √(4/5.77)
                // of the length.
                if *label == "bang-bang ½" {
                    assert!(
                        mean < 0.9 * quintic_mean,
                        "{name}: {mean} against {quintic_mean}"
                    );
                }
            }
            eprintln!("{line}");
        }
    }
}
