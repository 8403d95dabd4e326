//! The `web` fuzz target's inputs as normal tests on stable Rust: its seed
//! corpus, every committed regression input, and seeded mutations; and that
//! the seeds reach the routes, not only hyper's refusals.

include!("../../fuzz/harness/web.rs");
include!("../../fuzz/harness/corpus.rs");

#[test]
fn corpus_and_regressions_pass() {
    let mut statuses = Vec::new();
    replay("web", 10, |data| statuses.push(fuzz_web(data)));
    for want in [200, 400, 403, 404, 405, 409, 421] {
        assert!(statuses.contains(&Some(want)), "no {want} in {statuses:?}");
    }
}

#[test]
fn seeded_mutations_pass() {
    let alphabet = b"GETPOSHD /api?=&:.0123456789\r\n\r\nHost: 127.0.0.1:8080OriginContent-Length";
    mutations("web", 0x94D0_49BB_1331_11EB, 300, 4, alphabet, |d| {
        fuzz_web(d);
    });
}
