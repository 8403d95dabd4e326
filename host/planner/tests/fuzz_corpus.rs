//! The `job` and `points` fuzz targets' inputs as normal tests on stable
//! Rust: their seed corpora, every committed regression input, and seeded
//! mutations of them.

include!("../../../fuzz/harness/job.rs");
include!("../../../fuzz/harness/points.rs");
include!("../../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    replay("job", 4, fuzz_job);
}

#[test]
fn seeded_mutations_pass() {
    let alphabet = b"[]=,.-+0123456789eEnaifINF\"\n #xyzmpu";
    mutations("job", 0x2545_F491_4F6C_DD1D, 2000, 6, alphabet, fuzz_job);
}

/// Bytes that make up points files, so that random inputs get past the first line often.
const POINTS_ALPHABET: &[u8] =
    b"0123456789012345678901234567890123456789,,,,    \t\n\n\n\r#..--+eEexyznaif";

#[test]
fn points_corpus_and_random_inputs_pass() {
    replay("points", 1, fuzz_points);
    let mut next = seeded(0x9E37_79B9_7F4A_7C15);
    let mut oks = 0;
    for i in 0..100_000 {
        let len = (next() % 80) as usize;
        let data: Vec<u8> = (0..len)
            .map(|_| match i % 4 {
                0 => next() as u8,
                _ => POINTS_ALPHABET[(next() as usize) % POINTS_ALPHABET.len()],
            })
            .collect();
        fuzz_points(&data);
        oks += usize::from(
            triquint_planner::files::parse_points(std::str::from_utf8(&data).unwrap_or("")).is_ok(),
        );
    }
    assert!(oks > 100, "only {oks} inputs parsed");
    for text in [
        "1,,2,3",
        "1e999,0,0",
        "1 2",
        "1 2 3 4",
        "#",
        "x,y,z\nx,y,z",
        "",
        "\r\n",
        ",",
        "1,2,3\r\r\n",
        "nan,nan,nan",
        "inf inf inf",
        "\u{feff}",
        "1 2 3 # a # b",
        "1\u{a0}2\u{a0}3",
        "１ ２ ３",
        "1_000 2 3",
        "1e-400 0 0",
        "0x1 2 3",
    ] {
        fuzz_points(text.as_bytes());
    }
}
