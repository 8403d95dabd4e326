//! The library's surface: cancellation, time budget, thread independence,
//! evaluation of a plan, and errors as data.

use std::time::Duration;

use triquint_planner::bounds::MAX_POINTS;
use triquint_planner::files::parse_plan;
use triquint_planner::{
    CancelReason, Control, Job, Limit, Objective, Options, PlanError, PointKind, Progress, check,
    plan, plan_with,
};

fn case2() -> Job {
    Job::load(
        &std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-case2.toml"),
    )
    .unwrap()
}

#[test]
fn an_observer_can_cancel() {
    let mut calls = 0;
    let r = plan_with(&case2(), &Options::default(), &mut |p: &Progress| {
        calls += 1;
        assert!(p.lp_solves < 1_000_000);
        Control::Cancel
    });
    // Case II takes hundreds of LP solves: the first call comes before it
    // ends (and may be repeated while the search unwinds).
    assert!(calls >= 1);
    assert_eq!(
        r,
        Err(PlanError::Cancelled {
            reason: CancelReason::Observer
        })
    );
}

#[test]
fn an_observer_that_continues_sees_progress_and_the_same_plan() {
    let mut last = None;
    let mut watched = plan_with(&case2(), &Options::default(), &mut |p: &Progress| {
        last = Some(p.clone());
        Control::Continue
    })
    .unwrap();
    let mut direct = plan(&case2(), &Options::default()).unwrap();
    let last = last.expect("called at least once");
    assert!(last.lp_solves > 0);
    watched.solver.seconds = 0.0;
    direct.solver.seconds = 0.0;
    assert_eq!(watched, direct);
}

#[test]
fn the_time_budget_cancels() {
    let opts = Options {
        time_budget: Some(Duration::from_millis(1)),
        ..Options::default()
    };
    assert_eq!(
        plan(&case2(), &opts),
        Err(PlanError::Cancelled {
            reason: CancelReason::TimeBudget
        })
    );
}

#[test]
fn results_do_not_depend_on_threads() {
    let job = case2();
    let mut a = plan(
        &job,
        &Options {
            threads: 1,
            ..Options::default()
        },
    )
    .unwrap();
    let mut b = plan(
        &job,
        &Options {
            threads: 3,
            ..Options::default()
        },
    )
    .unwrap();
    a.solver.seconds = 0.0;
    b.solver.seconds = 0.0;
    assert_eq!(
        serde_json::to_string(&a).unwrap(),
        serde_json::to_string(&b).unwrap()
    );
}

#[test]
fn infeasible_is_data() {
    let job = case2().to_builder().total_time(3.0).build().unwrap();
    match plan(&job, &Options::default()) {
        Err(PlanError::Infeasible {
            limit,
            limit_value,
            reached,
            shortest_total_time: Some(t),
        }) => {
            assert_eq!(limit, Limit::Acceleration);
            assert_eq!(limit_value, 1.2);
            assert!(reached > limit_value);
            // Case II's shortest time is 3.49 s.
            assert!((3.4..3.6).contains(&t), "{t}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn bad_points_are_data() {
    let e = Job::builder()
        .objective(Objective::MinTime)
        .points_mm([[0.0, 0.0, 600.0], [0.0, 0.0, 610.0], [900.0, 0.0, 610.0]])
        .build()
        .unwrap_err();
    assert!(
        matches!(
            e,
            PlanError::OutsideWorkspace {
                point: PointKind::ViaPoint,
                index: 2,
                ..
            }
        ),
        "{e:?}"
    );
}

#[test]
fn a_path_longer_than_the_planner_takes_is_refused_at_once() {
    // 10 000 points on a small circle: each reachable, too many together.
    let pts: Vec<[f64; 3]> = (0..10_000)
        .map(|i| {
            let t = i as f64 * 1e-3;
            [50.0 * t.cos(), 50.0 * t.sin(), 600.0]
        })
        .collect();
    let e = Job::builder().points_mm(pts).build().unwrap_err();
    match &e {
        PlanError::InvalidJob { field, reason } => {
            assert_eq!(field, "path.points");
            assert!(reason.contains(&MAX_POINTS.to_string()), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    // The limit itself is accepted.
    let ok: Vec<[f64; 3]> = (0..MAX_POINTS)
        .map(|i| [0.0, 0.0, 550.0 + 100.0 * i as f64 / MAX_POINTS as f64])
        .collect();
    assert!(Job::builder().points_mm(ok).build().is_ok());
}

#[test]
fn plans_evaluate_and_round_trip_through_the_loader() {
    for n in 2..=5 {
        let pts: Vec<[f64; 3]> = (0..n)
            .map(|i| [10.0 * i as f64, 0.0, 600.0 + 5.0 * i as f64])
            .collect();
        let job = Job::builder().points_mm(pts).build().unwrap();
        let p = plan(&job, &Options::default()).unwrap();
        // The one loader reads every plan the planner writes.
        let back = parse_plan(&serde_json::to_string(&p).unwrap()).unwrap();
        assert_eq!(back, p);
        assert!(check(&p).unwrap().iter().all(|r| r.ok));
        let end = p.at(p.duration()).unwrap();
        assert!((end.q[0] - p.knots_m.last().unwrap()[0]).abs() < 1e-9);
        assert!(end.v.iter().all(|v| v.abs() < 1e-9));
    }
}
