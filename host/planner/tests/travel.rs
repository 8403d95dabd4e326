//! The sliders' travel is a limit of the planner like velocity: a path
//! whose quintics would overshoot a slider's travel between knots (every
//! via-point inside it) plans inside the travel, proved by the exact
//! extremes and the independent check; a path inside the travel plans as
//! if there were none.

use triquint_planner::{Job, Options, Plan, check, plan};
use triquint_shared::Travel;
use triquint_shared::plan::figures::kinematics;

/// Up, across and back: slider 1 and 2's optimal quintics overshoot
/// knot 2 and slider 3's knot 4 by millimetres.
const POINTS_MM: [[f64; 3]; 5] = [
    [0.0, 0.0, 600.0],
    [0.0, 0.0, 640.0],
    [30.0, 0.0, 610.0],
    [0.0, 20.0, 630.0],
    [0.0, 0.0, 600.0],
];

/// A travel whose tops sit a millimetre or less above every via-point's
/// slider position: 253.22, 253.22 and 254.19 mm at most.
const NARROW: Travel = Travel {
    min: [0.05; 3],
    max: [0.254, 0.254, 0.255],
};

fn job(travel: Travel) -> Job {
    Job::builder()
        .points_mm(POINTS_MM)
        .total_time(4.0)
        .travel(travel)
        .build()
        .unwrap()
}

fn extremes(p: &Plan) -> ([f64; 3], [f64; 3]) {
    let k = kinematics(&p.segments);
    (k.position_min, k.position_max)
}

#[test]
fn a_path_that_would_overshoot_the_travel_between_knots_plans_inside_it() {
    let free = plan(&job(Travel::default()), &Options::default()).unwrap();
    // Every via-point is inside the narrow travel…
    for q in &free.knots_m {
        assert_eq!(NARROW.outside(q), None, "{q:?}");
    }
    // …but the plan without it overshoots its top on every slider.
    let (_, top) = extremes(&free);
    for j in 0..3 {
        assert!(top[j] > NARROW.max[j] + 5e-4, "slider {}: {top:?}", j + 1);
    }
    // Was `LeavesTravel`, exit 3: now the travel binds in the solve.
    let bound = plan(&job(NARROW), &Options::default()).unwrap();
    assert_eq!(bound.travel, NARROW);
    let (low, high) = extremes(&bound);
    for j in 0..3 {
        assert!(low[j] >= NARROW.min[j], "slider {}: {low:?}", j + 1);
        assert!(high[j] <= NARROW.max[j], "slider {}: {high:?}", j + 1);
    }
    // It binds: slider 2 and 3 end within a micrometre of their tops.
    assert!(NARROW.max[1] - high[1] < 1e-6, "{high:?}");
    assert!(NARROW.max[2] - high[2] < 1e-6, "{high:?}");
    // The independent check proves it (its travel rows among the rest).
    let rows = check(&bound).unwrap();
    let failed: Vec<_> = rows.iter().filter(|r| !r.ok).collect();
    assert!(failed.is_empty(), "{failed:?}");
    assert_eq!(rows.iter().filter(|r| r.what.contains("travel")).count(), 6);
    // Keeping inside costs jerk, never a limit.
    let jerk = |p: &Plan| p.max_abs.jerk.iter().fold(0.0, |a: f64, &b| a.max(b));
    assert!(jerk(&bound) > jerk(&free));
    assert!(jerk(&bound) <= bound.limits.jerk);
}

#[test]
fn a_path_inside_the_travel_plans_as_without_it() {
    // A travel just above the default plan's highest positions changes nothing.
    let free = plan(&job(Travel::default()), &Options::default()).unwrap();
    let (low, high) = extremes(&free);
    let snug = Travel {
        min: low.map(|x| x - 1e-6),
        max: high.map(|x| x + 1e-6),
    };
    let p = plan(&job(snug.clone()), &Options::default()).unwrap();
    assert_eq!(p.segments, free.segments);
    assert_eq!(p.travel, snug);
}
