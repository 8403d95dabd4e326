//! Bounded reads of input files (`std` only): a file, FIFO or standard
//! input larger than its kind's limit is refused with a clear error instead
//! of being read whole into memory. The limits are the readers' own (the
//! planner's job, points and plan files; the binaries' robot files and
//! replay logs); this is the one reader they share.

use std::format;
use std::io::{self, Read};
use std::path::Path;
use std::string::{String, ToString};
use std::vec::Vec;

/// `limit` in the largest whole unit (MiB, KiB or bytes), for messages.
pub fn bytes(limit: u64) -> String {
    match limit {
        n if n >= 1 << 20 && n % (1 << 20) == 0 => format!("{} MiB", n >> 20),
        n if n >= 1 << 10 && n % (1 << 10) == 0 => format!("{} KiB", n >> 10),
        n => format!("{n} bytes"),
    }
}

/// Reads UTF-8 text of at most `limit` bytes from `path` (a file, a FIFO,
/// `/dev/stdin`); `what` names the kind of file in the error ("a plan
/// file").
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

/// The `std::io::Error` text without the trailing " (os error N)", for
/// one-line messages.
pub fn io_reason(e: &io::Error) -> String {
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
        let e = read_text(Path::new("/dev/zero"), 1024, "a robot file").unwrap_err();
        assert_eq!(
            e.to_string(),
            "larger than 1 KiB, the limit for a robot file"
        );
        let p = std::env::temp_dir().join(format!("triquint-bounded-{}", std::process::id()));
        std::fs::write(&p, "a".repeat(2048)).unwrap();
        assert_eq!(read_text(&p, 2048, "x").unwrap().len(), 2048);
        assert!(read_text(&p, 2047, "x").is_err());
        std::fs::write(&p, [0xff, 0xfe]).unwrap();
        assert_eq!(
            read_text(&p, 1024, "x").unwrap_err().to_string(),
            "not UTF-8 text"
        );
        std::fs::remove_file(&p).unwrap();
        assert_eq!(bytes(4 << 20), "4 MiB");
        assert_eq!(bytes(256 * 1024 * 1024), "256 MiB");
        assert_eq!(bytes(1000), "1000 bytes");
        assert_eq!(
            io_reason(&io::Error::from_raw_os_error(2)),
            "No such file or directory"
        );
    }
}
