//! The workspace's dependency rules (docs/architecture.md, "Dependency
//! rules"), checked on `cargo metadata`: a crate's own dependencies of
//! every kind (normal, build and dev), and what those bring along (their
//! normal and build dependencies, as cargo does).
//!
//! - `triquint-shared` and `triquint-module-graph` import nothing of ours;
//! - `triquint-firmware`, `triquint-link`, `triquint-planner` and
//!   `triquint-cli-common` use only `triquint-shared` (the firmware and the
//!   planner the module graph in their layer tests): in particular the
//!   bus side and the planner never the simulator;
//! - `triquint-sim` may use the firmware, the link and the CLI helpers, but
//!   not the planner, the plots or the host.
//!
//! Crates not named here (the `triquint` binary, the plots, bindings) may
//! use any of ours.

use std::collections::{BTreeMap, BTreeSet};
use std::process::Command;

/// Each ruled crate and the crates of ours it may use.
const RULES: &[(&str, &[&str])] = &[
    ("triquint-shared", &[]),
    ("triquint-module-graph", &[]),
    // The module graph only in their layer tests.
    (
        "triquint-firmware",
        &["triquint-shared", "triquint-module-graph"],
    ),
    ("triquint-link", &["triquint-shared"]),
    (
        "triquint-planner",
        &["triquint-shared", "triquint-module-graph"],
    ),
    ("triquint-cli-common", &["triquint-shared"]),
    (
        "triquint-sim",
        &[
            "triquint-shared",
            "triquint-firmware",
            "triquint-link",
            "triquint-cli-common",
        ],
    ),
];

/// Crates of ours a crate names: (name, is a dev-dependency).
type Graph = BTreeMap<String, BTreeSet<(String, bool)>>;

/// The workspace's crates and, for each, the crates of ours it names.
fn our_dependencies() -> Graph {
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/../Cargo.toml");
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let out = Command::new(cargo)
        .args([
            "metadata",
            "--format-version",
            "1",
            "--no-deps",
            "--offline",
        ])
        .args(["--manifest-path", manifest])
        .output()
        .expect("cargo metadata runs");
    assert!(
        out.status.success(),
        "cargo metadata: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let meta: serde_json::Value = serde_json::from_slice(&out.stdout).expect("metadata JSON");
    let packages = meta["packages"].as_array().expect("packages");
    let ours: BTreeSet<String> = packages
        .iter()
        .filter_map(|p| p["name"].as_str().map(String::from))
        .collect();
    packages
        .iter()
        .map(|p| {
            let deps = p["dependencies"]
                .as_array()
                .into_iter()
                .flatten()
                .filter_map(|d| Some((d["name"].as_str()?, d["kind"].as_str() == Some("dev"))))
                .filter(|(d, _)| ours.contains(*d))
                .map(|(d, dev)| (d.to_string(), dev))
                .collect();
            (p["name"].as_str().unwrap_or_default().to_string(), deps)
        })
        .collect()
}

/// Every crate of ours `name` reaches, with the path to it.
/// (Dev-dependencies count only for `name` itself.)
fn reach(graph: &Graph, name: &str) -> BTreeMap<String, String> {
    let mut seen = BTreeMap::new();
    let mut todo = vec![(name.to_string(), name.to_string())];
    while let Some((at, path)) = todo.pop() {
        for (d, dev) in graph.get(&at).into_iter().flatten() {
            // A crate's dev-dependency on itself only turns on its own
            // features for its tests (the planner's `evolution`).
            if (*dev && at != name) || d == name {
                continue;
            }
            if !seen.contains_key(d) {
                let p = format!("{path} → {d}");
                seen.insert(d.clone(), p.clone());
                todo.push((d.clone(), p));
            }
        }
    }
    seen
}

#[test]
fn crates_depend_only_on_what_the_architecture_allows() {
    let graph = our_dependencies();
    let mut broken = Vec::new();
    for (name, allowed) in RULES {
        assert!(
            graph.contains_key(*name),
            "{name} is not in the workspace: update RULES and docs/architecture.md"
        );
        for (dep, path) in reach(&graph, name) {
            if !allowed.contains(&dep.as_str()) {
                broken.push(format!("{path}: {name} must not use {dep}"));
            }
        }
    }
    assert!(broken.is_empty(), "\n{}", broken.join("\n"));
}

#[test]
fn the_rules_catch_a_forbidden_path() {
    // The same check on a made-up graph: link → cli-common → sim is caught
    // at the end of the path, not only at direct edges; a dev-dependency
    // counts for the crate itself, not for the crates that use it.
    let mut g = Graph::new();
    let mut edge = |a: &str, b: &str, dev: bool| {
        g.entry(a.into()).or_default().insert((b.into(), dev));
    };
    edge("triquint-link", "triquint-cli-common", true);
    edge("triquint-cli-common", "triquint-sim", false);
    edge("triquint-sim", "triquint-planner", true);
    let r = reach(&g, "triquint-link");
    assert_eq!(
        r.get("triquint-sim").map(String::as_str),
        Some("triquint-link → triquint-cli-common → triquint-sim")
    );
    assert!(!r.contains_key("triquint-planner"), "{r:?}");
    assert!(reach(&g, "triquint-sim").contains_key("triquint-planner"));
}
