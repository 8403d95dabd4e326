//! Planner benchmarks: both paper cases with the default search (what
//! `triquint plan` runs), and a point-to-point min-time move (what
//! `triquint move-to` runs).

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use triquint_planner::{Job, Objective, Options, plan};

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("planner");
    g.sample_size(10);
    for case in ["paper-case1", "paper-case2"] {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../../examples/{case}.toml"));
        let job = Job::load(&path).expect("example job");
        g.bench_function(case, |b| {
            b.iter(|| plan(&job, &Options::default()).expect("plan"))
        });
    }
    let p2p = Job::builder()
        .objective(Objective::MinTime)
        .points_mm([[-90.0, 90.0, 680.0], [-86.0, 83.66, 597.66]])
        .build()
        .expect("job");
    g.bench_function("point-to-point-min-time", |b| {
        b.iter(|| plan(&p2p, &Options::default()).expect("plan"))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
