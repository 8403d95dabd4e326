// Shared by the stable-Rust corpus tests (via include!): the files of a
// corpus or regression folder of `fuzz/`, and the seeded generator for
// mutations (rand_chacha, the one generator of the tests and the simulator;
// the including crates have it as a dev-dependency).

/// The contents of every file in `fuzz/<dir>` (dot files skipped).
fn inputs(dir: &str) -> Vec<Vec<u8>> {
    // The tests live in crates at different depths below the workspace.
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .ancestors()
        .map(|a| a.join("fuzz"))
        .find(|f| f.join("Cargo.toml").is_file())
        .unwrap_or_else(|| panic!("no fuzz/ above {}", env!("CARGO_MANIFEST_DIR")))
        .join(dir);
    let mut out = Vec::new();
    for e in std::fs::read_dir(&root).unwrap_or_else(|e| panic!("{}: {e}", root.display())) {
        let p = e.unwrap().path();
        if p.is_file() && !p.file_name().is_some_and(|n| n.to_string_lossy().starts_with('.')) {
            out.push(std::fs::read(&p).unwrap());
        }
    }
    out
}

/// A seeded stream of random `u64`s (ChaCha8): reproducible.
fn seeded(seed: u64) -> impl FnMut() -> u64 {
    use rand::{Rng, SeedableRng};
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
    move || rng.next_u64()
}
