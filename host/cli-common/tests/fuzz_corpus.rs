//! The `robot_file` fuzz target's inputs as normal tests on stable Rust: its
//! seed corpus, every committed regression input, and seeded mutations.

include!("../../../fuzz/harness/robot_file.rs");
include!("../../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    let corpus = inputs("corpus/robot_file");
    assert!(corpus.len() >= 4);
    for data in corpus.iter().chain(inputs("regressions/robot_file").iter()) {
        fuzz_robot_file(data);
    }
}

#[test]
fn seeded_mutations_pass() {
    let mut next = seeded(0xE703_7ED1_A0B4_28DB);
    let corpus = inputs("corpus/robot_file");
    let alphabet = b"0123456789-+.eE=[],\n #\"infa_homing";
    for i in 0..1000 {
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
        fuzz_robot_file(&data);
    }
}
