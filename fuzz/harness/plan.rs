// Shared by the `plan` fuzz target and host/planner/tests/fuzz_plan_corpus.rs
// (via include!): any bytes as a plan file go through the one plan loader
// and, when it accepts them, through the independent verifier, as
// `triquint check` and `triquint upload` do.

/// Runs one fuzz input: the loader refuses with a one-line error or gives a
/// plan that `check` takes without a load error; a row whose figure is not
/// a number never passes.
pub fn fuzz_plan(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let plan = match triquint_planner::files::parse_plan(text) {
        Ok(plan) => plan,
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.is_empty() && !msg.contains('\n'), "{msg:?}");
            return;
        }
    };
    match triquint_planner::check(&plan) {
        Ok(rows) => {
            assert!(!rows.is_empty());
            for r in &rows {
                assert!(!(r.value.is_nan() && r.ok), "NaN passes: {r:?}");
            }
        }
        // Loaded plans are structurally valid, so only the torque
        // evaluation may refuse one (a pose out of reach).
        Err(e) => assert!(
            matches!(e, triquint_planner::files::LoadError::Invalid(_)),
            "check refused a loaded plan: {e}"
        ),
    }
}
