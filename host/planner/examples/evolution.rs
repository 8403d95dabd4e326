//! Differential evolution over the intervals of a job, against the planner:
//! an independent global check on problems too large for a test.
//!
//! cargo run --release -p triquint-planner --features evolution --example evolution -- JOB.toml [GENERATIONS] [POPULATION_PER_SEGMENT]

use std::path::Path;
use std::process::ExitCode;

use triquint_planner::evolution::compare;
use triquint_planner::{Job, Options};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(path) = args.first() else {
        eprintln!("usage: evolution JOB.toml [GENERATIONS] [POP/SEGMENT]");
        return ExitCode::from(2);
    };
    let number = |i: usize, default: usize| args.get(i).map_or(Some(default), |s| s.parse().ok());
    let (Some(generations), Some(per_segment)) = (number(1, 300), number(2, 10)) else {
        eprintln!("evolution: GENERATIONS and POP/SEGMENT are whole numbers");
        return ExitCode::from(2);
    };
    let result = Job::load(Path::new(path)).and_then(|job| {
        compare(
            &job,
            generations,
            per_segment,
            &Options::default(),
            &|g, best| {
                if g % 10 == 0 {
                    eprintln!("generation {g}: best {best:.9}");
                }
            },
        )
    });
    match result {
        Ok(c) => {
            let de = &c.evolution;
            println!(
                "{path}: differential evolution {:.9} ({} evaluations) against the planner's {:.9}: {}",
                de.best,
                de.evaluations,
                c.search_best,
                if de.best < c.search_best * (1.0 - 1e-6) {
                    "DE FOUND BETTER"
                } else {
                    "nothing better"
                }
            );
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("evolution: {e}");
            ExitCode::from(2)
        }
    }
}
