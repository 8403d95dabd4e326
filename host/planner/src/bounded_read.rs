//! The size limits of the planner's input files: a job, points or plan file
//! (or a FIFO, or `/dev/stdin`) larger than its kind's limit is refused
//! with a clear error instead of being read whole into memory (the reader
//! is shared's `bounded_read`). Each limit is several times the largest
//! legitimate file (docs/cli.md, "Errors, output files and input limits").

/// A job file: [`crate::job::MAX_POINTS`] via-points inline at about 40 bytes
/// each are under 100 KiB; the limit leaves room for a comment per point.
pub const MAX_JOB_BYTES: u64 = 4 << 20;

/// A points file (`[path] file`): [`crate::job::MAX_POINTS`] lines of full-precision
/// numbers (about 70 bytes) are under 150 KiB; the limit leaves room for
/// long comments.
pub const MAX_POINTS_FILE_BYTES: u64 = 4 << 20;

/// A plan file: about 1.2 KiB a segment written by the planner, so the
/// largest plan it writes (2 000 via-points, 1 999 segments) is under
/// 2.5 MiB; the limit leaves six times that for fields later formats add.
pub const MAX_PLAN_BYTES: u64 = 16 << 20;

pub(crate) use triquint_shared::bounded_read::io_reason;
pub use triquint_shared::bounded_read::read_text;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_endless_plan_stops_at_its_limit() {
        let e = read_text(
            std::path::Path::new("/dev/zero"),
            MAX_PLAN_BYTES,
            "a plan file",
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "larger than 16 MiB, the limit for a plan file"
        );
    }
}
