//! Free-knot plans on the in-process virtual hardware: a move of no more
//! segments than the drives queue runs to completion. (A longer one that
//! would not stream, `protocol::streaming`, the planner writes at the
//! fixed knots instead; see docs/planner-speed.md.)

use triquint_host::inprocess::simulate::{SimulateOptions, simulate};
use triquint_planner::{Job, KnotPlacement, Objective, Options, plan};

fn free_move(to_mm: [f64; 3]) -> triquint_planner::Plan {
    let job = Job::builder()
        .objective(Objective::MinTime)
        .knots(KnotPlacement::Free)
        .points_mm([[0.0, 0.0, 600.0], to_mm])
        .build()
        .unwrap();
    plan(&job, &Options::default()).unwrap()
}

#[test]
fn a_free_knot_move_within_the_queue_runs_to_completion() {
    // Only jerk binds: 7 segments.
    let short = free_move([30.0, 20.0, 620.0]);
    assert_eq!(short.segments.len(), 7);
    assert!(!short.free_knots.is_empty());
    let r = simulate(&short, &SimulateOptions::default()).unwrap();
    assert!(
        r.run.completed && r.run.faults.is_empty(),
        "{:?}",
        r.run.faults
    );
    assert!(
        r.run.max_error_m.iter().all(|e| *e < 1e-4),
        "{:?}",
        r.run.max_error_m
    );
}
