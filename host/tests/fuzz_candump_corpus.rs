//! The `candump` fuzz target's inputs as normal tests on stable Rust: its
//! seed corpus, every committed regression input, and seeded mutations.

use triquint_host::web::candump;

include!("../../fuzz/harness/candump.rs");
include!("../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    let corpus = inputs("corpus/candump");
    assert!(corpus.len() >= 3);
    for data in corpus.iter().chain(inputs("regressions/candump").iter()) {
        fuzz_candump(data);
    }
}

#[test]
fn seeded_mutations_pass() {
    let mut next = seeded(0x8EBC_6AF0_9C88_C6E3);
    let corpus = inputs("corpus/candump");
    let alphabet = b"0123456789ABCDEFabcdef#.() \n\rR+-v";
    for i in 0..5000 {
        let mut data = corpus[i % corpus.len()].clone();
        for _ in 0..(1 + next() % 4) {
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
        fuzz_candump(&data);
    }
}
