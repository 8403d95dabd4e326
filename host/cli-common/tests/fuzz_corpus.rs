//! The `machine_file` fuzz target's inputs as normal tests on stable Rust: its
//! seed corpus, every committed regression input, and seeded mutations.

include!("../../../fuzz/harness/machine_file.rs");
include!("../../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    replay("machine_file", 4, fuzz_machine_file);
}

#[test]
fn seeded_mutations_pass() {
    let alphabet = b"0123456789-+.eE=[],\n #\"infa_[]axis.ceilings";
    mutations(
        "machine_file",
        0xE703_7ED1_A0B4_28DB,
        1000,
        4,
        alphabet,
        fuzz_machine_file,
    );
}
