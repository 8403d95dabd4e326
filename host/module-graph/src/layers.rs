//! Modules in layers: each names only modules listed before it.

use std::fs;
use std::path::Path;

use crate::paths::crate_paths;
use crate::sources::{rust_files, without_tests};

/// Every violation of `layers` (top-level modules, bottom first) in the
/// sources under `root`: a module not listed, or a `crate::` path outside
/// test items (a `use`, a path in code, a doc link) that names the module
/// itself, one listed after it, or no module (`crate::Name` through a
/// re-export of the root hides which module it points to). The root and
/// test-only modules (`tests`, `…_tests`) are not checked.
pub fn layer_violations(root: &Path, layers: &[&str]) -> Vec<String> {
    let mut bad = Vec::new();
    for path in rust_files(root) {
        let rel = path.strip_prefix(root).expect("file under root");
        let first = rel.iter().next().expect("a file name").to_string_lossy();
        let module = first.trim_end_matches(".rs");
        if module == "lib" || module == "tests" || module.ends_with("_tests") {
            continue;
        }
        let Some(level) = layers.iter().position(|m| *m == module) else {
            bad.push(format!(
                "{}: module `{module}` is not in LAYERS",
                rel.display()
            ));
            continue;
        };
        let text = without_tests(&fs::read_to_string(&path).expect("source readable"));
        let before = bad.len();
        for p in crate_paths(&text, &[]).into_iter().filter(|p| p.from_crate) {
            let line = p.line;
            let target = p.path.first().map(String::as_str).unwrap_or("");
            match layers.iter().position(|m| *m == target) {
                Some(t) if t < level => {}
                Some(t) if t == level => bad.push(format!(
                    "{}:{line}: crate::{target} inside `{module}` (use self:: or super::)",
                    rel.display()
                )),
                Some(_) => bad.push(format!(
                    "{}:{line}: `{module}` points up to crate::{target}",
                    rel.display()
                )),
                None => bad.push(format!(
                    "{}:{line}: crate::{target} is not a module path (name the module)",
                    rel.display()
                )),
            }
        }
        // One message for the paths of one use tree.
        let mut seen = std::collections::BTreeSet::new();
        let mut k = before;
        while k < bad.len() {
            if seen.insert(bad[k].clone()) {
                k += 1;
            } else {
                bad.remove(k);
            }
        }
    }
    bad
}
