//! The `frames` fuzz target's inputs as a normal test on stable Rust: its
//! seed corpus, every committed regression input, and 3,000 seeded random
//! streams and mutations (the long libFuzzer run is documented in the README).

include!("../../fuzz/harness/frames.rs");
include!("../../fuzz/harness/corpus.rs");

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
    let mut next = xorshift(0x9E37_79B9_7F4A_7C15);
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
