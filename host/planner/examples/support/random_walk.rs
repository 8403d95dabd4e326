//! The random-walk path of the scaling benchmark (`scripts/planner-scaling.sh`):
//! an open path of seeded steps, unlike the closed curve's smooth one, so the
//! figures do not depend on one path's regularity.

/// Length of each step (mm): a dispensing or inspection path's spacing.
const STEP_MM: f64 = 4.0;
/// The box the walk stays in (mm), the closed curve's reach.
const LO: [f64; 3] = [-90.0, -70.0, 540.0];
const HI: [f64; 3] = [90.0, 70.0, 660.0];

/// `n` points from (0, 0, 600) mm, each a step of [`STEP_MM`] in a direction
/// uniform on the sphere (xorshift64* from a fixed seed, so every run and
/// machine gets the same path), reflected back into the box, rounded to
/// 1 nm as the job files are written.
pub fn random_walk_mm(n: usize) -> Vec<[f64; 3]> {
    let mut state: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut uniform = move || {
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    };
    let nm = |mm: f64| (mm * 1e6).round() / 1e6;
    let mut p = [0.0, 0.0, 600.0];
    let mut out = vec![p];
    while out.len() < n {
        let z = 2.0 * uniform() - 1.0;
        let phi = std::f64::consts::TAU * uniform();
        let r = (1.0 - z * z).sqrt();
        let d = [r * phi.cos(), r * phi.sin(), z];
        for a in 0..3 {
            let mut v = p[a] + STEP_MM * d[a];
            if v > HI[a] {
                v = 2.0 * HI[a] - v;
            } else if v < LO[a] {
                v = 2.0 * LO[a] - v;
            }
            p[a] = nm(v);
        }
        out.push(p);
    }
    out
}
