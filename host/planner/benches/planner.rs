//! Planner benchmark: both paper cases, the default search (`triquint plan`).

use std::path::Path;

use criterion::{Criterion, criterion_group, criterion_main};
use triquint_host::job::Job;
use triquint_host::planner::{plan, search::SearchOptions};

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("planner");
    g.sample_size(10);
    for case in ["paper-case1", "paper-case2"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("../examples/{case}.toml"));
        let job = Job::load(&path).expect("example job");
        g.bench_function(case, |b| {
            b.iter(|| plan(&job, &SearchOptions::default()).expect("plan"))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
