//! Planner benchmarks, one for each row of the speed targets (docs/verification.md,
//! "Planner speed and scale"): both paper cases with the default search
//! (what `triquint plan` runs), Case II at minimum time, a point-to-point
//! min-time move (what `triquint move-to` runs), the infeasible verdict on
//! the 10-point closed curve, and the closed curve of 100 via-points.

#[path = "../examples/support/closed_curve.rs"]
mod closed_curve;

use std::path::Path;

use closed_curve::closed_curve_mm as curve;
use criterion::{Criterion, criterion_group, criterion_main};
use triquint_planner::{Job, Objective, Options, PlanError, plan};

fn example(case: &str) -> Job {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../examples/{case}.toml"));
    Job::load(&path).expect("example job")
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("planner");
    g.sample_size(10);
    for case in ["paper-case1", "paper-case2"] {
        let job = example(case);
        g.bench_function(case, |b| {
            b.iter(|| plan(&job, &Options::default()).expect("plan"))
        });
    }
    let min_time = example("paper-case2")
        .to_builder()
        .objective(Objective::MinTime)
        .build()
        .expect("job");
    g.bench_function("paper-case2-min-time", |b| {
        b.iter(|| plan(&min_time, &Options::default()).expect("plan"))
    });
    let p2p = Job::builder()
        .objective(Objective::MinTime)
        .points_mm([[-90.0, 90.0, 680.0], [-86.0, 83.66, 597.66]])
        .build()
        .expect("job");
    g.bench_function("point-to-point-min-time", |b| {
        b.iter(|| plan(&p2p, &Options::default()).expect("plan"))
    });
    let verdict = Job::builder()
        .points_mm(curve(10))
        .total_time(2.7)
        .build()
        .expect("job");
    g.bench_function("verdict-curve-10-at-2.7s", |b| {
        b.iter(|| match plan(&verdict, &Options::default()) {
            Err(e @ PlanError::Infeasible { .. }) => e,
            other => panic!("expected the infeasible verdict, got {other:?}"),
        })
    });
    let long = Job::builder()
        .points_mm(curve(100))
        .total_time(0.25 * 99.0)
        .build()
        .expect("job");
    g.bench_function("curve-100", |b| {
        b.iter(|| plan(&long, &Options::default()).expect("plan"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
