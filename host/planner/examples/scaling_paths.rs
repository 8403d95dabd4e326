//! Writes the scaling jobs of the planner's speed figures (docs/verification.md, "Planner
//! speed"): the closed curve x = 90 sin t, y = 70 sin 2t,
//! z = 600 + 60 sin(3t + 0.3) mm, t = 2πi/(n − 1), i = 0…n−1, as a
//! min-max-jerk job of `n` via-points with the default limits.
//!
//! `cargo run --release -p triquint-planner --example scaling_paths -- DIR SECONDS_PER_SEGMENT N...`
//! writes DIR/curve-N.toml for each N (total time = seconds per segment × (N − 1)).
//! With `--walk` after DIR it writes DIR/walk-N.toml instead: the seeded
//! random walk of `support/random_walk.rs` (steps of 4 mm).

#[path = "support/closed_curve.rs"]
mod closed_curve;
#[path = "support/random_walk.rs"]
mod random_walk;

use std::fmt::Write as _;
use std::path::PathBuf;

fn job_toml(what: &str, points: &[[f64; 3]], total_time: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# {what} of {} via-points (host/planner/examples/scaling_paths.rs).",
        points.len()
    );
    s.push_str("objective = \"min-max-jerk\"\n\n[limits]\n");
    s.push_str("velocity = 0.5\nacceleration = 1.2\njerk = 5.0\ntorque = 10.0\n");
    let _ = writeln!(
        s,
        "total_time = {total_time}\n\n[path]\nunits = \"mm\"\npoints = ["
    );
    for p in points {
        let _ = writeln!(s, "    [{:.6}, {:.6}, {:.6}],", p[0], p[1], p[2]);
    }
    s.push_str("]\n");
    s
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let walk = args.get(1).is_some_and(|a| a == "--walk");
    if walk {
        args.remove(1);
    }
    let [dir, per_segment, ns @ ..] = args.as_slice() else {
        return Err("usage: scaling_paths DIR [--walk] SECONDS_PER_SEGMENT N...".into());
    };
    let dir = PathBuf::from(dir);
    let per_segment: f64 = per_segment.parse()?;
    std::fs::create_dir_all(&dir)?;
    for n in ns {
        let n: usize = n.parse()?;
        if n < 3 {
            return Err(format!("a path needs at least 3 points, got {n}").into());
        }
        let (name, what, points) = if walk {
            ("walk", "Random walk", random_walk::random_walk_mm(n))
        } else {
            ("curve", "Closed curve", closed_curve::closed_curve_mm(n))
        };
        let path = dir.join(format!("{name}-{n}.toml"));
        std::fs::write(&path, job_toml(what, &points, per_segment * (n - 1) as f64))?;
        println!("{}", path.display());
    }
    Ok(())
}
