//! The import graph of a crate's modules, and its cycles.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::Path;

use crate::paths::crate_paths;
use crate::sources::{Module, module_of, rust_files, strip_comments, without_tests};

/// Module → the modules it imports.
pub type Graph = BTreeMap<Module, BTreeSet<Module>>;

/// The import graph of the crate whose sources are under `src`: every
/// `crate::` or `super::` path outside comments and test items, resolved
/// to the longest module prefix it names.
pub fn graph(src: &Path) -> Graph {
    let files = rust_files(src);
    let modules: BTreeSet<Module> = files.iter().map(|f| module_of(src, f)).collect();
    let mut g = Graph::new();
    for f in &files {
        let from = module_of(src, f);
        let text = fs::read_to_string(f).expect("source readable");
        let text = strip_comments(&without_tests(&text));
        let deps = g.entry(from.clone()).or_default();
        for p in crate_paths(&text, &from) {
            let to = (0..=p.path.len())
                .rev()
                .map(|n| p.path[..n].to_vec())
                .find(|m| modules.contains(m))
                .unwrap_or_default();
            if to != from && !to.is_empty() {
                deps.insert(to);
            }
        }
    }
    g
}

/// One cycle of `g`, if any, as the modules along it (first repeated last).
pub fn find_cycle(g: &Graph) -> Option<Vec<Module>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        Open,
        Done,
    }
    fn visit(
        g: &Graph,
        m: &Module,
        marks: &mut BTreeMap<Module, Mark>,
        stack: &mut Vec<Module>,
    ) -> Option<Vec<Module>> {
        match marks.get(m) {
            Some(Mark::Done) => return None,
            Some(Mark::Open) => {
                let at = stack.iter().position(|s| s == m).expect("open on stack");
                let mut cycle = stack[at..].to_vec();
                cycle.push(m.clone());
                return Some(cycle);
            }
            None => {}
        }
        marks.insert(m.clone(), Mark::Open);
        stack.push(m.clone());
        for d in g.get(m).into_iter().flatten() {
            if let Some(c) = visit(g, d, marks, stack) {
                return Some(c);
            }
        }
        stack.pop();
        marks.insert(m.clone(), Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    for m in g.keys() {
        if let Some(c) = visit(g, m, &mut marks, &mut Vec::new()) {
            return Some(c);
        }
    }
    None
}

/// `crate::a::b -> crate::c`.
pub fn show(modules: &[Module]) -> String {
    modules
        .iter()
        .map(|m| format!("crate::{}", m.join("::")))
        .collect::<Vec<_>>()
        .join(" -> ")
}
