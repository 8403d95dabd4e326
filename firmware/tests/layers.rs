//! The firmware core's modules depend on each other in one direction only:
//! every `crate::…` path in a module (a `use`, a path in code, a doc link),
//! outside its test module, names a module listed before it in [`LAYERS`].
//! So there is no import cycle, and a reader can take the modules in this
//! order. `crate::Name` through a re-export of the crate root is refused
//! too: it hides which module it points to.

use std::fs;
use std::path::{Path, PathBuf};

/// Bottom first. A new module goes where its dependencies allow.
const LAYERS: &[&str] = &[
    "f32_cast",       // integer ↔ f32 conversions of the tick
    "watchdog",       // when a board feeds its hardware watchdog
    "segment",        // a queued segment and its evaluation
    "ceilings",       // the machine ceilings a segment is held to
    "ceiling_lock",   // a new configuration may tighten them, not widen
    "scaling",        // the jerk-limited time-scaling of stops and resumes
    "sync",           // host time from TimeSync frames
    "derived_config", // what a configuration derives once
    "inbox",          // the hand-off between the receive side and the tick
    "hal",            // the hardware traits
    "handoff",        // the receive task's hand-off behind a full inbox
    "law",            // the control law, a pure step function
    "reaction",       // the fault reaction table
    "enable_check",   // does the axis move the way it is told
    "homing",         // the homing state machine, a pure step function
    "receiver",       // the CAN receive side
    "drive",          // the control side: state machine, queue, tick
    "node",           // both sides in one context
];

fn src() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("src")
}

/// The module a source file belongs to (`drive/x.rs` is part of `drive`).
fn module_of(rel: &Path) -> String {
    let first = rel
        .components()
        .next()
        .unwrap()
        .as_os_str()
        .to_string_lossy();
    first.trim_end_matches(".rs").to_string()
}

/// The text outside `#[cfg(test)]` items (a test module, a test-only `use`).
fn without_tests(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(i) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..i]);
        let after = &rest[i..];
        // The item ends at its `;` or at the brace closing its first `{`.
        let semi = after.find(';').unwrap_or(after.len());
        let brace = after.find('{').unwrap_or(after.len());
        if semi < brace {
            rest = &after[semi + 1..];
            continue;
        }
        let mut depth = 0;
        let mut end = after.len();
        for (k, c) in after.char_indices().skip(brace) {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth -= 1;
                    if depth == 0 {
                        end = k + 1;
                        break;
                    }
                }
                _ => {}
            }
        }
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// First segments of every `crate::` path, with their line numbers.
fn crate_paths(text: &str) -> Vec<(usize, String)> {
    let mut v = Vec::new();
    for (n, line) in text.lines().enumerate() {
        let mut rest = line;
        while let Some(i) = rest.find("crate::") {
            let before = rest[..i].chars().last();
            rest = &rest[i + "crate::".len()..];
            // `$crate::` and `triquint_shared::…crate::` are not this crate.
            if before.is_some_and(|c| c == '$' || c == '_' || c.is_alphanumeric()) {
                continue;
            }
            let name: String = rest
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            v.push((n + 1, name));
        }
    }
    v
}

fn files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// Every violation in the sources under `root`.
fn violations(root: &Path) -> Vec<String> {
    let mut all = Vec::new();
    files(root, &mut all);
    all.sort();
    let mut bad = Vec::new();
    for path in all {
        let rel = path.strip_prefix(root).unwrap();
        let module = module_of(rel);
        if module == "lib" || module == "tests" {
            continue; // the crate root and the crate's test module
        }
        let Some(level) = LAYERS.iter().position(|m| *m == module) else {
            bad.push(format!(
                "{}: module `{module}` is not in LAYERS",
                rel.display()
            ));
            continue;
        };
        let text = fs::read_to_string(&path).unwrap();
        for (line, target) in crate_paths(&without_tests(&text)) {
            match LAYERS.iter().position(|m| *m == target) {
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
    }
    bad
}

#[test]
fn modules_depend_in_one_direction() {
    let bad = violations(&src());
    assert!(bad.is_empty(), "module layering:\n{}", bad.join("\n"));
}

#[test]
fn the_check_catches_a_path_up_a_re_export_and_an_unlisted_module() {
    let dir = std::env::temp_dir().join(format!("triquint-layers-{}", std::process::id()));
    fs::create_dir_all(&dir).unwrap();
    fs::write(
        dir.join("inbox.rs"),
        "//! See [`crate::drive::Drive`].\nuse crate::sync::X;\n#[cfg(test)]\nmod tests { use crate::node::Node; }\n",
    )
    .unwrap();
    fs::write(dir.join("hal.rs"), "fn f() { crate::Drive::new(1); }\n").unwrap();
    fs::write(dir.join("extra.rs"), "\n").unwrap();
    let bad = violations(&dir);
    fs::remove_dir_all(&dir).unwrap();
    assert_eq!(bad.len(), 3, "{bad:#?}");
    assert!(bad[0].contains("not in LAYERS"), "{}", bad[0]);
    assert!(bad[1].contains("not a module path"), "{}", bad[1]);
    assert!(bad[2].contains("inbox.rs:1") && bad[2].contains("points up to crate::drive"));
}
