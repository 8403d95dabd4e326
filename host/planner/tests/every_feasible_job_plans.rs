//! Seeded random jobs in the workspace and the travel (2, 3, 4 and 5–12 via-points, both
//! objectives, several total times): each either plans and passes the
//! independent check, or is infeasible with a shortest total time that is
//! right — the job plans at 1.01 × that time and is infeasible at 0.99 × it.

use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_planner::{Job, Objective, Options, PlanError, check, plan};

/// Jobs per test (200 in all); four tests run in parallel.
const JOBS: usize = 50;
const TOTAL_TIMES: [f64; 4] = [0.6, 1.2, 2.5, 5.0];

fn opts() -> Options {
    Options {
        starts: 2,
        threads: 1,
        ..Options::default()
    }
}

/// A job of `n` reachable via-points (mm), each within 60 mm of the last.
fn random_job(rng: &mut ChaCha8Rng, n: usize, objective: Objective, total_time: f64) -> Job {
    loop {
        let mut pts = vec![[
            rng.random_range(-90.0..90.0),
            rng.random_range(-90.0..90.0),
            rng.random_range(540.0..690.0),
        ]];
        while pts.len() < n {
            let p: [f64; 3] = pts[pts.len() - 1];
            let step = if n <= 2 { 150.0 } else { 60.0 };
            pts.push([
                (p[0] + rng.random_range(-step..step)).clamp(-100.0, 100.0),
                (p[1] + rng.random_range(-step..step)).clamp(-100.0, 100.0),
                (p[2] + rng.random_range(-step..step)).clamp(520.0, 700.0),
            ]);
        }
        let job = Job::builder()
            .objective(objective)
            .total_time(total_time)
            .points_mm(pts)
            .build();
        match job {
            Ok(job) => return job,
            Err(PlanError::OutsideWorkspace { .. } | PlanError::OutsideTravel { .. }) => continue,
            Err(e) => panic!("{e}"),
        }
    }
}

fn assert_passes_check(job: &Job, p: &triquint_planner::Plan) {
    let rows = check(p).unwrap_or_else(|e| panic!("{job:?}: the plan does not load: {e}"));
    for r in rows {
        assert!(r.ok, "{job:?}: {} = {} > {}", r.what, r.value, r.bound);
    }
    assert!(p.total_time_s <= job.limits().total_time * (1.0 + 1e-12));
}

/// Plans `count` jobs; returns (planned, infeasible).
fn run(seed: u64, points: impl Fn(&mut ChaCha8Rng) -> usize) -> (usize, usize) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut planned, mut infeasible) = (0, 0);
    for i in 0..JOBS {
        let n = points(&mut rng);
        let objective = if i % 2 == 0 {
            Objective::MinTime
        } else {
            Objective::MinMaxJerk
        };
        // Longer paths get proportionally more time, so that some plan.
        let t = TOTAL_TIMES[(i / 2) % TOTAL_TIMES.len()] * (n as f64 / 3.0).max(1.0);
        let job = random_job(&mut rng, n, objective, t);
        let clock = std::time::Instant::now();
        let r = plan(&job, &opts());
        if std::env::var_os("PROP_DEBUG").is_some() {
            eprintln!(
                "{n} {objective:?} {t}: {:.2} s {}",
                clock.elapsed().as_secs_f64(),
                r.as_ref().map_or_else(|e| e.to_string(), |_| "ok".into())
            );
        }
        match r {
            Ok(p) => {
                assert_passes_check(&job, &p);
                planned += 1;
            }
            Err(PlanError::Infeasible {
                shortest_total_time: Some(shortest),
                ..
            }) => {
                assert!(shortest > t, "{job:?}: shortest {shortest} ≤ {t}");
                let longer = job
                    .to_builder()
                    .total_time(1.01 * shortest)
                    .build()
                    .unwrap();
                let p = plan(&longer, &opts())
                    .unwrap_or_else(|e| panic!("{job:?}: at 1.01 × {shortest} s: {e}"));
                assert_passes_check(&longer, &p);
                let shorter = job
                    .to_builder()
                    .total_time(0.99 * shortest)
                    .build()
                    .unwrap();
                let r = plan(&shorter, &opts());
                assert!(
                    matches!(r, Err(PlanError::Infeasible { .. })),
                    "{job:?}: at 0.99 × {shortest} s: {r:?}"
                );
                infeasible += 1;
            }
            Err(e) => panic!("{job:?}: {e}"),
        }
    }
    eprintln!("seed {seed}: {planned} planned, {infeasible} infeasible with a right shortest time");
    (planned, infeasible)
}

#[test]
fn two_points() {
    let (planned, _) = run(2, |_| 2);
    assert!(planned > JOBS / 4);
}

#[test]
fn three_points() {
    let (planned, _) = run(3, |_| 3);
    assert!(planned > JOBS / 4);
}

#[test]
fn four_points() {
    let (planned, _) = run(4, |_| 4);
    assert!(planned > JOBS / 4);
}

#[test]
fn five_to_twelve_points() {
    let (planned, _) = run(5, |r| r.random_range(5..=12));
    assert!(planned > JOBS / 4);
}
