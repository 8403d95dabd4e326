//! The drives' configurations for a run: the same plan limits and robot for
//! every node, gains from the settings' bandwidth, and the stop ramps —
//! controlled stop T_s and quick stop T_q — long enough to bring the
//! largest velocity and acceleration of the motion to rest within the jerk
//! budget (`stop_time`, docs/protocol.md, Stopping); for a plan, the feed
//! override cap (`override_cap.rs`). A plan's maxima are computed from its
//! segments (exactly, `triquint_shared::plan::figures`), never read from
//! the `max_abs` it records: a tampered summary cannot shorten a stop.

use triquint_shared::plan::Plan;
use triquint_shared::plan::figures::kinematics;
use triquint_shared::protocol::DriveConfig;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::segment_maxima;
use triquint_shared::protocol::stop_ramp::stop_time;
use triquint_shared::{Limits, Robot};

use triquint_shared::plan::override_cap::{Maxima, override_scaling};

/// Why a plan's maxima cannot size the stop ramps.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum PlanConfigError {
    #[error("the plan's largest {field} is {value}, not a finite number ≥ 0")]
    Maxima { field: &'static str, value: f64 },
    #[error("the plan does not move (its velocity, acceleration and jerk are all zero)")]
    NoMotion,
}

/// The three nodes' configurations (node i + 1 drives axis i).
#[derive(Clone, Debug, PartialEq)]
pub struct DriveConfigs {
    pub nodes: [DriveConfig; 3],
    /// The controlled-stop ramp T_s every node is configured with (s).
    pub stop_time_s: f64,
    /// The feed-override cap every node is configured with (σ, 1–32).
    pub override_cap: f64,
}

impl DriveConfigs {
    /// For `plan`, from the exact continuous-time maxima of its segments
    /// (not the `max_abs` it records, which nothing here trusts).
    pub fn for_plan(plan: &Plan, settings: &DriveSettings) -> Result<Self, PlanConfigError> {
        let [v, a, j] = largest(plan)?;
        // The override cap, and the stop ramps sized for a stop from it.
        let s = override_scaling(plan, Maxima { v, a, j }, settings.max_override);
        let (robot, limits) = (&plan.robot, &plan.limits);
        // The drives' own rule over every segment: never shorter than the
        // ramp a drive sizes for the segments it holds.
        let r = segment_maxima::for_plan(plan, settings, &s);
        let (ts, tq) = (r.stop_time_s, r.quick_stop_time_s);
        Ok(Self {
            nodes: [0, 1, 2].map(|i| {
                let mut c = DriveConfig::new(robot, limits, i, settings, ts, tq);
                c.override_cap = r.cap as f32;
                c
            }),
            stop_time_s: ts,
            override_cap: r.cap,
        })
    }

    /// [`DriveConfigs::override_cap`] in per mille, as the drives' answers
    /// and the `+`/`-` keys count it.
    pub fn override_cap_permille(&self) -> u16 {
        (self.override_cap * 1000.0).round() as u16
    }

    /// For any motion within `limits` (before there is a plan, e.g. to
    /// configure drives so they report their position): the limits
    /// themselves as the maxima.
    pub fn for_limits(robot: &Robot, limits: &Limits, settings: &DriveSettings) -> Self {
        Self::from_maxima(
            robot,
            limits,
            settings,
            limits.velocity,
            limits.acceleration,
            limits.jerk,
        )
    }

    /// Stop ramps for a motion whose largest joint velocity, acceleration
    /// and jerk are `v`, `a`, `j`: T_s within the jerk limit (less the
    /// motion's own jerk, at least half of it), T_q at three times the limit.
    pub fn from_maxima(
        robot: &Robot,
        limits: &Limits,
        settings: &DriveSettings,
        v: f64,
        a: f64,
        j: f64,
    ) -> Self {
        let ts = stop_time(v, a, j, limits.jerk, 1.0);
        let tq = stop_time(v, a, 0.0, 3.0 * limits.jerk, 1.0);
        Self {
            nodes: [0, 1, 2].map(|i| DriveConfig::new(robot, limits, i, settings, ts, tq)),
            stop_time_s: ts,
            // No plan to scale: no override above 100 %.
            override_cap: 1.0,
        }
    }
}

/// Largest |v|, |a|, |jerk| over the three joints of `plan`'s segments.
fn largest(plan: &Plan) -> Result<[f64; 3], PlanConfigError> {
    let m = kinematics(&plan.segments);
    let mut out = [0.0f64; 3];
    for (k, (field, per_joint)) in [
        ("velocity", m.velocity),
        ("acceleration", m.acceleration),
        ("jerk", m.jerk),
    ]
    .into_iter()
    .enumerate()
    {
        for value in per_joint {
            if !(value.is_finite() && value >= 0.0) {
                return Err(PlanConfigError::Maxima { field, value });
            }
            out[k] = out[k].max(value);
        }
    }
    if out.iter().all(|x| *x == 0.0) {
        return Err(PlanConfigError::NoMotion);
    }
    Ok(out)
}

/// A plan committed under testdata/protocol/plans/ (tests).
#[cfg(test)]
pub(crate) fn committed_plan(name: &str) -> Plan {
    let text = std::fs::read_to_string(format!(
        "{}/../../testdata/protocol/plans/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .expect("a test plan");
    serde_json::from_str(&text).expect("a plan")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn limits_and_maxima_give_the_same_ramps_for_the_same_numbers() {
        let (robot, limits, s) = (
            Robot::default(),
            Limits::default(),
            DriveSettings::default(),
        );
        let a = DriveConfigs::for_limits(&robot, &limits, &s);
        let b = DriveConfigs::from_maxima(
            &robot,
            &limits,
            &s,
            limits.velocity,
            limits.acceleration,
            limits.jerk,
        );
        assert_eq!(a, b);
        // A slower motion stops sooner; never below the 50 ms floor.
        let c = DriveConfigs::from_maxima(&robot, &limits, &s, 0.01, 0.01, 0.1);
        assert!(c.stop_time_s < a.stop_time_s && c.stop_time_s >= 0.05);
        assert!(
            c.nodes
                .iter()
                .zip(&a.nodes)
                .all(|(x, y)| x.crc() != y.crc())
        );
    }

    fn plan_with(coeffs: [[f64; 6]; 3]) -> Plan {
        use triquint_shared::plan::{MaxAbs, Objective, PLAN_FORMAT, Segment, SolverStats};
        Plan {
            format: PLAN_FORMAT.into(),
            objective: Objective::MinMaxJerk,
            robot: Robot::default(),
            limits: Limits::default(),
            travel: Default::default(),
            ceilings: Default::default(),
            via_points_m: vec![],
            knots_m: vec![],
            free_knots: vec![],
            max_deviation_m: None,
            intervals_s: vec![1.0],
            total_time_s: 1.0,
            segments: vec![Segment {
                t0_s: 0.0,
                duration_s: 1.0,
                coeffs,
            }],
            max_abs: MaxAbs::default(),
            solver: SolverStats::default(),
            shaping: None,
        }
    }

    #[test]
    fn bad_maxima_are_named() {
        let rest = [[0.3, 0.0, 0.0, 0.0, 0.0, 0.0]; 3];
        assert_eq!(largest(&plan_with(rest)), Err(PlanConfigError::NoMotion));
        let mut c = rest;
        c[2][3] = f64::NAN;
        let e = largest(&plan_with(c)).unwrap_err();
        assert!(
            e.to_string().starts_with("the plan's largest velocity"),
            "{e}"
        );
        // q = 0.3 + t³/6 on joint 2: v ≤ ½, a ≤ 1, jerk 1 on [0, 1].
        let mut c = rest;
        c[1][3] = 1.0 / 6.0;
        assert_eq!(largest(&plan_with(c)), Ok([0.5, 1.0, 1.0]));
    }

    #[test]
    fn a_tampered_summary_changes_no_configuration() {
        // q = 0.3 + t³/6 − t⁴/8 + t⁵/40 on every joint: some motion.
        let plan = plan_with([[0.3, 0.0, 0.0, 1.0 / 6.0, -1.0 / 8.0, 1.0 / 40.0]; 3]);
        let s = DriveSettings::default();
        let honest = DriveConfigs::for_plan(&plan, &s).unwrap();
        let mut tampered = plan.clone();
        tampered.max_abs.velocity = [1e-9; 3];
        tampered.max_abs.acceleration = [1e-9; 3];
        tampered.max_abs.jerk = [1e-9; 3];
        assert_eq!(DriveConfigs::for_plan(&tampered, &s).unwrap(), honest);
        // The ramps are sized from the segments' own maxima: no shorter
        // than the drives' own for each segment, and longer than the
        // floor the tampered summary would give.
        use triquint_shared::protocol::segment_maxima::wire_ramps;
        let [v, a, j] = largest(&plan).unwrap();
        assert!(j > 0.1 && v > 0.0 && a > 0.0);
        let (jl, ceiling) = (plan.limits.jerk.min(s.ceilings.jerk), s.ceilings.jerk);
        for w in plan.wire_segments().unwrap() {
            let (own, _) =
                wire_ramps(&w, jl as f32, ceiling as f32, honest.override_cap as f32).unwrap();
            assert!(
                honest.stop_time_s >= own as f64,
                "{} < {own}",
                honest.stop_time_s
            );
        }
        assert!(honest.stop_time_s > 0.05, "{}", honest.stop_time_s);
    }

    #[test]
    fn case2_with_a_tampered_summary_gets_the_honest_ramps() {
        let plan = committed_plan("case2-spline");
        let s = DriveSettings::default();
        let honest = DriveConfigs::for_plan(&plan, &s).unwrap();
        let mut tampered = plan.clone();
        tampered.max_abs.velocity = [1e-9; 3];
        tampered.max_abs.acceleration = [1e-9; 3];
        let got = DriveConfigs::for_plan(&tampered, &s).unwrap();
        assert_eq!(got, honest);
        // Sized from the segments: the recorded summary would have given
        // the 50 ms floor, a stop far above the jerk limit.
        assert!(got.stop_time_s > 0.05, "{}", got.stop_time_s);
    }

    /// A machine whose override stops at 100 % (`drive.max_override = 1`):
    /// the cap is 1, every ramp is sized for a stop from σ = 1, and the
    /// look-ahead the drives' Underrun rule and `check` ask for shrinks
    /// with it (printed with `--nocapture`; docs/protocol.md, "Stop ramp").
    #[test]
    fn a_lower_max_override_shortens_the_ramps_and_the_look_ahead() {
        use triquint_shared::protocol::streaming::{QUEUE_CAPACITY, StreamRule};
        let free = DriveSettings::default();
        for name in ["case1-spline", "case2-spline", "spiral-spline"] {
            let plan = committed_plan(name);
            let a = DriveConfigs::for_plan(&plan, &free).unwrap();
            let mut rows = vec![];
            for max in [a.override_cap, 1.5, 1.2, 1.0] {
                let s = DriveSettings {
                    max_override: max,
                    ..free.clone()
                };
                let c = DriveConfigs::for_plan(&plan, &s).unwrap();
                let look = StreamRule::for_plan(&plan, &s, QUEUE_CAPACITY).unwrap();
                assert!(c.override_cap <= max.max(1.0) + 1e-12, "{name}");
                assert!(
                    c.nodes
                        .iter()
                        .all(|n| n.override_cap == c.override_cap as f32)
                );
                assert!(c.stop_time_s <= a.stop_time_s * (1.0 + 1e-9), "{name}");
                rows.push((c.override_cap, c.stop_time_s, look.lookahead_us));
            }
            let text: Vec<String> = rows
                .iter()
                .map(|(cap, ts, l)| {
                    format!(
                        "cap {cap:.3}: T_s {ts:.3} s, look-ahead {:.3} s",
                        *l as f64 * 1e-6
                    )
                })
                .collect();
            eprintln!("{name}: {}", text.join("; "));
            // From the plan's own cap (above 1 on all three) to 1: shorter,
            // by much where the cap, not the plan at σ = 1, sized the ramp.
            let (first, last) = (rows[0], rows[rows.len() - 1]);
            assert!(first.0 > 1.0 && last.0 == 1.0, "{name}: {rows:?}");
            assert!(last.1 < first.1 && last.2 < first.2, "{name}: {rows:?}");
            if name != "case2-spline" {
                assert!(last.1 < 0.8 * first.1, "{name}: {rows:?}");
            }
        }
    }

    /// The stop ramps of the committed test plans and of a move at the
    /// limits, by this rule and by the one that takes every peak at once
    /// (printed with `--nocapture`; docs/protocol.md, "Stop ramp").
    #[test]
    fn stop_ramps_are_no_longer_than_by_separate_peaks() {
        use triquint_shared::protocol::stop_ramp::stop_time_separate_peaks;
        let s = DriveSettings::default();
        let mut rows = vec![];
        for name in ["case1-spline", "case2-spline", "spiral-spline"] {
            let plan = committed_plan(name);
            let c = DriveConfigs::for_plan(&plan, &s).unwrap();
            let [v, a, j] = largest(&plan).unwrap();
            let old = stop_time_separate_peaks(v, a, j, plan.limits.jerk, c.override_cap);
            rows.push((name, c.override_cap, c.stop_time_s, old));
        }
        let l = Limits::default();
        let c = DriveConfigs::for_limits(&Robot::default(), &l, &s);
        let old = stop_time_separate_peaks(l.velocity, l.acceleration, l.jerk, l.jerk, 1.0);
        rows.push(("at the limits", 1.0, c.stop_time_s, old));
        // The drives' per-segment rule for one segment at the limits.
        let (coarse, _) = triquint_shared::protocol::stop_ramp::segment_ramps(
            l.velocity as f32,
            l.acceleration as f32,
            l.jerk as f32,
            l.jerk as f32,
            s.ceilings.jerk as f32,
            1.0,
        )
        .unwrap();
        eprintln!("at the limits, by the drives' per-segment rule: T_s {coarse:.3} s");
        assert!(coarse as f64 >= c.stop_time_s && (coarse as f64) < 1.2 * c.stop_time_s);
        for (name, cap, new, old) in rows {
            eprintln!(
                "{name}: cap {cap:.3}, T_s {new:.3} s (look-ahead at σ = 1 {:.3} s), by separate peaks {old:.3} s ({:.3} s), ratio {:.3}",
                0.5 * new,
                0.5 * old,
                new / old
            );
            assert!(new <= old * (1.0 + 1e-9) && new >= 0.05, "{name}");
        }
    }

    /// The ramp for the path ahead that stops carry (session/path_ramps.rs
    /// with its ±20 ms margin; here without): at each of 400 instants of
    /// the committed test plans, the largest of the drives' own
    /// per-piece ramps for a stop from σ ≤ 1 over the pieces a stop
    /// from there can pass through (those overlapping the next T_s/2 of
    /// plan time at σ = 1, which the Underrun rule makes every node hold), against the
    /// configured T_s; and how many segments end within 100 ms of plan
    /// time (`APPLY_LATE_MAX_US`), the ones a late node may already have
    /// dropped (printed with `--nocapture`; docs/protocol.md, "Stop ramp").
    #[test]
    fn stop_ramp_for_the_path_ahead() {
        use triquint_shared::protocol::segment_maxima::{PIECES, wire_ramps_and_units};
        let s = DriveSettings::default();
        for name in ["case1-spline", "case2-spline", "spiral-spline"] {
            let plan = committed_plan(name);
            let c = DriveConfigs::for_plan(&plan, &s).unwrap();
            let (cap, ts) = (c.override_cap as f32, c.stop_time_s);
            let jl = plan.limits.jerk.min(s.ceilings.jerk) as f32;
            let ceiling = s.ceilings.jerk as f32;
            // Each piece's plan-time span (s) and its own controlled ramp.
            let mut start = 0.0;
            let wire = plan.wire_segments().unwrap();
            let mut segs: Vec<(f64, f64, f64)> = Vec::new();
            for w in &wire {
                let a = s.ceilings.acceleration as f32;
                let (_, units) = wire_ramps_and_units(w, jl, ceiling, cap, a).unwrap();
                let piece = w.duration_us as f64 * 1e-6 / PIECES as f64;
                let at = |k: usize| start + piece * k as f64;
                for (k, (r, _)) in units.into_iter().enumerate() {
                    segs.push((at(k), at(k + 1), r as f64));
                }
                start = at(PIECES);
            }
            let total = start;
            let n = 400;
            let (mut sum, mut worst, mut best, mut shorter) = (0.0, 0.0f64, f64::MAX, 0);
            for i in 0..n {
                let t = total * i as f64 / n as f64;
                let ahead = segs
                    .iter()
                    .filter(|&&(a, b, _)| b > t && a < t + 0.5 * ts)
                    .map(|x| x.2)
                    .fold(0.0, f64::max);
                // Never longer than the configured ramp (every piece's
                // own is within it), never shorter than the piece it is in.
                let own = segs.iter().find(|&&(a, b, _)| a <= t && t < b).unwrap().2;
                assert!(ahead <= ts * (1.0 + 1e-6) && ahead >= own, "{name} at {t}");
                let r = ahead / ts;
                sum += r;
                worst = worst.max(r);
                best = best.min(r);
                shorter += usize::from(r < 0.99);
            }
            let ends: Vec<f64> = wire
                .iter()
                .scan(0.0, |t, w| {
                    *t += w.duration_us as f64 * 1e-6;
                    Some(*t)
                })
                .collect();
            let late = ends
                .iter()
                .map(|&end| {
                    ends.iter()
                        .filter(|&&e| e > end - 0.1 * cap as f64 && e <= end)
                        .count()
                })
                .max()
                .unwrap();
            eprintln!(
                "{name}: T_s {ts:.3} s over {} segments; the path ahead's ramp / T_s at {n} instants: mean {:.3}, min {best:.3}, max {worst:.3}, below 0.99 at {shorter}; at most {late} segments end within 100 ms at the cap {cap:.3}",
                wire.len(),
                sum / n as f64,
            );
        }
    }

    /// What bounds the drives' stop ramp on the committed test plans: the
    /// rule now (each joint's maxima on each of the 4 pieces of a
    /// segment) against the same f32 node rule over one triple per
    /// segment (v, a, j over the whole segment and its three joints, the
    /// rule before), over each joint's sampled maxima on K pieces and at
    /// each sampled instant, all with the segment's own budgets; and a
    /// jerk-limited stop from the plan's peak joint speed under its
    /// acceleration and jerk limits (printed with `--nocapture`;
    /// docs/protocol.md, "Stop ramp").
    #[test]
    fn stop_ramp_by_pieces_and_instants() {
        use triquint_shared::protocol::segment_maxima::{inv_h, maxima};
        use triquint_shared::protocol::stop_ramp::{budgets, segment_ramp};
        let s = DriveSettings::default();
        for name in ["case1-spline", "case2-spline", "spiral-spline"] {
            let plan = committed_plan(name);
            let c = DriveConfigs::for_plan(&plan, &s).unwrap();
            let cap = c.override_cap as f32;
            let jl = plan.limits.jerk.min(s.ceilings.jerk) as f32;
            let ceiling = s.ceilings.jerk as f32;
            // K = 1, 2, 4, 16 pieces, then every one of 400 instants.
            let ks = [1usize, 2, 4, 16, 400];
            let mut t = [0.0f32; 5];
            let mut one = 0.0f32;
            let n = 400;
            for w in plan.wire_segments().unwrap() {
                let b = w.normalised_f32();
                let ih = inv_h(w.duration_us) as f64;
                let [v, a, j] = maxima(&b, ih as f32);
                let bs = budgets(j, jl, ceiling, cap);
                one = one.max(segment_ramp(v, a, j, bs, cap).unwrap()[0]);
                for c in &b {
                    let c = c.map(|x| x as f64);
                    let at = |i: usize| {
                        let u = i as f64 / n as f64;
                        let d1 = c[1]
                            + u * (2.0 * c[2]
                                + u * (3.0 * c[3] + u * (4.0 * c[4] + u * 5.0 * c[5])));
                        let d2 =
                            2.0 * c[2] + u * (6.0 * c[3] + u * (12.0 * c[4] + u * 20.0 * c[5]));
                        let d3 = 6.0 * c[3] + u * (24.0 * c[4] + u * 60.0 * c[5]);
                        [d1.abs() * ih, d2.abs() * ih * ih, d3.abs() * ih * ih * ih]
                    };
                    let samples: Vec<[f64; 3]> = (0..=n).map(at).collect();
                    for (k, tk) in ks.iter().zip(t.iter_mut()) {
                        for p in 0..*k {
                            let m = samples[p * n / k..=(p + 1) * n / k]
                                .iter()
                                .fold([0.0f64; 3], |m, x| {
                                    [m[0].max(x[0]), m[1].max(x[1]), m[2].max(x[2])]
                                });
                            let [v, a, j] = m.map(|x| x as f32);
                            *tk = tk.max(segment_ramp(v, a, j, bs, cap).unwrap()[0]);
                        }
                    }
                }
            }
            let [v, _, _] = largest(&plan).unwrap();
            let (am, jm) = (plan.limits.acceleration, plan.limits.jerk);
            let optimal = if v >= am * am / jm {
                v / am + am / jm
            } else {
                2.0 * (v / jm).sqrt()
            };
            let now = c.stop_time_s;
            eprintln!(
                "{name}: T_s now {now:.3} s, by one triple per segment {one:.3} s (x{:.3}); sampled per joint on 1/2/4/16 pieces {:.3}/{:.3}/{:.3}/{:.3} s; per instant {:.3} s (x{:.3}); jerk-limited stop from v {v:.3} m/s {optimal:.3} s (now x{:.2}, per instant x{:.2})",
                now / one as f64,
                t[0],
                t[1],
                t[2],
                t[3],
                t[4],
                t[4] as f64 / now,
                now / optimal,
                t[4] as f64 / optimal
            );
            // The exact maxima on 4 pieces are the sampled ones' bound,
            // never above one triple per segment; nested pieces never
            // lengthen the ramp; none beats the jerk-limited stop.
            assert!(t[2] as f64 <= now * (1.0 + 1e-6), "{name}");
            assert!(
                now <= one as f64 * (1.0 + 1e-6) && t[0] <= one * (1.0 + 1e-6),
                "{name}"
            );
            for k in 2..4 {
                assert!(t[k] <= t[k - 1] * (1.0 + 1e-6), "{name} {k}");
            }
            assert!(
                t[4] <= t[3] * (1.0 + 1e-6) && t[4] as f64 > optimal,
                "{name}"
            );
        }
    }
}
