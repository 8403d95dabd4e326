//! Input shaping that stays piecewise quintic: a plan convolved with a few
//! positive impulses (ZV, MZV, ZVD, EI, 2HUMP-EI for a frequency and damping
//! ratio, `shaper.rs`), one shaper for all three joints so the joint
//! path keeps its shape in time. Torque is not linear in q, and the path
//! between via-points changes: the shaped plan records the unshaped one and
//! the shaper (format 5), and `check` convolves again, compares, re-proves
//! torque and travel and reports how far the path leaves the via-points.

use triquint_shared::plan::shaping::{Shaping, Unshaped};
use triquint_shared::plan::{PLAN_FORMAT_SHAPED, Plan};

use triquint_shared::plan::Objective;
use triquint_shared::readable::readable;

use crate::check::{TORQUE_CHECK_SAMPLES, max_abs};
use crate::error::PlanError;
use crate::job::{Job, KNOT_SEGMENTS, KnotPlacement};
use crate::shaper::convolve;
use crate::streaming::{shortfall, streams, streams_with_margin};

pub use crate::shaper::{ConvolveError, Impulses, MAX_SHAPER_HZ};
pub use triquint_shared::plan::shaping::{DEFAULT_DAMPING, Shaper, ShaperSpec, UnknownShaper};

/// `plan` convolved with `spec`'s impulses: a format 5 plan that starts
/// where it starts and ends where it ends, the shaper's duration later,
/// with its maxima recomputed and the unshaped plan recorded. Its
/// total-time limit grows by the shaper's duration; every other limit, the
/// robot and the travel are the plan's, for `check` to prove again. Its
/// via-points are the first and the last: shaping moves the path off the
/// others (`check` reports how far). A plan already shaped is refused.
pub fn shape(plan: &Plan, spec: &ShaperSpec) -> Result<Plan, PlanError> {
    let invalid = |reason: String| PlanError::invalid("shaper", reason);
    if plan.shaping.is_some() {
        return Err(invalid("the plan is shaped already".into()));
    }
    let impulses = Impulses::for_spec(spec)?;
    let segments = convolve(&plan.segments, &impulses).map_err(|e| invalid(e.to_string()))?;
    let (Some(first), Some(last)) = (segments.first(), segments.last()) else {
        return Err(invalid(ConvolveError::Empty.to_string()));
    };
    let end = last
        .coeffs
        .map(|c| triquint_shared::quintic::eval_poly(&c, last.duration_s)[0]);
    let mut shaped = plan.clone();
    shaped.format = PLAN_FORMAT_SHAPED.to_string();
    shaped.intervals_s = segments.iter().map(|s| s.duration_s).collect();
    shaped.total_time_s = last.t0_s + last.duration_s - first.t0_s;
    shaped.limits.total_time += impulses.duration_s();
    shaped.knots_m = segments
        .iter()
        .map(|s| s.coeffs.map(|c| c[0]))
        .chain([end])
        .collect();
    shaped.free_knots = Vec::new();
    // The bound is the unshaped path's: shaping leaves the via-points.
    shaped.max_deviation_m = None;
    shaped.segments = segments;
    if let (Some(a), Some(b)) = (plan.via_points_m.first(), plan.via_points_m.last()) {
        shaped.via_points_m = vec![*a, *b];
    }
    shaped.max_abs = max_abs(&shaped, TORQUE_CHECK_SAMPLES)
        .map_err(|e| invalid(format!("the shaped plan leaves the workspace: {e}")))?;
    shaped.shaping = Some(Shaping {
        shaper: *spec,
        unshaped: Unshaped {
            via_points_m: plan.via_points_m.clone(),
            knots_m: plan.knots_m.clone(),
            free_knots: plan.free_knots.clone(),
            intervals_s: plan.intervals_s.clone(),
            total_time_s: plan.total_time_s,
            segments: plan.segments.clone(),
            max_abs: plan.max_abs.clone(),
            total_time_limit_s: plan.limits.total_time,
            retimed: None,
        },
    });
    Ok(shaped)
}

/// The job's plan shaped by `spec`, proven by `check` and keeping the
/// streaming rule. Each impulse adds a copy of every knot, so a plan that
/// streams can shape into one that does not; for a point-to-point move
/// whose segment count is the planner's choice, `replan` (the planner, for
/// a job without a shaper) gives the move again in fewer free-knot
/// segments, from 3 up to the first count whose shaped plan does not
/// stream, and the shortest shaped plan that streams is kept. A plan at
/// the job's own knots (a path's via-points) is slowed instead: `retime`
/// gives it with its intervals × s (None when that breaks a limit), and
/// the least s found whose shaped plan streams and passes `check` is kept
/// and recorded ([`slowed`]). Otherwise the verdict is
/// [`PlanError::Unstreamable`] naming the shaper.
pub(crate) fn job_shaped(
    job: &Job,
    plan: &Plan,
    spec: &ShaperSpec,
    replan: &mut dyn FnMut(&Job) -> Result<Plan, PlanError>,
    retime: &mut dyn FnMut(f64) -> Option<Plan>,
) -> Result<Plan, PlanError> {
    let first = proven(plan, spec)?;
    if shortfall(&first).is_none() {
        return Ok(first);
    }
    let counts_free = job.knot_placement() == KnotPlacement::Free
        && job.objective() == Objective::MinTime
        && job.knot_segments().is_none()
        && job.points_m().len() == 2;
    let mut best: Option<Plan> = None;
    if counts_free {
        for n in KNOT_SEGMENTS.0..plan.segments.len() {
            let Ok(fewer) = job.to_builder().shaper(None).knot_segments(n).build() else {
                continue;
            };
            let unshaped = match replan(&fewer) {
                Ok(p) => p,
                Err(e @ PlanError::Cancelled { .. }) => return Err(e),
                Err(_) => continue,
            };
            let Ok(s) = proven(&unshaped, spec) else {
                continue;
            };
            // More segments shape into more, shorter ones: the counts
            // above the first that does not stream are not tried.
            if shortfall(&s).is_some() {
                break;
            }
            if best
                .as_ref()
                .is_none_or(|b| s.total_time_s < b.total_time_s)
            {
                best = Some(s);
            }
        }
    }
    if best.is_none() && !counts_free && plan.free_knots.is_empty() {
        best = slowed(spec, retime);
    }
    match best {
        Some(s) => Ok(s),
        None => streams(&first).map(|()| first),
    }
}

/// Grid step of the slow-down search.
const SLOWDOWN_STEP: f64 = 0.02;
/// The largest slow-down tried (the job's total-time limit may stop it first).
const MAX_SLOWDOWN: f64 = 3.0;
/// Bisections between the last grid step that failed and the first that held.
const SLOWDOWN_BISECTIONS: usize = 7;
/// What a slowed plan's shortest run keeps above the rule's need (µs): the
/// drives' configuration carries the stop time in f32, so the session's
/// need can be a microsecond above the planner's, and the bisection would
/// otherwise stop on the edge.
const SLOWDOWN_MARGIN_US: u64 = 1_000;

/// The shaped plan of the job's plan slowed by the least s found (a grid
/// of [`SLOWDOWN_STEP`] from 1, then bisected) whose shaped plan streams
/// (by [`SLOWDOWN_MARGIN_US`]) and passes its check, with s recorded.
/// Short shaped segments come from shifted knots t_k + τ_i landing close
/// together; a uniform slow-down
/// spreads the knots apart (velocity ÷ s, acceleration ÷ s², jerk ÷ s³;
/// torque, travel and the total time checked by `retime`).
fn slowed(spec: &ShaperSpec, retime: &mut dyn FnMut(f64) -> Option<Plan>) -> Option<Plan> {
    let mut at = |s: f64| -> Option<Plan> {
        let unshaped = retime(s)?;
        let shaped = shape(&unshaped, spec).ok()?;
        if !streams_with_margin(&shaped, SLOWDOWN_MARGIN_US) {
            return None;
        }
        let mut shaped = proven(&unshaped, spec).ok()?;
        if let Some(r) = shaped.shaping.as_mut() {
            r.unshaped.retimed = Some(s);
        }
        Some(shaped)
    };
    let (mut lo, mut hi, mut best) = (1.0, 1.0, None);
    while best.is_none() && hi < MAX_SLOWDOWN {
        lo = hi;
        hi = 1.0 + SLOWDOWN_STEP * ((hi - 1.0) / SLOWDOWN_STEP).round() + SLOWDOWN_STEP;
        best = at(hi);
    }
    best.as_ref()?;
    for _ in 0..SLOWDOWN_BISECTIONS {
        let mid = 0.5 * (lo + hi);
        match at(mid) {
            Some(p) => {
                hi = mid;
                best = Some(p);
            }
            None => lo = mid,
        }
    }
    best
}

/// `plan` shaped by `spec`, every row of its `check` passing (velocity,
/// acceleration and jerk cannot grow; torque can).
fn proven(plan: &Plan, spec: &ShaperSpec) -> Result<Plan, PlanError> {
    let s = shape(plan, spec)?;
    let rows = crate::check::check(&s).map_err(|e| PlanError::invalid("shaper", e.to_string()))?;
    if let Some(bad) = rows.iter().find(|r| !r.ok) {
        return Err(PlanError::invalid(
            "shaper",
            format!(
                "the shaped plan fails its check: {} is {}, bound {}",
                bad.what,
                readable(bad.value),
                readable(bad.bound)
            ),
        ));
    }
    Ok(s)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::check::check;
    use crate::load::{parse_plan, unshaped};

    /// Paper Case I's min-max-jerk plan (the planner comes after this layer).
    fn case1() -> Plan {
        parse_plan(include_str!("../../../testdata/hil/paper-case1.json")).unwrap()
    }

    fn spec(shaper: Shaper) -> ShaperSpec {
        ShaperSpec {
            shaper,
            frequency_hz: 25.5,
            damping: 0.026,
        }
    }

    #[test]
    fn a_shaped_plan_is_a_c3_plan_within_the_original_bounds() {
        let p = case1();
        for shaper in Shaper::ALL {
            let imp = Impulses::for_spec(&spec(shaper)).unwrap();
            let s = shape(&p, &spec(shaper)).unwrap();
            assert_eq!(s.format, PLAN_FORMAT_SHAPED);
            assert!((s.total_time_s - p.total_time_s - imp.duration_s()).abs() < 1e-9);
            // The convolution, pointwise.
            for k in 0..=200 {
                let t = s.total_time_s * k as f64 / 200.0;
                let want: [f64; 3] = core::array::from_fn(|j| {
                    imp.times_s
                        .iter()
                        .zip(&imp.amplitudes)
                        .map(|(d, a)| a * p.at(t - d).unwrap().q[j])
                        .sum()
                });
                let got = s.at(t).unwrap().q;
                for j in 0..3 {
                    assert!((got[j] - want[j]).abs() < 1e-12, "{shaper:?} t {t}");
                }
            }
            // check proves it again: C3, rest at both ends, limits, travel,
            // records, the convolution from the record.
            let rows = check(&s).unwrap();
            assert!(
                rows.iter().all(|r| r.ok),
                "{shaper:?}: {:?}",
                rows.iter().filter(|r| !r.ok).collect::<Vec<_>>()
            );
            assert!(rows.iter().any(|r| r.what.starts_with("shaped = unshaped")));
            let dev = rows
                .iter()
                .find(|r| r.what.starts_with("via-point deviation"))
                .unwrap();
            // Off the via-points, by less than the platform moves in the shaper's time.
            assert!(dev.value > 0.0 && dev.value <= dev.bound, "{dev:?}");
            for j in 0..3 {
                assert!(s.max_abs.velocity[j] <= p.max_abs.velocity[j] * (1.0 + 1e-9));
                assert!(s.max_abs.acceleration[j] <= p.max_abs.acceleration[j] * (1.0 + 1e-9));
                assert!(s.max_abs.jerk[j] <= p.max_abs.jerk[j] * (1.0 + 1e-9));
            }
            // The record gives the plan back, and it round-trips through JSON.
            let mut base = unshaped(&s).unwrap();
            base.format = p.format.clone();
            assert_eq!(base, p);
            let back = parse_plan(&serde_json::to_string(&s).unwrap()).unwrap();
            assert_eq!(back, s);
        }
        let moving = parse_plan(include_str!(
            "../../../testdata/protocol/plans/case2-spline.json"
        ))
        .unwrap();
        assert!(shape(&moving, &spec(Shaper::Ei)).is_err());
        let twice = shape(&p, &spec(Shaper::Zv)).unwrap();
        assert!(shape(&twice, &spec(Shaper::Zv)).is_err());
    }

    #[test]
    fn inconsistent_shaped_plans_are_refused_or_fail_their_check() {
        let s = shape(&case1(), &spec(Shaper::Ei)).unwrap();
        let err = |p: &Plan| crate::load::validate_plan(p).unwrap_err().to_string();
        let mut p = s.clone();
        p.shaping = None;
        assert!(err(&p).contains("records its `shaping`"), "{}", err(&p));
        let mut p = s.clone();
        p.format = triquint_shared::plan::PLAN_FORMAT.into();
        assert!(err(&p).contains("has no `shaping`"), "{}", err(&p));
        let mut p = s.clone();
        p.shaping.as_mut().unwrap().shaper.frequency_hz = -3.0;
        assert!(
            err(&p).contains("shaping: shaper.frequency_hz"),
            "{}",
            err(&p)
        );
        let mut p = s.clone();
        p.shaping.as_mut().unwrap().unshaped.intervals_s.pop();
        assert!(err(&p).starts_with("shaping.unshaped: "), "{}", err(&p));
        let mut p = s.clone();
        p.limits.total_time += 0.1;
        assert!(err(&p).contains("plus the shaper's"), "{}", err(&p));
        // A record that is not what the plan was shaped from: another
        // shaper of the same duration, fails the convolution row; a moved
        // segment of the record fails the check of the unshaped plan.
        let row = |p: &Plan| {
            check(p)
                .unwrap()
                .into_iter()
                .find(|r| r.what.starts_with("shaped = unshaped"))
                .unwrap()
        };
        assert!(row(&s).ok);
        let mut p = s.clone();
        p.shaping.as_mut().unwrap().shaper.shaper = Shaper::Zvd;
        assert!(!row(&p).ok, "{:?}", row(&p));
        let mut p = s.clone();
        p.shaping.as_mut().unwrap().unshaped.segments[3].coeffs[1][5] += 1e-6;
        // The unshaped plan itself is then no longer C3: refused by check.
        assert!(check(&p).is_err());
    }

    /// A point-to-point move and its limits (m/s, m/s², m/s³, N·m).
    fn p2p(v: f64, a: f64, j: f64, torque: f64) -> crate::JobBuilder {
        let l = crate::Limits {
            velocity: v,
            acceleration: a,
            jerk: j,
            torque,
            total_time: 5.0,
        };
        Job::builder()
            .objective(Objective::MinTime)
            .limits(l)
            .points_mm([[-60.0, 40.0, 560.0], [60.0, -40.0, 640.0]])
    }

    /// Shaping multiplies a plan's knots by its impulses: the move at
    /// Table 3's limits and at a fast machine's, shaped by every shaper,
    /// streams, because the planner takes the move in fewer segments; the
    /// plan is still the convolution of its record, and no longer than the
    /// default segments' unshaped plan plus the shaper.
    #[test]
    fn shaped_point_to_point_moves_keep_the_streaming_rule() {
        use crate::{Options, plan};
        for limits in [(0.5, 1.2, 5.0, 10.0), (1.0, 10.0, 500.0, 1000.0)] {
            let job = |s| {
                p2p(limits.0, limits.1, limits.2, limits.3)
                    .shaper(s)
                    .build()
                    .unwrap()
            };
            let bare = plan(&job(None), &Options::default()).unwrap();
            for shaper in [Shaper::Zvd, Shaper::TwoHumpEi] {
                let sp = spec(shaper);
                // Its default segments, shaped, do not stream.
                assert!(shortfall(&shape(&bare, &sp).unwrap()).is_some());
                let s = plan(&job(Some(sp)), &Options::default()).unwrap();
                assert_eq!(shortfall(&s), None, "{limits:?} {shaper}");
                let rows = check(&s).unwrap();
                assert!(rows.iter().all(|r| r.ok), "{shaper}");
                let record = &s.shaping.as_ref().unwrap().unshaped;
                assert!(record.segments.len() < bare.segments.len());
                let imp = Impulses::for_spec(&sp).unwrap();
                // What streaming costs: the fewer segments' move is a little
                // slower than the default segments' one.
                let cost = (s.total_time_s - imp.duration_s()) / bare.total_time_s;
                println!(
                    "{limits:?} {shaper}: {} segments ({} unshaped), {:.4} s, unshaped {:.4} s against {:.4} s (x{cost:.3})",
                    s.segments.len(),
                    record.segments.len(),
                    s.total_time_s,
                    record.total_time_s,
                    bare.total_time_s
                );
                assert!((1.0..1.15).contains(&cost), "{limits:?} {shaper}: x{cost}");
            }
        }
    }

    /// Case II at a fast machine's limits: its path's knots are its
    /// via-points, so fewer segments are not an option. Shaped by 2HUMP-EI
    /// (four copies of every knot) its plan does not stream; the planner
    /// slows the plan until the shaped one does, and records by how much.
    /// Shaped by EI it streams as it is and is not slowed.
    #[test]
    fn a_path_at_its_via_points_is_slowed_until_its_shaped_plan_streams() {
        use crate::{Options, plan};
        let job = |s| {
            Job::from_toml(include_str!("../../../examples/paper-case2.toml"))
                .unwrap()
                .to_builder()
                .objective(Objective::MinTime)
                .limits(crate::Limits {
                    velocity: 2.0,
                    acceleration: 30.0,
                    jerk: 5000.0,
                    torque: 1000.0,
                    total_time: 5.0,
                })
                .shaper(s)
                .build()
                .unwrap()
        };
        let bare = plan(&job(None), &Options::default()).unwrap();
        let at = |shaper| ShaperSpec {
            shaper,
            frequency_hz: 0.8 * 25.6,
            damping: 0.062,
        };
        let ei = plan(&job(Some(at(Shaper::Ei))), &Options::default()).unwrap();
        assert_eq!(ei.shaping.unwrap().unshaped.retimed, None);
        let sp = at(Shaper::TwoHumpEi);
        assert!(shortfall(&shape(&bare, &sp).unwrap()).is_some());
        let s = plan(&job(Some(sp)), &Options::default()).unwrap();
        assert!(streams_with_margin(&s, SLOWDOWN_MARGIN_US));
        let rows = check(&s).unwrap();
        assert!(rows.iter().all(|r| r.ok), "{rows:?}");
        assert!(rows.iter().any(|r| r.what.starts_with("shaped = unshaped")));
        let record = &s.shaping.as_ref().unwrap().unshaped;
        let r = record.retimed.expect("recorded");
        assert!(r > 1.0 && r < MAX_SLOWDOWN, "{r}");
        // The same knots, every interval the planned one × r to the µs,
        // and slower everywhere.
        assert_eq!(record.knots_m, bare.knots_m);
        for (a, b) in record.intervals_s.iter().zip(&bare.intervals_s) {
            assert!((a - b * r).abs() <= 0.5e-6 + 1e-12, "{a} vs {b} × {r}");
        }
        for j in 0..3 {
            assert!(record.max_abs.velocity[j] <= bare.max_abs.velocity[j]);
            assert!(record.max_abs.jerk[j] <= bare.max_abs.jerk[j]);
        }
        let imp = Impulses::for_spec(&sp).unwrap();
        println!(
            "case II 2hump_ei {:.2} Hz: slowed x{r:.4}, {} segments, {:.4} s ({:.4} s unshaped, {:.4} s planned, x{:.4}), shaper {:.4} s",
            sp.frequency_hz,
            s.segments.len(),
            s.total_time_s,
            record.total_time_s,
            bare.total_time_s,
            record.total_time_s / bare.total_time_s,
            imp.duration_s()
        );
        // Loaded back, and a recorded factor that is no slow-down refused.
        let back = parse_plan(&serde_json::to_string(&s).unwrap()).unwrap();
        assert_eq!(back, s);
        let mut p = s.clone();
        p.shaping.as_mut().unwrap().unshaped.retimed = Some(0.5);
        let e = crate::load::validate_plan(&p).unwrap_err().to_string();
        assert!(e.contains("retimed"), "{e}");
    }

    /// A segment count the job sets is kept: shaped into a plan that does
    /// not stream, the job is refused naming the shaper.
    #[test]
    fn a_shaped_plan_that_cannot_stream_is_refused_naming_the_shaper() {
        let job = p2p(1.0, 10.0, 500.0, 1000.0)
            .knots(KnotPlacement::Free)
            .knot_segments(7)
            .shaper(Some(spec(Shaper::TwoHumpEi)))
            .build()
            .unwrap();
        match crate::plan(&job, &crate::Options::default()) {
            Err(
                e @ PlanError::Unstreamable {
                    shaper: Some(s), ..
                },
            ) => {
                assert_eq!(s, spec(Shaper::TwoHumpEi));
                let m = e.to_string();
                assert!(m.contains("shaped by 2hump_ei at 25.5 Hz"), "{m}");
                assert!(m.contains("fewer impulses"), "{m}");
            }
            other => panic!("not refused: {other:?}"),
        }
    }
}
