//! Bounded reads of the binaries' own input files (machine files, replay
//! logs): a file, FIFO or standard input larger than its kind's limit is
//! refused with a clear error instead of being read whole into memory.
//! Each limit is many times the largest legitimate file (docs/cli.md,
//! "Errors, output files and input limits"); job, points and plan files are bounded by the planner. The
//! reader is shared's `bounded_read`, the planner's too.

/// A machine file: five tables of a few dozen keys are under 4 KiB.
pub const MAX_MACHINE_BYTES: u64 = 64 * 1024;

/// A candump log replayed by `monitor --web --replay`: a saturated bus
/// (1 Mbit/s, about 8 000 frames/s at about 40 bytes a line) for ten
/// minutes is under 200 MiB.
pub const MAX_LOG_BYTES: u64 = 256 * 1024 * 1024;

pub use triquint_shared::bounded_read::{bytes, read_text};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_limits_read_as_whole_units() {
        assert_eq!(bytes(MAX_LOG_BYTES), "256 MiB");
        assert_eq!(bytes(MAX_MACHINE_BYTES), "64 KiB");
    }
}
