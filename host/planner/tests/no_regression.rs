//! No regression against b0eb6e5: on committed paths of 10–40 via-points
//! (four shapes, `tests/regression/generate.py`; one of them at a quarter
//! of the time, where acceleration binds), the max jerk of each plan
//! is never worse than b0eb6e5's (`tests/regression/baseline.toml`, written
//! by that binary) by more than 1e-4 relative, and every plan passes the
//! independent check. On three of them with only jerk limited, differential evolution over the
//! intervals finds nothing better than the search by more than 0.1 %. Case II
//! min-time is never longer than b0eb6e5's, and an infeasible verdict names it.

use std::path::{Path, PathBuf};

use triquint_planner::evolution::compare;
use triquint_planner::{Job, Limits, Objective, Options, PlanError, check, plan};

fn dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/regression")
}

fn baseline() -> Vec<(String, f64)> {
    let text = std::fs::read_to_string(dir().join("baseline.toml")).unwrap();
    let table: toml::Table = text.parse().unwrap();
    let mut out: Vec<(String, f64)> = table
        .into_iter()
        .map(|(k, v)| (k, v.as_float().expect("a max jerk")))
        .collect();
    out.sort_by(|a, b| a.0.cmp(&b.0));
    out
}

fn job(name: &str) -> Job {
    Job::load(&dir().join(format!("{name}.toml"))).unwrap()
}

#[test]
fn max_jerk_is_never_worse_than_b0eb6e5() {
    let jobs = baseline();
    assert_eq!(jobs.len(), 10, "the committed set");
    for (name, base) in jobs {
        let p = plan(&job(&name), &Options::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
        for r in check(&p).unwrap() {
            assert!(r.ok, "{name}: {} = {} > {}", r.what, r.value, r.bound);
        }
        let jerk = p.max_abs.jerk.iter().fold(0.0, |a: f64, b| a.max(*b));
        eprintln!(
            "{name}: {jerk:.9} against b0eb6e5's {base:.9} ({:+.2e})",
            jerk / base - 1.0
        );
        assert!(jerk <= base * (1.0 + 1e-4), "{name}: {jerk} against {base}");
    }
}

#[test]
fn differential_evolution_finds_nothing_better() {
    // With only jerk limited (every other limit far away), each candidate
    // costs DE one LP; with the committed limits DE's random intervals
    // break the others and each costs ten (the search tests' DE check has
    // a job where they bind).
    for name in ["lissajous-10", "walk-10", "zigzag-12"] {
        let j = job(name);
        let limits = Limits {
            velocity: 100.0,
            acceleration: 1e4,
            torque: 1e6,
            ..j.limits().clone()
        };
        let j = j.to_builder().limits(limits).build().unwrap();
        let c = compare(&j, 30, 4, &Options::default(), &|_, _| {}).unwrap();
        let de = c.evolution.best;
        eprintln!(
            "{name}: DE {de:.9} ({} evaluations), search {:.9}",
            c.evolution.evaluations, c.search_best
        );
        assert!(
            de >= c.search_best * (1.0 - 1e-3),
            "{name}: DE {de} < search {}",
            c.search_best
        );
    }
}

/// Case II's shortest time by b0eb6e5's min-time search (bisection), s.
const B0EB6E5_CASE2_MIN_TIME_S: f64 = 3.4910;

#[test]
fn case2_min_time_is_never_longer_than_b0eb6e5s_and_the_verdict_agrees() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../examples/paper-case2.toml");
    let case2 = Job::load(&path).unwrap();
    let min_time = case2
        .to_builder()
        .objective(Objective::MinTime)
        .build()
        .unwrap();
    let p = plan(&min_time, &Options::default()).unwrap();
    for r in check(&p).unwrap() {
        assert!(r.ok, "{} = {} > {}", r.what, r.value, r.bound);
    }
    let t = p.total_time_s;
    eprintln!("Case II min-time {t:.6} s against b0eb6e5's {B0EB6E5_CASE2_MIN_TIME_S} s");
    assert!(t <= B0EB6E5_CASE2_MIN_TIME_S, "{t}");
    // Asked for 3.0 s, the verdict's shortest time is the min-time answer.
    let short = case2.to_builder().total_time(3.0).build().unwrap();
    match plan(&short, &Options::default()) {
        Err(PlanError::Infeasible {
            shortest_total_time: Some(s),
            ..
        }) => assert!(
            (s - t).abs() <= 1e-5 * t,
            "verdict {s} against min-time {t}"
        ),
        other => panic!("{other:?}"),
    }
}
