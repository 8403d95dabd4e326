//! The `plan` fuzz target's inputs as normal tests on stable Rust: its seed
//! corpus, every committed regression input, and seeded mutations of them
//! (digits, signs and structure of the JSON).

include!("../../../fuzz/harness/plan.rs");
include!("../../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    let mut loaded = 0;
    replay("plan", 3, |data| {
        fuzz_plan(data);
        loaded += usize::from(
            triquint_planner::files::parse_plan(std::str::from_utf8(data).unwrap()).is_ok(),
        );
    });
    // The seeds reach `check`, not only the loader's refusals.
    assert!(loaded >= 3, "only {loaded} seeds load");
}

#[test]
fn seeded_mutations_pass() {
    let alphabet = b"0123456789-+.eE,:[]{}\"nul";
    mutations("plan", 0xD1B5_4A32_D192_ED03, 300, 4, alphabet, fuzz_plan);
}
