//! The planner's modules depend on each other in one direction only: every
//! `crate::…` path in a module (a `use`, a path in code, a doc link), outside
//! its test module, names a module listed before it in [`LAYERS`], and no
//! module calls a method that a module after it adds to the core types
//! (`impl Problem` and `impl Solution` are spread over the core's layers, so
//! a call upwards needs no `use` and the paths alone would not show it).
//! So there is no cycle, and a reader can take the modules in this order.
//! `crate::Name` through a re-export of the crate root is refused too: it
//! hides which module it points to.

use std::collections::BTreeMap;
use std::fs;
use std::path::{Path, PathBuf};

use triquint_module_graph::{block_end, layer_violations, module_of, rust_files, without_tests};

/// Bottom first. A new module goes where its dependencies allow.
const LAYERS: &[&str] = &[
    "error",        // PlanError
    "options",      // how hard to search; the observer's side
    "run_state",    // cancellation and progress shared with the observer
    "workers",      // worker threads and spare cores
    "extrema",      // polynomial extrema (the search's)
    "sturm",        // polynomial extrema by Sturm sequences (the check's)
    "banded",       // banded least-change projection
    "spline",       // the quintic spline as affine forms of the knot derivatives
    "shaper",       // a shaper's impulses and the convolution with them
    "lp",           // the conic program and its solver
    "holding",      // the torque that holds the platform still
    "job",          // the job model
    "bounded_read", // size-limited reads of input files
    "points_file",  // points files
    "job_file",     // job files
    "load",         // plan files
    "stats",        // statistics of a plan
    "check",        // independent verification of a plan
    "streaming",    // the streaming rule every plan written keeps to
    "shaping",      // input shaping of a plan, re-checked
    "problem",      // the problem at fixed knots and its exact evaluation
    "program",      // its program at a point (cutting planes, trust region)
    "jerk_only",    // the jerk-only inner problem without interior point
    "inner",        // the inner solve at fixed intervals, by a method
    "step",         // the trust-region step
    "second_order", // a descent step corrected to second order
    "time_scaling", // a shape time-scaled
    "coarse_start", // a long path's starts from its coarser path
    "search",       // the multistart search
    "time_descent", // the descent on the total time
    "min_time",     // the shortest total time
    "rounding",     // whole microseconds
    "free_knots",   // a point-to-point move's knots chosen by the planner
    "jerk_knots",   // min-max-jerk knots added and chosen by the planner
    "planning",     // the entry point, `plan`
    "evolution",    // differential evolution, the search's independent check
];

/// Types whose methods are spread over several layers.
const CORE_TYPES: &[&str] = &["Problem", "Solution"];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

fn identifier_after(text: &str) -> String {
    text.chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// Every `fn` declared in the text.
fn functions(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut rest = text;
    while let Some(i) = rest.find("fn ") {
        let before = rest[..i].chars().last();
        rest = &rest[i + 3..];
        if before.is_none_or(|c| !(c.is_alphanumeric() || c == '_')) {
            let name = identifier_after(rest);
            if !name.is_empty() {
                out.push(name);
            }
        }
    }
    out
}

/// The methods the text adds to the core types.
fn core_methods(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    for ty in CORE_TYPES {
        let head = format!("impl {ty} {{");
        let mut from = 0;
        while let Some(i) = text[from..].find(&head) {
            let start = from + i;
            let end = block_end(text, start);
            out.extend(functions(&text[start..end]));
            from = end;
        }
    }
    out
}

/// Every violation in the sources under `root`: the layers' paths, then
/// calls of a core method added by a layer above.
fn violations(root: &Path) -> Vec<String> {
    let mut bad = layer_violations(root, LAYERS);
    // (file, module, level, text outside tests) of every listed module.
    let mut sources = Vec::new();
    for path in rust_files(root) {
        let rel = path.strip_prefix(root).unwrap().to_path_buf();
        let module = module_of(root, &path).first().cloned().unwrap_or_default();
        if let Some(level) = LAYERS.iter().position(|m| *m == module) {
            let text = without_tests(&fs::read_to_string(&path).unwrap());
            sources.push((rel, module, level, text));
        }
    }
    // The level that adds each core method, and every fn name per level.
    let mut adds: BTreeMap<String, usize> = BTreeMap::new();
    let mut declared: Vec<(usize, String)> = Vec::new();
    for (_, _, level, text) in &sources {
        for m in core_methods(text) {
            adds.entry(m).or_insert(*level);
        }
        declared.extend(functions(text).into_iter().map(|f| (*level, f)));
    }
    // Below the first layer that adds core methods there is no core value
    // to call them on without a path to it (checked above).
    let core_floor = adds.values().copied().min().unwrap_or(usize::MAX);
    for (rel, module, level, text) in &sources {
        for (method, &at) in &adds {
            // A name that this layer or one below declares as well may be
            // that function (another type's method): not a call upwards.
            let known_below = declared.iter().any(|(l, f)| l <= level && f == method);
            if at <= *level || *level < core_floor || known_below {
                continue;
            }
            for (n, l) in text.lines().enumerate() {
                if l.contains(&format!(".{method}(")) {
                    bad.push(format!(
                        "{}:{}: `{module}` calls {method}, added by `{}` above it",
                        rel.display(),
                        n + 1,
                        LAYERS[at]
                    ));
                }
            }
        }
    }
    // File by file, each file's paths before its calls.
    bad.sort_by_key(|m| m.split(':').next().unwrap_or("").to_string());
    bad
}

#[test]
fn modules_depend_in_one_direction() {
    let bad = violations(&src());
    assert!(bad.is_empty(), "module layering:\n{}", bad.join("\n"));
}

#[test]
fn the_check_catches_a_path_up_a_call_up_a_re_export_and_an_unlisted_module() {
    let dir = std::env::temp_dir().join(format!("triquint-planner-layers-{}", std::process::id()));
    fs::create_dir_all(&dir).unwrap();
    fs::write(
        dir.join("problem.rs"),
        "//! See [`crate::search::global`].\nuse crate::spline::Knots;\n\
         impl Problem { fn evaluate(&self) {} }\n\
         fn f(p: &Problem) { p.evaluate(); p.descend_time(); }\n\
         #[cfg(test)]\nmod tests {\n    use crate::planning::plan;\n}\n\
         fn g(p: &Problem) { p.descend_time(); }\n",
    )
    .unwrap();
    fs::write(
        dir.join("min_time.rs"),
        "impl Problem {\n    fn descend_time(&self) { self.evaluate(); }\n}\n",
    )
    .unwrap();
    fs::write(dir.join("step.rs"), "fn f() { crate::Job::new(); }\n").unwrap();
    fs::write(dir.join("extra.rs"), "\n").unwrap();
    let bad = violations(&dir);
    fs::remove_dir_all(&dir).unwrap();
    assert_eq!(bad.len(), 5, "{bad:#?}");
    assert!(bad[0].contains("not in LAYERS"), "{}", bad[0]);
    assert!(
        bad[1].contains("problem.rs:1") && bad[1].contains("points up to crate::search"),
        "{}",
        bad[1]
    );
    assert!(
        bad[2].contains("problem.rs:4") && bad[2].contains("calls descend_time"),
        "{}",
        bad[2]
    );
    assert!(
        bad[3].contains("problem.rs:9") && bad[3].contains("calls descend_time"),
        "{}",
        bad[3]
    );
    assert!(bad[4].contains("not a module path"), "{}", bad[4]);
}
