//! The platform's largest distance from the straight segment between two
//! via-points, for joint positions sampled along a motion (the paper's
//! robot): what `scripts/ruckig_bench.py` reports for both planners.
//!
//! Reads one JSON object a line on stdin, `{"via": [[x, y, z], [x, y, z]],
//! "q": [[q1, q2, q3], ...]}` in metres, and prints the largest distance
//! (mm) of the samples' forward kinematics from the segment, one a line.
//!
//! `cargo run --release -p triquint-planner --example path_deviation < samples.jsonl`

use std::io::BufRead;

use nalgebra::Vector3;
use serde::Deserialize;
use triquint_shared::Robot;
use triquint_shared::kinematics::platform_position;

#[derive(Deserialize)]
struct Samples {
    via: [[f64; 3]; 2],
    q: Vec<[f64; 3]>,
}

/// Distance of `p` from the segment a–b.
fn from_segment(p: Vector3<f64>, a: Vector3<f64>, b: Vector3<f64>) -> f64 {
    let ab = b - a;
    let u = ((p - a).dot(&ab) / ab.norm_squared()).clamp(0.0, 1.0);
    (p - (a + ab * u)).norm()
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let model = Robot::default().model::<f64>();
    for line in std::io::stdin().lock().lines() {
        let s: Samples = serde_json::from_str(&line?)?;
        let (a, b) = (Vector3::from(s.via[0]), Vector3::from(s.via[1]));
        let mut worst: f64 = 0.0;
        for q in &s.q {
            let p = platform_position(&model, *q)?;
            worst = worst.max(from_segment(p, a, b));
        }
        println!("{}", worst * 1e3);
    }
    Ok(())
}
