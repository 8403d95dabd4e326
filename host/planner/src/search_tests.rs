//! Search tests: the paper's cases beat the paper, the optimum is a true
//! (local and multistart-global) optimum, plans pass the independent check,
//! and torque limits bind for real.

#[path = "../examples/support/closed_curve.rs"]
mod closed_curve;
#[path = "../examples/support/random_walk.rs"]
mod random_walk;

use std::path::Path;
use std::sync::Arc;

use crate::bounds::MAX_SEGMENT_S;
use crate::coarse_start::{COARSE_ABOVE_KNOTS, coarse_starts, window_start};
use crate::evolution::{EvolutionOptions, differential_evolution};
use crate::inner::{Method, ROUNDS};
use crate::problem::{Problem, Solution};
use crate::run_state::RunState;
use crate::search::{
    Multistart, REFERENCE_S_PER_SEGMENT, REFINE_TOL, SearchResult, global, multistart_with,
    relaxed_global, relaxed_shapes, start_points,
};
use crate::{Job, Options, Plan, check, plan};

fn job_problem(job: &Job) -> Result<Problem, crate::PlanError> {
    crate::planning::job_problem(job, &Arc::new(RunState::new(None)))
}

/// The problem of an example job (`examples/NAME`), for the core's unit tests.
pub(crate) fn example_problem(name: &str) -> Problem {
    job_problem(&example(name)).unwrap()
}

/// Uneven intervals summing to the problem's total time, so that interior
/// extrema matter.
pub(crate) fn uneven_intervals(p: &Problem) -> Vec<f64> {
    let n = p.knots.segments();
    let h: Vec<f64> = (0..n).map(|k| 1.0 + 0.3 * (k % 3) as f64).collect();
    let sum: f64 = h.iter().sum();
    h.iter().map(|x| x * p.total_time / sum).collect()
}

fn example(name: &str) -> Job {
    Job::load(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../examples")
            .join(name),
    )
    .unwrap()
}

/// The speed figures' closed curve of `n` via-points
/// (examples/scaling_paths.rs, to 1 nm as it writes them) with the default
/// limits.
fn closed_curve(n: usize, total_time: f64) -> Job {
    Job::builder()
        .points_mm(closed_curve::closed_curve_mm(n))
        .total_time(total_time)
        .build()
        .unwrap()
}

fn opts(starts: usize) -> Options {
    Options {
        starts,
        ..Options::default()
    }
}

fn max_jerk(p: &Plan) -> f64 {
    p.max_abs.jerk.iter().fold(0.0, |a, b| a.max(*b))
}

fn assert_checks(p: &Plan) {
    let rows = check(p).unwrap();
    for r in &rows {
        assert!(r.ok, "{}: {} > {}", r.what, r.value, r.bound);
    }
}

#[test]
fn paper_cases_beat_the_paper_and_pass_check() {
    for (file, bound, paper_reopt) in [
        ("paper-case1.toml", 0.34, 1.054),
        ("paper-case2.toml", 1.55, 2.661),
    ] {
        let p = plan(&example(file), &opts(4)).unwrap();
        let j = max_jerk(&p);
        eprintln!("{file}: max jerk {j:.6} m/s³ (paper re-optimised {paper_reopt})");
        assert!(j < bound, "{file}: {j}");
        assert_checks(&p);
        assert!(p.total_time_s <= 5.0 + 1e-12);
        // Whole microseconds.
        for h in &p.intervals_s {
            assert!((h * 1e6 - (h * 1e6).round()).abs() < 1e-6);
        }
    }
}

#[test]
fn paper_intervals_reoptimised_exactly() {
    // The paper's own intervals, coefficients re-optimised: 1.054 and 2.661 m/s³.
    for (file, h, expect) in [
        (
            "paper-case1.toml",
            vec![
                0.738, 0.238, 0.588, 0.370, 0.388, 0.623, 0.799, 0.267, 0.756,
            ],
            1.054,
        ),
        (
            "paper-case2.toml",
            vec![
                1.027, 0.229, 0.225, 0.347, 0.583, 0.455, 0.255, 0.212, 0.307, 1.359,
            ],
            2.661,
        ),
    ] {
        let p = job_problem(&example(file)).unwrap();
        let s = p
            .inner(&h, &p.zero_x(), Method::ViaRelaxation, ROUNDS)
            .unwrap();
        assert!((s.jerk - expect).abs() < 1e-3, "{file}: {}", s.jerk);
    }
}

/// Local optimality: moving time between any two segments never helps.
#[test]
fn perturbing_the_intervals_never_improves() {
    let job = example("paper-case1.toml");
    let p = job_problem(&job).unwrap();
    let best = global(&p, &opts(4)).unwrap().best;
    let n = best.h.len();
    let mut worst_gain: f64 = f64::NEG_INFINITY;
    for i in 0..n {
        for j in 0..n {
            if i == j {
                continue;
            }
            for eps in [1e-3, 1e-2] {
                let mut h = best.h.clone();
                h[i] += eps;
                h[j] -= eps;
                let s: Solution = p.inner(&h, &best.x, Method::ViaRelaxation, ROUNDS).unwrap();
                worst_gain = worst_gain.max(best.jerk - s.jerk);
            }
        }
    }
    assert!(
        worst_gain < 1e-7 * best.jerk,
        "a perturbation improved the jerk by {worst_gain:e}"
    );
}

/// Multistart agreement: independent starts driven to convergence agree with
/// the reported optimum, and none beats it.
#[test]
fn seeded_starts_agree_on_the_optimum() {
    let job = example("paper-case1.toml");
    let p = job_problem(&job).unwrap();
    let best = global(&p, &opts(4)).unwrap().best;
    let mut agree = 0;
    // On the jerk-only relaxation, as the search does: its optimum meets
    // every other limit of Case I, so it is the optimum.
    let relaxed = p.relaxed();
    for h in start_points(&p, 6, 7) {
        let s0 = relaxed
            .inner(&h, &p.zero_x(), Method::Direct, ROUNDS)
            .unwrap();
        let s = relaxed.local_search(&s0, 400, 1e-11);
        assert!(
            s.jerk >= best.jerk * (1.0 - 1e-6),
            "a start found {} < {}",
            s.jerk,
            best.jerk
        );
        if (s.jerk - best.jerk).abs() <= 1e-6 * best.jerk {
            agree += 1;
        }
    }
    eprintln!("{agree} of 6 seeded starts reach the optimum {}", best.jerk);
    assert!(agree >= 3, "only {agree} of 6 starts agree");
}

/// Torque binds for real: with 0.95 × the unconstrained peak torque as the
/// limit, a plan comes back, passes check, and its peak sits at the limit.
#[test]
fn torque_limit_binds() {
    let job = example("paper-case2.toml");
    let free = plan(&job, &opts(2)).unwrap();
    let peak = free.max_abs.torque.iter().fold(0.0, |a: f64, b| a.max(*b));
    let mut limits = job.limits().clone();
    limits.torque = 0.95 * peak;
    let job = job.to_builder().limits(limits).build().unwrap();
    let tight = plan(&job, &opts(2)).unwrap();
    assert_checks(&tight);
    let got = tight.max_abs.torque.iter().fold(0.0, |a: f64, b| a.max(*b));
    eprintln!("peak torque {got} at limit {}", job.limits().torque);
    assert!(
        got <= job.limits().torque * 1.001 && got >= 0.99 * job.limits().torque,
        "{got}"
    );
}

#[test]
fn min_time_finds_the_shortest_time() {
    let job = example("paper-case1.toml");
    let mut limits = job.limits().clone();
    limits.jerk = 1.0;
    let job = job
        .to_builder()
        .objective(crate::Objective::MinTime)
        .limits(limits)
        .build()
        .unwrap();
    let p = plan(&job, &opts(2)).unwrap();
    assert_checks(&p);
    // Jerk binds: any shorter time would exceed the jerk limit.
    let j = max_jerk(&p);
    eprintln!("min-time T = {} s at max jerk {j}", p.total_time_s);
    assert!(j <= 1.0 * (1.0 + 1e-9) && j > 0.99, "{j}");
    assert!(p.total_time_s < 5.0);
}

/// An independent global method: seeded differential evolution over the
/// intervals (`planner::evolution`), each candidate scored by the exact inner
/// problem. It shares nothing with the multistart SLP but the inner solve, and
/// must not beat the planner. DE needs thousands of evaluations, so the test
/// runs it on a five-point arc of Case II (four segments) at 2 s, where its
/// population converges within the test; `cargo run --release -p
/// triquint-planner --features evolution --example evolution` runs it on
/// a job.
#[test]
fn differential_evolution_finds_nothing_better() {
    let job = Job::from_toml(
        r#"
[limits]
total_time = 2.0
[path]
units = "mm"
points = [[-86, 83.66, 597.66], [-43, 97.74, 654.74], [0, 84.85, 684.85],
          [43, 54.74, 697.74], [86, -2.34, 683.66]]
"#,
    )
    .unwrap();
    let p = job_problem(&job).unwrap();
    let best = global(&p, &opts(8)).unwrap().best;
    let n = best.h.len();
    let o = EvolutionOptions {
        population: 6 * n,
        generations: 60,
        f: 0.6,
        cr: 0.9,
        seed: 2026,
        threads: 2,
    };
    let de = differential_evolution(&p, &o, &|_, _| {});
    eprintln!(
        "differential evolution ({} evaluations): {:.9} against the planner's {:.9}",
        de.evaluations, de.best, best.jerk
    );
    assert!(
        de.best >= best.merit(p.weight) * (1.0 - 1e-6),
        "differential evolution found {} < {}",
        de.best,
        best.jerk
    );
    // It is a real search: it must get near the optimum, not stall at random.
    assert!(
        de.best <= best.jerk * 1.01,
        "differential evolution stalled at {}",
        de.best
    );
}

#[test]
fn refined_agreement_keeps_the_optimum_of_every_start() {
    // The jerk-only relaxation (searched first) of the speed figures'
    // closed curve (examples/scaling_paths.rs) with 200 via-points, above
    // the knots where refined agreement applies: its first two coarse
    // results were 2.6e-3 apart in merit, refined 6e-7 (points unrounded;
    // at 1 nm the two searches end 8e-7 apart). Four starts, so that
    // the search without the refined agreement runs two more.
    let n = 200;
    let job = closed_curve(n, 0.25 * (n - 1) as f64);
    let p = job_problem(&job).unwrap().relaxed();
    let o = opts(4);
    let starts = start_points(&p, o.starts, o.seed);
    let early = multistart_with(&p, &starts, &o, true).unwrap();
    let all = multistart_with(&p, &starts, &o, false).unwrap();
    eprintln!(
        "refined agreement: {} starts, {} LPs, max jerk {:.9}; every start: {} starts, {} LPs, {:.9}",
        early.starts, early.lp_solves, early.best.jerk, all.starts, all.lp_solves, all.best.jerk
    );
    assert!(early.starts < all.starts, "the starts did not end early");
    assert!(
        early.best.merit(p.weight) <= all.best.merit(p.weight) * (1.0 + 1e-6),
        "{} > {}",
        early.best.jerk,
        all.best.jerk
    );
}

/// A regression job's problem (tests/regression/NAME.toml).
fn regression_problem(name: &str) -> Problem {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/regression/{name}.toml"));
    job_problem(&Job::load(&path).unwrap()).unwrap()
}

/// The relaxation's multistart at the reference time without the refined
/// agreement (its starts end only where two coarse results agree; a path
/// of at most 64 knots, which has no coarser path to start from), its best
/// intervals time-scaled to the problem's.
fn every_start_relaxed(p: &Problem, o: &Options) -> (usize, Vec<f64>) {
    assert!(p.knots.len() <= COARSE_ABOVE_KNOTS);
    let reference = p
        .relaxed()
        .retimed(REFERENCE_S_PER_SEGMENT * p.knots.segments() as f64);
    let starts = start_points(&reference, o.starts, o.seed);
    let all = multistart_with(&reference, &starts, o, false).unwrap();
    let alpha = p.total_time / all.best.h.iter().sum::<f64>();
    (all.starts, all.best.h.iter().map(|h| h * alpha).collect())
}

#[test]
fn a_relaxation_that_is_the_plan_runs_every_start() {
    // Lissajous-10: jerk alone binds, so the relaxation's optimum is the
    // plan and every start runs as before; its shapes for min-time end at
    // the first refined agreement.
    let p = regression_problem("lissajous-10");
    let o = Options::default();
    let plan = relaxed_global(&p, &o).unwrap();
    assert!(p.accept_relaxed(&plan.best).is_some());
    let (starts, h) = every_start_relaxed(&p, &o);
    assert_eq!(plan.starts, starts);
    for (a, b) in plan.best.h.iter().zip(&h) {
        assert!((a - b).abs() <= 1e-12 * b, "{a} against {b}");
    }
    assert!(!plan.ended_early && !plan.as_shapes);
    let shapes = relaxed_shapes(&p, &o).unwrap();
    eprintln!(
        "every start: {} starts, {} LPs; to the first refined agreement: {} starts, {} LPs",
        plan.starts, plan.lp_solves, shapes.starts, shapes.lp_solves
    );
    assert!(shapes.starts < plan.starts);
    assert!(shapes.lp_solves < plan.lp_solves);
    assert!(shapes.ended_early && shapes.as_shapes);
}

#[test]
fn a_relaxation_that_can_only_be_a_shape_is_its_coarse_results() {
    // The closed curve of 20 via-points in 5.7 s (the speed figures'
    // verdict): time-scaled to its jerk limit the relaxation's best still
    // breaks acceleration by more than the margin, so it only starts
    // min-time, and its shapes are the coarse results as they are. The
    // same starts refined in full cost more solves for the same jerk to
    // 1e-5.
    let p = job_problem(&closed_curve(20, 5.7)).unwrap();
    let o = Options::default();
    let r = relaxed_global(&p, &o).unwrap();
    assert!(r.loose && r.as_shapes);
    // Min-time's own relaxation gives the same shapes: the verdict's
    // shortest time is the job's at any time asked.
    let shapes = relaxed_shapes(&p, &o).unwrap();
    assert!(shapes.loose);
    assert_eq!(r.best.h, shapes.best.h);
    let t_ref = REFERENCE_S_PER_SEGMENT * p.knots.segments() as f64;
    let q = p.relaxed().retimed(t_ref);
    let full = multistart_with(&q, &start_points(&q, o.starts, o.seed), &o, true).unwrap();
    assert!(!full.loose);
    // Jerk scales as T⁻³: the loose best at the reference time.
    let loose_jerk = r.best.jerk * (p.total_time / t_ref).powi(3);
    eprintln!(
        "as a shape: {} LPs, jerk {loose_jerk}; in full: {} LPs, jerk {}",
        r.lp_solves, full.lp_solves, full.best.jerk
    );
    assert!(r.lp_solves < full.lp_solves);
    assert!((loose_jerk / full.best.jerk - 1.0).abs() < 1e-5);
    // Where the relaxation is the plan, it is refined in full.
    let case2 = example_problem("paper-case2.toml");
    let r2 = relaxed_global(&case2, &o).unwrap();
    assert!(case2.accept_relaxed(&r2.best).is_some() && !r2.loose);
}

#[test]
fn a_relaxation_that_is_not_the_plan_ends_at_the_first_refined_agreement() {
    // The closed curve of 10 via-points in 2.7 s (the speed figures'
    // verdict): acceleration binds at the relaxation's optimum, whose
    // shapes only start min-time: they are the ones min-time's own
    // relaxation gives, so the verdict and the job's shortest time agree.
    let p = job_problem(&closed_curve(10, 2.7)).unwrap();
    let o = Options::default();
    let r = relaxed_global(&p, &o).unwrap();
    assert!(p.accept_relaxed(&r.best).is_none());
    let (starts, _) = every_start_relaxed(&p, &o);
    assert!(r.starts < starts, "{} starts against {starts}", r.starts);
    assert!(r.ended_early && r.as_shapes);
    let shapes = relaxed_shapes(&p, &o).unwrap();
    assert_eq!(r.starts, shapes.starts);
    assert_eq!(r.best.h, shapes.best.h);
}

#[test]
fn a_multistart_that_goes_on_keeps_every_start_of_one_run_to_the_end() {
    // Lissajous-10's relaxation ends at a refined agreement after its
    // first two starts (the test above); going on from there runs the
    // rest, as a search without the refined agreement does.
    let p = regression_problem("lissajous-10").relaxed();
    let p = p.retimed(REFERENCE_S_PER_SEGMENT * p.knots.segments() as f64);
    let o = Options::default();
    let starts = start_points(&p, o.starts, o.seed);
    let mut search = Multistart::new(&p, starts.clone(), &o);
    search.run(&|_| Some(REFINE_TOL));
    let early = search.result().unwrap();
    search.run(&|_| None);
    let resumed = search.result().unwrap();
    let all = multistart_with(&p, &starts, &o, false).unwrap();
    assert!(early.ended_early && early.starts < all.starts);
    assert!(!resumed.ended_early);
    assert_eq!(resumed.starts, all.starts);
    assert!(
        resumed.best.merit(p.weight) <= all.best.merit(p.weight),
        "{} > {}",
        resumed.best.jerk,
        all.best.jerk
    );
    // It counts the solves of both results.
    assert!(resumed.lp_solves > early.lp_solves);
    assert!(resumed.lp_solves >= all.lp_solves);
}

#[test]
fn a_long_path_started_from_its_coarser_one_keeps_the_optimum() {
    // The relaxation of the speed figures' closed curve of 200 via-points
    // at its reference time: searched as `global` searches it (from the
    // optima of every fourth via-point's path) and from the usual starts
    // alone. Compared to the search's precision on this path, which is
    // coarser than 1e-6 (docs/planner-speed.md).
    let n = 200;
    assert!(n > COARSE_ABOVE_KNOTS);
    let job = closed_curve(n, 0.5 * (n - 1) as f64);
    let p = job_problem(&job).unwrap().relaxed();
    let o = Options::default();
    let coarse = relaxed_global(&p, &o).unwrap();
    let usual = no_worse_than_the_usual_starts(&p, &o, &coarse, "the coarser path");
    assert!(coarse.lp_solves < usual.lp_solves);
}

/// The usual starts' search of `p`, which `found` (searched from
/// `from`) must be no worse than, to the search's precision.
fn no_worse_than_the_usual_starts(
    p: &Problem,
    o: &Options,
    found: &SearchResult,
    from: &str,
) -> SearchResult {
    let usual = multistart_with(p, &start_points(p, o.starts, o.seed), o, true).unwrap();
    eprintln!(
        "from {from}: {} LPs, max jerk {:.12}; from the usual starts: {} LPs, {:.12}",
        found.lp_solves, found.best.jerk, usual.lp_solves, usual.best.jerk
    );
    assert!(
        found.best.merit(p.weight) <= usual.best.merit(p.weight) * (1.0 + 1e-5),
        "{} > {}",
        found.best.jerk,
        usual.best.jerk
    );
    usual
}

#[test]
fn a_long_walk_started_from_its_windows_keeps_the_optimum() {
    // The relaxation of the scaling benchmark's random walk of 200
    // via-points at its reference time: searched as `global` searches it
    // (from its windows' optima: its every fourth via-point does not trace
    // it) and from the usual starts alone.
    let n = 200;
    let job = Job::builder()
        .points_mm(random_walk::random_walk_mm(n))
        .total_time(0.5 * (n - 1) as f64)
        .build()
        .unwrap();
    let p = job_problem(&job).unwrap().relaxed();
    let o = Options::default();
    let (starts, solves) = window_start(&p, |windows| {
        windows
            .iter()
            .map(|w| {
                assert!(w.knots.len() < p.knots.len());
                let h = start_points(w, 1, o.seed).pop()?;
                w.inner(&h, &w.zero_x(), Method::Direct, ROUNDS)
            })
            .collect()
    })
    .expect("the walk's windows");
    assert_eq!(starts.len(), 1);
    assert_eq!(starts[0].len(), p.knots.segments());
    assert!(solves > 0);
    let total: f64 = starts[0].iter().sum();
    assert!((total - p.total_time).abs() <= 1e-9 * p.total_time);
    assert!(starts[0].iter().all(|&h| h >= p.h_min && h <= p.h_max));
    let windowed = relaxed_global(&p, &o).unwrap();
    no_worse_than_the_usual_starts(&p, &o, &windowed, "the windows");
}

#[test]
fn only_a_path_its_coarse_path_resolves_starts_from_it() {
    // A closed curve's every fourth via-point is within 5 % of its length;
    // a random walk's is half of it, and its coarse optimum says little
    // about where the walk's turns need time.
    let starts = |points: Vec<[f64; 3]>| {
        let job = Job::builder()
            .points_mm(points)
            .total_time(50.0)
            .build()
            .unwrap();
        let p = job_problem(&job).unwrap().relaxed();
        coarse_starts(&p, |c| {
            assert!(c.knots.len() < p.knots.len());
            relaxed_global(c, &Options::default()).map(|r| (r.shapes, r.lp_solves))
        })
    };
    let (curve, solves) = starts(closed_curve::closed_curve_mm(100)).expect("the curve's");
    assert!(solves > 0);
    for h in &curve {
        assert_eq!(h.len(), 99);
        assert!(h.iter().all(|&x| x > 0.0));
        assert!((h.iter().sum::<f64>() - 50.0).abs() < 1e-9);
    }
    assert!(starts(random_walk::random_walk_mm(100)).is_none());
    assert!(starts(closed_curve::closed_curve_mm(COARSE_ABOVE_KNOTS)).is_none());
}

#[test]
fn a_slow_long_path_keeps_every_segment_within_the_wire_limit() {
    // At 59 s a segment the time-scaled relaxation leaves [h_min, h_max]
    // and is searched at the job's time; the coarser path's intervals are
    // unbounded, so its starts must not carry that into the plan.
    let n = 100;
    plans_within_the_wire_limit(&closed_curve(n, 59.0 * (n - 1) as f64));
}

/// `job` plans, every segment within what the wire carries, and checks.
fn plans_within_the_wire_limit(job: &Job) {
    let p = plan(job, &Options::default()).unwrap();
    let longest = p.intervals_s.iter().fold(0.0, |a: f64, b| a.max(*b));
    assert!(longest <= MAX_SEGMENT_S, "a segment of {longest} s");
    assert_checks(&p);
}

#[test]
fn a_slow_plan_keeps_every_segment_within_the_wire_limit() {
    // Case II's 10 segments in 590 s: its shape time-scaled would want
    // segments over 60 s at the rest ends.
    let case2 = example("paper-case2.toml");
    let job = Job::builder()
        .points_m(case2.points_m().to_vec())
        .limits(crate::Limits {
            total_time: 590.0,
            ..case2.limits().clone()
        })
        .build()
        .unwrap();
    plans_within_the_wire_limit(&job);
}

#[test]
fn the_observer_is_offered_the_jobs_own_jerk() {
    // The relaxation is searched at 0.5 s a segment and time-scaled: the
    // best max jerk offered to the observer (what `Progress` shows) is at
    // the job's total time (Case II's points in 4.5 s, its reference 5 s:
    // 1.37 times the reference's jerk). At 4.5 s only jerk binds, so the
    // offered best is the search's optimum, to the solves' accuracy, or a
    // little above it.
    let case2 = example("paper-case2.toml");
    let job = Job::builder()
        .points_m(case2.points_m().to_vec())
        .total_time(4.5)
        .build()
        .unwrap();
    let state = Arc::new(RunState::new(None));
    let p = crate::planning::job_problem(&job, &state).unwrap();
    let r = global(&p, &opts(Options::default().starts)).unwrap();
    let offered = state.progress().best_max_jerk.expect("a best offered");
    eprintln!("offered {offered}, optimum {}", r.best.jerk);
    assert!(
        offered >= r.best.jerk * (1.0 - 1e-6) && offered <= r.best.jerk * 1.1,
        "offered {offered} against the optimum {}",
        r.best.jerk
    );
}
