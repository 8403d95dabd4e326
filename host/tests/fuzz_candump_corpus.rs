//! The `candump` fuzz target's inputs as normal tests on stable Rust: its
//! seed corpus, every committed regression input, and seeded mutations.

use triquint_host::web::candump;

include!("../../fuzz/harness/candump.rs");
include!("../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    replay("candump", 3, fuzz_candump);
}

#[test]
fn seeded_mutations_pass() {
    let alphabet = b"0123456789ABCDEFabcdef#.() \n\rR+-v";
    mutations(
        "candump",
        0x8EBC_6AF0_9C88_C6E3,
        5000,
        4,
        alphabet,
        fuzz_candump,
    );
}
