//! The job files shown in docs/planner.md are real jobs: each `toml`
//! block there parses and plans, and its plan passes `check`.

use std::path::Path;

use triquint_planner::{Job, Options, check, plan};

fn toml_blocks(text: &str) -> Vec<String> {
    let mut out = Vec::new();
    let mut open: Option<String> = None;
    for line in text.lines() {
        match (line.strip_prefix("```"), open.as_mut()) {
            (Some(info), None) => {
                open = (info.trim() == "toml").then(String::new);
                if open.is_none() {
                    // A block of another language: skip to its end.
                    open = Some("\u{0}".into());
                }
            }
            (Some(_), Some(_)) => {
                let block = open.take().unwrap();
                if !block.starts_with('\u{0}') {
                    out.push(block);
                }
            }
            (None, Some(block)) => {
                block.push_str(line);
                block.push('\n');
            }
            (None, None) => {}
        }
    }
    out
}

#[test]
fn every_job_in_the_planner_guide_plans_and_checks() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/planner.md");
    let blocks = toml_blocks(&std::fs::read_to_string(path).unwrap());
    assert!(!blocks.is_empty(), "docs/planner.md shows no job");
    for text in blocks {
        let job = Job::from_toml(&text).unwrap_or_else(|e| panic!("{e}\n{text}"));
        let p = plan(&job, &Options::default()).unwrap_or_else(|e| panic!("{e}\n{text}"));
        assert!(check(&p).unwrap().iter().all(|row| row.ok), "{text}");
    }
}
