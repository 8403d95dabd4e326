//! The `link_rx` fuzz target's inputs as normal tests on stable Rust: its
//! seed corpus, every committed regression input, and seeded random streams
//! and bit flips; and that the seeds take the session as far as Arm.

include!("../../../fuzz/harness/link_rx.rs");
include!("../../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    let mut ends = Vec::new();
    replay("link_rx", 3, |data| ends.push(fuzz_link_rx(data).ended));
    // A recorded upload's drive frames take the session through
    // configuration, sync and filling to Arm, not only to a timeout in
    // discovery; the feed seed stops it on request.
    assert!(
        ends.iter()
            .any(|e| matches!(e, Some(Err(m)) if m.contains("Arm"))),
        "{ends:?}"
    );
    assert!(ends.contains(&Some(Ok(false))), "{ends:?}");
}

#[test]
fn seeded_random_streams_and_flips_pass() {
    streams_and_flips("link_rx", 0xA076_1D64_78BD_642F, 60, 400, |d| {
        fuzz_link_rx(d);
    });
}
