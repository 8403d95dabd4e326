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

/// Every seed of `fuzz/corpus/<target>` (at least `min_seeds` of them) and
/// every committed input of `fuzz/regressions/<target>` through `run`.
#[allow(dead_code)]
fn replay(target: &str, min_seeds: usize, mut run: impl FnMut(&[u8])) {
    let corpus = inputs(&format!("corpus/{target}"));
    assert!(
        corpus.len() >= min_seeds,
        "{} seeds in corpus/{target}, want {min_seeds}",
        corpus.len()
    );
    for data in corpus.iter().chain(inputs(&format!("regressions/{target}")).iter()) {
        run(data);
    }
}

/// `rounds` seeded mutations of the seeds of `fuzz/corpus/<target>` through
/// `run`: each changes, inserts or removes 1 to `max_edits` bytes, new
/// bytes drawn from `alphabet` (the input language's, so that mutants get
/// past the first token often).
#[allow(dead_code)]
fn mutations(
    target: &str,
    seed: u64,
    rounds: usize,
    max_edits: u64,
    alphabet: &[u8],
    mut run: impl FnMut(&[u8]),
) {
    let mut next = seeded(seed);
    let corpus = inputs(&format!("corpus/{target}"));
    for i in 0..rounds {
        let mut data = corpus[i % corpus.len()].clone();
        for _ in 0..(1 + next() % max_edits) {
            let k = (next() as usize) % data.len().max(1);
            let c = alphabet[(next() as usize) % alphabet.len()];
            match next() % 3 {
                0 if k < data.len() => data[k] = c,
                1 => data.insert(k.min(data.len()), c),
                _ if k < data.len() => {
                    data.remove(k);
                }
                _ => {}
            }
        }
        run(&data);
    }
}

/// `rounds` seeded inputs through `run`, for binary protocols: by turns a
/// seed of `fuzz/corpus/<target>` and random bytes (shorter than
/// `max_len`), each with up to 7 bits flipped.
#[allow(dead_code)]
fn streams_and_flips(
    target: &str,
    seed: u64,
    rounds: usize,
    max_len: u64,
    mut run: impl FnMut(&[u8]),
) {
    let mut next = seeded(seed);
    let corpus = inputs(&format!("corpus/{target}"));
    for i in 0..rounds {
        let mut data = if i % 2 == 0 {
            corpus[i / 2 % corpus.len()].clone()
        } else {
            (0..(next() % max_len)).map(|_| next() as u8).collect()
        };
        for _ in 0..(next() % 8) {
            if data.is_empty() {
                break;
            }
            let k = (next() as usize) % data.len();
            data[k] ^= 1 << (next() % 8);
        }
        run(&data);
    }
}
