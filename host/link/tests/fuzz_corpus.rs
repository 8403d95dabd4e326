//! The `link_rx` fuzz target's inputs as normal tests on stable Rust: its
//! seed corpus, every committed regression input, and seeded random streams
//! and bit flips; and that the seeds take the session as far as Arm.

include!("../../../fuzz/harness/link_rx.rs");
include!("../../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    let corpus = inputs("corpus/link_rx");
    assert!(corpus.len() >= 3);
    let mut ends = Vec::new();
    for data in corpus.iter().chain(inputs("regressions/link_rx").iter()) {
        ends.push(fuzz_link_rx(data).ended);
    }
    // A recorded upload's drive frames take the session through
    // configuration, sync and filling to Arm, not only to a timeout in
    // discovery; the feed seed stops it on request.
    assert!(
        ends.iter()
            .any(|e| matches!(e, Some(Err(m)) if m.contains("Arm"))),
        "{ends:?}"
    );
    assert!(ends.contains(&Some(Ok(false))), "{ends:?}");
}

#[test]
fn seeded_random_streams_and_flips_pass() {
    let mut next = seeded(0xA076_1D64_78BD_642F);
    let corpus = inputs("corpus/link_rx");
    for i in 0..60 {
        let mut data = if i % 2 == 0 {
            corpus[i / 2 % corpus.len()].clone()
        } else {
            (0..(next() % 400)).map(|_| next() as u8).collect()
        };
        for _ in 0..(next() % 8) {
            if data.is_empty() {
                break;
            }
            let k = (next() as usize) % data.len();
            data[k] ^= 1 << (next() % 8);
        }
        fuzz_link_rx(&data);
    }
}
