//! The `frames` fuzz target's inputs as a normal test on stable Rust: its
//! seed corpus, every committed regression input, and 3,000 seeded random
//! streams and mutations (the long libFuzzer run is documented in the README).

include!("../../fuzz/harness/frames.rs");

fn inputs(dir: &str) -> Vec<Vec<u8>> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz")
        .join(dir);
    let mut out = Vec::new();
    for e in std::fs::read_dir(&root).unwrap_or_else(|e| panic!("{}: {e}", root.display())) {
        let p = e.unwrap().path();
        if p.is_file()
            && !p
                .file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        {
            out.push(std::fs::read(&p).unwrap());
        }
    }
    out
}

#[test]
fn corpus_and_regressions_pass() {
    let corpus = inputs("corpus/frames");
    assert!(corpus.len() >= 3);
    for data in corpus.iter().chain(inputs("regressions/frames").iter()) {
        fuzz_frames(data);
    }
}

#[test]
fn seeded_random_streams_and_mutations_pass() {
    // xorshift: no dependency, reproducible.
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    let corpus = inputs("corpus/frames");
    for i in 0..3000 {
        let mut data = if i % 2 == 0 {
            corpus[i / 2 % corpus.len()].clone()
        } else {
            (0..(next() % 600)).map(|_| next() as u8).collect()
        };
        for _ in 0..(next() % 8) {
            if data.is_empty() {
                break;
            }
            let k = (next() as usize) % data.len();
            data[k] ^= 1 << (next() % 8);
        }
        fuzz_frames(&data);
    }
}
