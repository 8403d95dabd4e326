//! The `plan` fuzz target's inputs as normal tests on stable Rust: its seed
//! corpus, every committed regression input, and seeded mutations of them
//! (digits, signs and structure of the JSON).

include!("../../../fuzz/harness/plan.rs");
include!("../../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    let corpus = inputs("corpus/plan");
    assert!(corpus.len() >= 3);
    let mut loaded = 0;
    for data in corpus.iter().chain(inputs("regressions/plan").iter()) {
        fuzz_plan(data);
        loaded += usize::from(
            triquint_planner::files::parse_plan(std::str::from_utf8(data).unwrap()).is_ok(),
        );
    }
    // The seeds reach `check`, not only the loader's refusals.
    assert!(loaded >= 3, "only {loaded} seeds load");
}

#[test]
fn seeded_mutations_pass() {
    let mut next = seeded(0xD1B5_4A32_D192_ED03);
    let corpus = inputs("corpus/plan");
    let alphabet = b"0123456789-+.eE,:[]{}\"nul";
    for i in 0..300 {
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
        fuzz_plan(&data);
    }
}
