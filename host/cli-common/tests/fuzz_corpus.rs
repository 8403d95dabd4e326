//! The `robot_file` fuzz target's inputs as normal tests on stable Rust: its
//! seed corpus, every committed regression input, and seeded mutations.

include!("../../../fuzz/harness/robot_file.rs");
include!("../../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    replay("robot_file", 4, fuzz_robot_file);
}

#[test]
fn seeded_mutations_pass() {
    let alphabet = b"0123456789-+.eE=[],\n #\"infa_homing";
    mutations(
        "robot_file",
        0xE703_7ED1_A0B4_28DB,
        1000,
        4,
        alphabet,
        fuzz_robot_file,
    );
}
