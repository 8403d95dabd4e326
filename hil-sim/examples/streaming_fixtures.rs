//! Writes issue 35's streaming fixtures ([`testplan::streaming_fixtures`])
//! as plan files for `triquint upload` (the VM suite,
//! hil-sim/python/test_streaming.py):
//! `cargo run --release -p triquint-sim --example streaming_fixtures -- DIR`.

use std::path::PathBuf;

use triquint_sim::testplan;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(
        std::env::args()
            .nth(1)
            .ok_or("usage: streaming_fixtures DIR")?,
    );
    std::fs::create_dir_all(&dir)?;
    for (name, plan) in testplan::streaming_fixtures()? {
        let path = dir.join(format!("{name}.json"));
        std::fs::write(&path, serde_json::to_string(&plan)? + "\n")?;
        println!(
            "{}: {} segments, {:.3} s",
            path.display(),
            plan.segments.len(),
            plan.total_time_s
        );
    }
    Ok(())
}
