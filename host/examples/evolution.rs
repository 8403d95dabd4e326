//! Differential evolution over the intervals of a job, against the planner:
//! an independent global check on problems too large for a test.
//!
//! cargo run --release -p triquint-host --example evolution -- JOB.toml [GENERATIONS] [POPULATION_PER_SEGMENT]

use std::path::Path;

use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use triquint_host::job::Job;
use triquint_host::planner::evolution::{EvolutionOptions, differential_evolution};
use triquint_host::planner::job_problem;
use triquint_host::planner::search::{SearchOptions, global};

fn main() -> Result<()> {
    let mut args = std::env::args().skip(1);
    let path = args
        .next()
        .context("usage: evolution JOB.toml [GENERATIONS] [POP/SEGMENT]")?;
    let generations: usize = args.next().map_or(Ok(300), |s| s.parse())?;
    let per_segment: usize = args.next().map_or(Ok(10), |s| s.parse())?;
    let job = Job::load(Path::new(&path)).map_err(|e| anyhow::anyhow!("{e}"))?;
    let p = job_problem(&job).map_err(|e| anyhow::anyhow!("{e}"))?;
    let planner = global(&p, &SearchOptions::default()).context("the planner found no plan")?;
    let o = EvolutionOptions {
        population: per_segment * p.knots.segments(),
        generations,
        f: 0.6,
        cr: 0.9,
        seed: 2026,
        threads: SearchOptions::default().threads,
    };
    let pb = ProgressBar::new(generations as u64);
    if let Ok(style) =
        ProgressStyle::with_template("DE [{bar:30}] {pos}/{len} generations, best {msg}")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    let de = differential_evolution(&p, &o, &|_, best| {
        pb.set_message(format!("{best:.9}"));
        pb.inc(1);
    });
    pb.finish_and_clear();
    let ours = planner.best.merit(p.weight);
    println!(
        "{path}: differential evolution {:.9} ({} evaluations) against the planner's {ours:.9}: {}",
        de.best,
        de.evaluations,
        if de.best < ours * (1.0 - 1e-6) {
            "DE FOUND BETTER"
        } else {
            "nothing better"
        }
    );
    Ok(())
}
