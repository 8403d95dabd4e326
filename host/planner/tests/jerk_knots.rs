//! Free knots for min-max-jerk: a knot added inside every segment, the
//! plan kept only when its max jerk is below the fixed knots'. Every plan
//! passes `check`, keeps the via-points as knots, and is never worse.

use std::path::Path;

use triquint_planner::files::parse_plan;
use triquint_planner::{Job, KnotPlacement, Objective, Options, Plan, check, plan};

fn paper(case: u32) -> Job {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../examples/paper-case{case}.toml"));
    Job::load(&path).unwrap()
}

fn max_jerk(p: &Plan) -> f64 {
    p.max_abs.jerk.iter().fold(0.0, |a: f64, &b| a.max(b))
}

/// The paper's cases: the free plan passes every check, its via-points are
/// knots (the loader proves it), the added knots are the odd ones between
/// them, and its max jerk is below the fixed knots' in the same time.
#[test]
fn the_paper_cases_get_a_lower_max_jerk_at_free_knots() {
    for case in [1, 2] {
        let fixed_job = paper(case);
        assert_eq!(fixed_job.objective(), Objective::MinMaxJerk);
        let fixed = plan(&fixed_job, &Options::default()).unwrap();
        let free_job = fixed_job
            .to_builder()
            .knots(KnotPlacement::Free)
            .build()
            .unwrap();
        let free = plan(&free_job, &Options::default()).unwrap();
        assert!(check(&free).unwrap().iter().all(|r| r.ok), "case {case}");
        assert_eq!(free.format, "triquint-plan/4");
        let n = fixed.segments.len();
        assert_eq!(free.segments.len(), 2 * n, "case {case}");
        assert_eq!(
            free.free_knots,
            (0..n).map(|k| 2 * k + 1).collect::<Vec<_>>()
        );
        for k in 0..=n {
            assert_eq!(free.knots_m[2 * k], fixed.knots_m[k], "case {case}");
        }
        assert!(free.total_time_s <= fixed_job.limits().total_time);
        let (a, b) = (max_jerk(&fixed), max_jerk(&free));
        assert!(b < 0.9 * a, "case {case}: {b} against {a}");
        let back = parse_plan(&serde_json::to_string(&free).unwrap()).unwrap();
        assert_eq!(back, free);
    }
}

/// Never worse: on seeded short paths (two to four via-points, fixed knots
/// on the straight lines between them) the free plan's max jerk is at most
/// the fixed one's, and it is the fixed plan itself when not lower.
#[test]
fn free_knots_never_raise_the_max_jerk() {
    let mut state: u64 = 41;
    let mut next = || {
        state = state
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (state >> 11) as f64 / (1u64 << 53) as f64
    };
    let mut lower = 0;
    for i in 0..6 {
        let points: Vec<[f64; 3]> = (0..2 + i % 3)
            .map(|_| {
                [
                    -80.0 + 160.0 * next(),
                    -80.0 + 160.0 * next(),
                    550.0 + 120.0 * next(),
                ]
            })
            .collect();
        let builder = Job::builder().points_mm(points).total_time(4.0);
        let fixed = plan(
            &builder.clone().knots(KnotPlacement::Fixed).build().unwrap(),
            &Options::default(),
        );
        let free = plan(
            &builder.knots(KnotPlacement::Free).build().unwrap(),
            &Options::default(),
        );
        // No plan at fixed knots: the free knots start from none either.
        let Ok(fixed) = fixed else {
            assert_eq!(free, fixed, "path {i}");
            continue;
        };
        let free = free.unwrap();
        assert!(check(&free).unwrap().iter().all(|r| r.ok), "path {i}");
        let (a, b) = (max_jerk(&fixed), max_jerk(&free));
        assert!(b <= a, "path {i}: {b} against {a}");
        if free.free_knots.is_empty() {
            assert_eq!(free.segments, fixed.segments, "path {i}");
        } else {
            assert!(b < a, "path {i}");
            lower += 1;
        }
    }
    assert!(lower >= 3, "only {lower} paths gained");
}
