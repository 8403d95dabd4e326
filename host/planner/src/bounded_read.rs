//! Bounded reads of the planner's input files: a job, points or plan file
//! (or a FIFO, or `/dev/stdin`) larger than its kind's limit is refused
//! with a clear error instead of being read whole into memory. Each limit
//! is several times the largest legitimate file (README, "Exit status").

use std::io::{self, Read};
use std::path::Path;

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

/// `limit` in MiB or KiB, for messages.
fn bytes(limit: u64) -> String {
    if limit >= 1 << 20 && limit % (1 << 20) == 0 {
        format!("{} MiB", limit >> 20)
    } else if limit >= 1 << 10 && limit % (1 << 10) == 0 {
        format!("{} KiB", limit >> 10)
    } else {
        format!("{limit} bytes")
    }
}

/// Reads UTF-8 text of at most `limit` bytes from `path`; `what` names the
/// kind of file in the error ("a plan file").
pub fn read_text(path: &Path, limit: u64, what: &str) -> io::Result<String> {
    let mut buf = Vec::new();
    std::fs::File::open(path)?
        .take(limit + 1)
        .read_to_end(&mut buf)?;
    if buf.len() as u64 > limit {
        return Err(io::Error::new(
            io::ErrorKind::InvalidData,
            format!("larger than {}, the limit for {what}", bytes(limit)),
        ));
    }
    String::from_utf8(buf).map_err(|_| io::Error::new(io::ErrorKind::InvalidData, "not UTF-8 text"))
}

/// The `std::io::Error` text without the trailing " (os error N)".
pub(crate) fn io_reason(e: &io::Error) -> String {
    let text = e.to_string();
    match text.rsplit_once(" (os error ") {
        Some((reason, _)) => reason.to_string(),
        None => text,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn endless_inputs_stop_at_the_limit() {
        let e = read_text(Path::new("/dev/zero"), MAX_PLAN_BYTES, "a plan file").unwrap_err();
        assert_eq!(
            e.to_string(),
            "larger than 16 MiB, the limit for a plan file"
        );
        let p = std::env::temp_dir().join(format!("triquint-bounded-{}", std::process::id()));
        std::fs::write(&p, "x".repeat(2048)).unwrap();
        assert_eq!(read_text(&p, 2048, "x").unwrap().len(), 2048);
        assert!(read_text(&p, 2047, "x").is_err());
        std::fs::remove_file(&p).unwrap();
        assert_eq!(bytes(MAX_JOB_BYTES), "4 MiB");
        assert_eq!(
            io_reason(&io::Error::from_raw_os_error(2)),
            "No such file or directory"
        );
    }
}
