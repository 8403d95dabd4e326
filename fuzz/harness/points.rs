// Shared by the `points` fuzz target and host/planner/tests/fuzz_corpus.rs
// (via include!): the points-file reader's contract on any bytes.

use triquint_planner::files::parse_points;

/// Feeds `data` (when it is UTF-8) to [`parse_points`] and checks the
/// contract: success means at least one point, all coordinates finite;
/// failure means a one-line message that names the line the error has.
///
fn fuzz_points(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    match parse_points(text) {
        Ok(points) => {
            assert!(!points.is_empty(), "Ok with no points");
            assert!(
                points.iter().flatten().all(|x| x.is_finite()),
                "non-finite point accepted"
            );
        }
        Err(e) => {
            let msg = e.to_string();
            assert!(!msg.contains(['\n', '\r']), "multi-line message {msg:?}");
            if let Some(line) = e.line() {
                assert!(line >= 1, "line 0 in {msg:?}");
                assert!(
                    msg.starts_with(&format!("line {line}: ")),
                    "{msg:?} does not name line {line}"
                );
            }
        }
    }
}
