//! The `job` fuzz target's inputs as a normal test on stable Rust: its seed
//! corpus (the example jobs and a few more), every committed regression
//! input, and 2,000 seeded mutations of them.

include!("../../fuzz/harness/job.rs");
include!("../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    let corpus = inputs("corpus/job");
    assert!(corpus.len() >= 4);
    for data in corpus.iter().chain(inputs("regressions/job").iter()) {
        fuzz_job(data);
    }
}

#[test]
fn seeded_mutations_pass() {
    let mut next = xorshift(0x2545_F491_4F6C_DD1D);
    let corpus = inputs("corpus/job");
    let alphabet = b"[]=,.-+0123456789eEnaifINF\"\n #xyzmpu";
    for i in 0..2000 {
        let mut data = corpus[i % corpus.len()].clone();
        for _ in 0..(1 + next() % 6) {
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
        fuzz_job(&data);
    }
}
