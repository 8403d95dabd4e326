// Shared by the `job` fuzz target and host/planner/tests/fuzz_corpus.rs (via
// include!): any bytes as a job file are either refused with a one-line
// error or give a job whose via-points are finite and at least two.

/// Runs one fuzz input.
pub fn fuzz_job(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match triquint_planner::Job::from_toml(text) {
        Ok(job) => {
            let pts = job.points_m();
            assert!(pts.len() >= 2);
            assert!(pts.iter().all(|p| p.iter().all(|x| x.is_finite())));
        }
        Err(e) => assert!(!e.to_string().contains('\n'), "{e}"),
    }
}
