//! The firmware core's modules depend on each other in one direction only:
//! every `crate::…` path in a module (a `use`, a path in code, a doc link),
//! outside its test module, names a module listed before it in [`LAYERS`].
//! So there is no import cycle, and a reader can take the modules in this
//! order. `crate::Name` through a re-export of the crate root is refused
//! too: it hides which module it points to.

use std::fs;
use std::path::{Path, PathBuf};

use triquint_module_graph::layer_violations;

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

fn violations(root: &Path) -> Vec<String> {
    layer_violations(root, LAYERS)
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
