//! The closed curve of the speed figures' scaling jobs and verdicts, shared by
//! `examples/scaling_paths.rs` (which writes it as job files) and
//! `benches/planner.rs` (which plans it in process).

/// x = 90 sin t, y = 70 sin 2t, z = 600 + 60 sin(3t + 0.3) mm at
/// t = 2πi/(n − 1), i = 0…n−1, rounded to 1 nm as the job files are written
/// (the search's path depends on the points' last digits).
pub fn closed_curve_mm(n: usize) -> Vec<[f64; 3]> {
    let nm = |mm: f64| (mm * 1e6).round() / 1e6;
    (0..n)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / (n - 1) as f64;
            [
                nm(90.0 * t.sin()),
                nm(70.0 * (2.0 * t).sin()),
                nm(600.0 + 60.0 * (3.0 * t + 0.3).sin()),
            ]
        })
        .collect()
}
