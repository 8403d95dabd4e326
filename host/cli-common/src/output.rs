//! Where a command's results go: output files replaced atomically and
//! safely, and standard output that may be a closed pipe or a full disk.
//!
//! An output file is written to a temporary file created exclusively
//! (`O_EXCL`, random name, so a planted symbolic link is never followed) in
//! the target's folder, then renamed over the target: a failing command
//! leaves the old file or none, never a partial one. A target that is not a
//! regular file (a device, FIFO, folder or symbolic link) or that is one of
//! the command's inputs is refused before anything is written.

use std::fmt;
use std::io::{self, Write};
use std::path::Path;

use crate::exit::{CliError, CliResult};

pub use triquint_shared::bounded_read::io_reason;

/// What kind of file system object a non-regular file is, for messages.
fn kind_of(meta: &std::fs::Metadata) -> &'static str {
    let t = meta.file_type();
    if t.is_symlink() {
        return "a symbolic link";
    }
    if t.is_dir() {
        return "a folder";
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_char_device() || t.is_block_device() {
            return "a device";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    "not a regular file"
}

/// Whether two metadata describe the same file (hard links included).
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        a.dev() == b.dev() && a.ino() == b.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (a, b);
        false
    }
}

fn refused(reason: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, reason)
}

/// Checks that `path` may be replaced by an output: it does not exist yet,
/// or it is a regular file (not through a symbolic link) that is none of
/// `inputs`. Nothing is created. Commands call it before their work, so a
/// refused output costs nothing.
pub fn check_target(path: &Path, inputs: &[&Path]) -> io::Result<()> {
    if path.file_name().is_none() {
        return Err(refused("not a file name".into()));
    }
    let meta = match std::fs::symlink_metadata(path) {
        Ok(m) => m,
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        Err(e) => return Err(e),
    };
    if !meta.file_type().is_file() {
        return Err(refused(format!(
            "is {}, not a regular file; outputs replace regular files only",
            kind_of(&meta)
        )));
    }
    for input in inputs {
        if let Ok(m) = std::fs::metadata(input)
            && same_file(&meta, &m)
        {
            return Err(refused(format!(
                "is also an input of this command ({}); choose another output",
                input.display()
            )));
        }
    }
    Ok(())
}

/// Writes `contents` to an exclusive temporary file in `path`'s folder
/// (created if missing), after [`check_target`]. A new file gets the usual
/// permissions (0666 less the umask).
fn stage(path: &Path, contents: &[u8], inputs: &[&Path]) -> io::Result<tempfile::NamedTempFile> {
    check_target(path, inputs)?;
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    std::fs::create_dir_all(dir)?;
    let prefix = format!(
        ".{}.",
        path.file_name().unwrap_or_default().to_string_lossy()
    );
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        builder.permissions(std::fs::Permissions::from_mode(0o666));
    }
    let mut tmp = builder.tempfile_in(dir)?;
    tmp.write_all(contents)?;
    // A full disk can show only when the data is written out.
    tmp.as_file().sync_all()?;
    Ok(tmp)
}

/// Replaces each file with its contents: every one is first written to its
/// temporary file, and only when all are written are they renamed into
/// place, so a failure (a full disk, a refused target) leaves none of them
/// changed. On error, the path it is about.
pub fn replace_files(
    files: &[(&Path, &[u8])],
    inputs: &[&Path],
) -> Result<(), (std::path::PathBuf, io::Error)> {
    let mut staged = Vec::with_capacity(files.len());
    for (path, contents) in files {
        let tmp = stage(path, contents, inputs).map_err(|e| (path.to_path_buf(), e))?;
        staged.push((path, tmp));
    }
    for (path, tmp) in staged {
        tmp.persist(path)
            .map_err(|e| (path.to_path_buf(), e.error))?;
    }
    Ok(())
}

/// Replaces `path` with `contents` (see [`replace_files`]).
pub fn replace_file(path: &Path, contents: &[u8], inputs: &[&Path]) -> io::Result<()> {
    replace_files(&[(path, contents)], inputs).map_err(|(_, e)| e)
}

/// [`replace_file`] with no inputs to protect; any failure is bad input
/// (exit 2) naming the path.
pub fn write_atomic(path: &Path, contents: &[u8]) -> CliResult {
    write_outputs(&[(path, contents)], &[])
}

/// [`replace_file`]; any failure is bad input (exit 2) naming the path.
pub fn write_output(path: &Path, contents: &[u8], inputs: &[&Path]) -> CliResult {
    write_outputs(&[(path, contents)], inputs)
}

/// [`replace_files`]; any failure is bad input (exit 2) naming the path.
pub fn write_outputs(files: &[(&Path, &[u8])], inputs: &[&Path]) -> CliResult {
    replace_files(files, inputs).map_err(|(path, e)| output_error(&path, &e))
}

/// The one-line error of an output that cannot be written.
pub fn output_error(path: &Path, e: &io::Error) -> CliError {
    CliError::bad_input(format!("{}: {}", path.display(), io_reason(e)))
}

/// What a failed write to standard output means: a closed pipe (the reader
/// has all it wanted, as with `| head`) ends the process quietly with
/// status 0, as ripgrep does, since nothing more can reach the reader;
/// anything else (a full disk) is bad input (exit 2).
pub fn stdout_error(e: &io::Error) -> CliError {
    if e.kind() == io::ErrorKind::BrokenPipe {
        std::process::exit(0);
    }
    CliError::bad_input(format!("cannot write standard output: {}", io_reason(e)))
}

/// Writes to standard output and flushes, so that a closed pipe or a full
/// disk is seen here (see [`stdout_error`]) instead of panicking in
/// `print!`.
pub fn write_stdout(args: fmt::Arguments<'_>) -> CliResult {
    let mut out = io::stdout().lock();
    out.write_fmt(args)
        .and_then(|()| out.flush())
        .map_err(|e| stdout_error(&e))
}

/// `println!` for commands: a [`CliResult`] instead of a panic when
/// standard output is closed or full (see [`write_stdout`]).
#[macro_export]
macro_rules! outln {
    () => {
        $crate::output::write_stdout(format_args!("\n"))
    };
    ($($arg:tt)*) => {
        $crate::output::write_stdout(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// Writes a message to standard error, ignoring failure: a closed or full
/// standard error (`2>&-`) must not turn an error or a progress line into
/// a panic (as `eprintln!` does), and there is nowhere left to report it.
pub fn write_stderr(args: fmt::Arguments<'_>) {
    let _ = io::stderr().lock().write_fmt(args);
}

/// `eprintln!` for commands: never panics (see [`write_stderr`]).
#[macro_export]
macro_rules! errln {
    ($($arg:tt)*) => {
        $crate::output::write_stderr(format_args!("{}\n", format_args!($($arg)*)))
    };
}

/// `print!` for commands, as [`outln!`] without the newline.
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {
        $crate::output::write_stdout(format_args!($($arg)*))
    };
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exit::Status;

    fn scratch(name: &str) -> std::path::PathBuf {
        let dir =
            std::env::temp_dir().join(format!("triquint-output-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        dir
    }

    #[test]
    fn atomic_write_leaves_the_file_or_nothing() {
        let dir = scratch("atomic");
        let path = dir.join("sub").join("out.json");
        write_atomic(&path, b"{}").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"{}");
        write_atomic(&path, b"[]").unwrap();
        assert_eq!(std::fs::read(&path).unwrap(), b"[]");
        // A folder where the file should be: bad input, no temporary left.
        let e = write_atomic(&dir.join("sub"), b"x").unwrap_err();
        assert_eq!(e.status, Status::BadInput);
        assert!(e.message.contains("a folder"), "{}", e.message);
        let left: Vec<_> = std::fs::read_dir(dir.join("sub"))
            .unwrap()
            .flatten()
            .collect();
        assert_eq!(left.len(), 1, "{left:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn symbolic_links_are_neither_followed_nor_replaced() {
        let dir = scratch("links");
        let target = dir.join("target");
        std::fs::write(&target, b"keep").unwrap();
        let link = dir.join("out.json");
        std::os::unix::fs::symlink(&target, &link).unwrap();
        let e = write_atomic(&link, b"plan").unwrap_err();
        assert!(e.message.contains("a symbolic link"), "{}", e.message);
        assert_eq!(std::fs::read(&target).unwrap(), b"keep");
        assert!(
            std::fs::symlink_metadata(&link)
                .unwrap()
                .file_type()
                .is_symlink()
        );
        // Links planted at the old predictable temporary names are ignored.
        let out = dir.join("plan.json");
        for pid in [std::process::id(), 1, 2] {
            std::os::unix::fs::symlink(&target, dir.join(format!(".plan.json.tmp{pid}"))).unwrap();
        }
        write_atomic(&out, b"plan").unwrap();
        assert_eq!(std::fs::read(&out).unwrap(), b"plan");
        assert_eq!(std::fs::read(&target).unwrap(), b"keep");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn several_outputs_are_all_written_or_none() {
        let dir = scratch("several");
        let (a, b) = (dir.join("a.svg"), dir.join("b.svg"));
        std::fs::write(&a, b"old").unwrap();
        std::fs::create_dir(&b).unwrap();
        let e = write_outputs(&[(&a, b"new"), (&b, b"new")], &[]).unwrap_err();
        assert!(
            e.message.starts_with(&b.display().to_string()),
            "{}",
            e.message
        );
        assert_eq!(std::fs::read(&a).unwrap(), b"old");
        assert_eq!(std::fs::read_dir(&dir).unwrap().count(), 2);
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn an_input_is_never_an_output() {
        let dir = scratch("inputs");
        let job = dir.join("job.toml");
        std::fs::write(&job, b"job").unwrap();
        let e = write_output(&job, b"plan", &[&job]).unwrap_err();
        assert!(e.message.contains("also an input"), "{}", e.message);
        // The same file by another name.
        let other = dir.join(".").join("job.toml");
        assert!(write_output(&other, b"plan", &[&job]).is_err());
        assert_eq!(std::fs::read(&job).unwrap(), b"job");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[cfg(unix)]
    #[test]
    fn new_files_get_the_usual_permissions() {
        use std::os::unix::fs::PermissionsExt;
        let dir = scratch("mode");
        let path = dir.join("out.json");
        write_atomic(&path, b"{}").unwrap();
        let mode = std::fs::metadata(&path).unwrap().permissions().mode();
        // 0666 less the umask, as `File::create` makes it (not the 0600 of a temporary).
        let umask = std::fs::read_to_string("/proc/self/status")
            .ok()
            .and_then(|s| {
                let line = s.lines().find(|l| l.starts_with("Umask:"))?;
                u32::from_str_radix(line["Umask:".len()..].trim(), 8).ok()
            });
        if let Some(umask) = umask {
            assert_eq!(mode & 0o777, 0o666 & !umask, "{mode:o}");
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn io_reasons_are_one_line_without_the_code() {
        let e = io::Error::from_raw_os_error(28);
        assert_eq!(io_reason(&e), "No space left on device");
    }
}
