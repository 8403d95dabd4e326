//! Differential evolution over the intervals: a global method independent of
//! the multistart search, used to check it. DE/rand/1/bin on weights
//! w ∈ [0.05, 1]ⁿ with h = T·w/Σw; every candidate is scored by the exact
//! inner problem at its intervals, so it shares nothing with the search but
//! that solve. Generations are synchronous (trials built from one population,
//! then selected), so the result does not depend on the thread count.

use std::sync::Arc;

use crate::error::PlanError;
use crate::inner::{Method, ROUNDS};
use crate::job::Job;
use crate::options::Options;
use crate::planning::job_problem;
use crate::problem::Problem;
use crate::run_state::RunState;
use crate::search::{SplitMix, global};
use crate::workers::parallel;

/// Size and seed of a run.
#[derive(Clone, Debug)]
pub struct EvolutionOptions {
    pub population: usize,
    pub generations: usize,
    /// Differential weight F and crossover rate CR.
    pub f: f64,
    pub cr: f64,
    pub seed: u64,
    pub threads: usize,
}

/// The best candidate found.
#[derive(Clone, Debug)]
pub struct Evolution {
    /// Its merit (max jerk, plus the priced violation of the other limits).
    pub best: f64,
    pub h: Vec<f64>,
    pub evaluations: usize,
}

/// Differential evolution against the planner's global search on one job,
/// both at the job's total time, before rounding to whole microseconds.
#[derive(Clone, Debug)]
pub struct Comparison {
    pub evolution: Evolution,
    /// The search's optimum (merit, as [`Evolution::best`]).
    pub search_best: f64,
}

/// Runs the planner's search and DE (with `population_per_segment` ×
/// segments candidates) on a job; `report(generation, best)` after each
/// generation.
pub fn compare(
    job: &Job,
    generations: usize,
    population_per_segment: usize,
    opts: &Options,
    report: &dyn Fn(usize, f64),
) -> Result<Comparison, PlanError> {
    let p = job_problem(job, &Arc::new(RunState::new(opts.time_budget)))?;
    let search =
        global(&p, opts).ok_or_else(|| PlanError::Solver("the search found no solution".into()))?;
    let o = EvolutionOptions {
        population: population_per_segment * p.knots.segments(),
        generations,
        f: 0.6,
        cr: 0.9,
        seed: 2026,
        threads: opts.threads,
    };
    Ok(Comparison {
        evolution: differential_evolution(&p, &o, report),
        search_best: search.best.merit(p.weight),
    })
}

/// Runs DE on `p`; `report(generation, best)` is called after each generation.
pub(crate) fn differential_evolution(
    p: &Problem,
    o: &EvolutionOptions,
    report: &dyn Fn(usize, f64),
) -> Evolution {
    let n = p.knots.segments();
    let mut rng = SplitMix(o.seed);
    let mut uniform = |lo: f64, hi: f64| lo + (hi - lo) * rng.next_f64();
    let intervals = |w: &[f64]| {
        let sum: f64 = w.iter().sum();
        w.iter()
            .map(|x| x * p.total_time / sum)
            .collect::<Vec<f64>>()
    };
    let score = |w: &Vec<f64>| {
        p.inner(&intervals(w), &p.zero_x(), Method::ViaRelaxation, ROUNDS)
            .map_or(f64::INFINITY, |s| s.merit(p.weight))
    };
    let mut pop: Vec<Vec<f64>> = (0..o.population)
        .map(|_| (0..n).map(|_| uniform(0.05, 1.0)).collect())
        .collect();
    let mut fit = parallel(&pop, o.threads, score);
    let mut evaluations = pop.len();
    for g in 0..o.generations {
        let trials: Vec<Vec<f64>> = (0..o.population)
            .map(|i| {
                let mut pick = || loop {
                    let k = (uniform(0.0, 1.0) * o.population as f64) as usize;
                    if k != i && k < o.population {
                        break k;
                    }
                };
                let (a, b, c) = (pick(), pick(), pick());
                let forced = ((uniform(0.0, 1.0) * n as f64) as usize).min(n - 1);
                (0..n)
                    .map(|d| {
                        if d == forced || uniform(0.0, 1.0) < o.cr {
                            (pop[a][d] + o.f * (pop[b][d] - pop[c][d])).clamp(0.05, 1.0)
                        } else {
                            pop[i][d]
                        }
                    })
                    .collect()
            })
            .collect();
        let scores = parallel(&trials, o.threads, score);
        evaluations += trials.len();
        for (i, (t, s)) in trials.into_iter().zip(scores).enumerate() {
            if s <= fit[i] {
                pop[i] = t;
                fit[i] = s;
            }
        }
        report(g, fit.iter().copied().fold(f64::INFINITY, f64::min));
    }
    let (i, best) = fit
        .iter()
        .copied()
        .enumerate()
        .fold(
            (0, f64::INFINITY),
            |acc, (i, f)| if f < acc.1 { (i, f) } else { acc },
        );
    Evolution {
        best,
        h: intervals(&pop[i]),
        evaluations,
    }
}
