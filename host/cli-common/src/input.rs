//! Bounded reads of the binaries' own input files (robot files, replay
//! logs): a file, FIFO or standard input larger than its kind's limit is
//! refused with a clear error instead of being read whole into memory.
//! Each limit is many times the largest legitimate file (README, "Exit
//! status"); job, points and plan files are bounded by the planner.

use std::io::{self, Read};
use std::path::Path;

/// A `--robot` file: a dozen keys and a `[homing]` table are under 2 KiB.
pub const MAX_ROBOT_BYTES: u64 = 64 * 1024;

/// A candump log replayed by `monitor --web --replay`: a saturated bus
/// (1 Mbit/s, about 8 000 frames/s at about 40 bytes a line) for ten
/// minutes is under 200 MiB.
pub const MAX_LOG_BYTES: u64 = 256 * 1024 * 1024;

/// `limit` in the largest whole unit, for messages.
pub fn bytes(limit: u64) -> String {
    match limit {
        n if n >= 1 << 20 && n % (1 << 20) == 0 => format!("{} MiB", n >> 20),
        n if n >= 1 << 10 && n % (1 << 10) == 0 => format!("{} KiB", n >> 10),
        n => format!("{n} bytes"),
    }
}

/// Reads UTF-8 text of at most `limit` bytes from `path` (a file, a FIFO,
/// `/dev/stdin`); `what` names the kind of file in the error.
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn over_the_limit_is_refused_without_reading_on() {
        let e = read_text(Path::new("/dev/zero"), 1024, "a robot file").unwrap_err();
        assert_eq!(
            e.to_string(),
            "larger than 1 KiB, the limit for a robot file"
        );
        let p = std::env::temp_dir().join(format!("triquint-input-{}", std::process::id()));
        std::fs::write(&p, "a".repeat(1024)).unwrap();
        assert_eq!(read_text(&p, 1024, "x").unwrap().len(), 1024);
        assert!(read_text(&p, 1023, "x").is_err());
        std::fs::write(&p, [0xff, 0xfe]).unwrap();
        assert_eq!(
            read_text(&p, 1024, "x").unwrap_err().to_string(),
            "not UTF-8 text"
        );
        std::fs::remove_file(&p).unwrap();
        assert_eq!(bytes(MAX_LOG_BYTES), "256 MiB");
        assert_eq!(bytes(1000), "1000 bytes");
    }
}
