//! The `job` fuzz target's inputs as a normal test on stable Rust: its seed
//! corpus (the example jobs and a few more), every committed regression
//! input, and 2,000 seeded mutations of them.

include!("../../fuzz/harness/job.rs");

fn inputs(dir: &str) -> Vec<Vec<u8>> {
    let root = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../fuzz")
        .join(dir);
    let mut out = Vec::new();
    for e in std::fs::read_dir(&root).unwrap_or_else(|e| panic!("{}: {e}", root.display())) {
        let p = e.unwrap().path();
        if p.is_file()
            && !p
                .file_name()
                .is_some_and(|n| n.to_string_lossy().starts_with('.'))
        {
            out.push(std::fs::read(&p).unwrap());
        }
    }
    out
}

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
    let mut x: u64 = 0x2545_F491_4F6C_DD1D;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
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
