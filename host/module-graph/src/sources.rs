//! Source files, the module each defines, and their text without tests or
//! comments.

use std::fs;
use std::path::{Path, PathBuf};

/// A module path from the crate root (empty for the root).
pub type Module = Vec<String>;

/// Every `.rs` file under `dir`, sorted.
pub fn rust_files(dir: &Path) -> Vec<PathBuf> {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let mut entries: Vec<_> = fs::read_dir(dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|e| e.expect("directory entry").path())
            .collect();
        entries.sort();
        for p in entries {
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().is_some_and(|x| x == "rs") {
                out.push(p);
            }
        }
    }
    let mut out = Vec::new();
    walk(dir, &mut out);
    out
}

/// The module a file under `src` defines (`mod.rs` stands for its
/// directory, `main.rs` and `lib.rs` at the top for the root).
pub fn module_of(src: &Path, file: &Path) -> Module {
    let rel = file.strip_prefix(src).expect("file under src");
    let mut segs: Module = rel
        .iter()
        .map(|s| s.to_string_lossy().into_owned())
        .collect();
    let last = segs.pop().expect("a file name");
    let stem = last.trim_end_matches(".rs");
    let root_file = segs.is_empty() && matches!(stem, "main" | "lib");
    if stem != "mod" && !root_file {
        segs.push(stem.to_string());
    }
    segs
}

/// The end (exclusive) of the block whose `{` is the first at or after `from`.
pub fn block_end(text: &str, from: usize) -> usize {
    let Some(open) = text[from..].find('{') else {
        return text.len();
    };
    let mut depth = 0;
    for (k, c) in text[from + open..].char_indices() {
        match c {
            '{' => depth += 1,
            '}' => {
                depth -= 1;
                if depth == 0 {
                    return from + open + k + 1;
                }
            }
            _ => {}
        }
    }
    text.len()
}

/// The text outside `#[cfg(test)]` items (a test module, a test-only `use`),
/// each item replaced by its line breaks so that line numbers stay the file's.
pub fn without_tests(text: &str) -> String {
    let mut out = String::new();
    let mut rest = text;
    while let Some(i) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..i]);
        let after = &rest[i..];
        // The item ends at its `;` or at the brace closing its first `{`.
        let semi = after.find(';').unwrap_or(after.len());
        let brace = after.find('{').unwrap_or(after.len());
        let end = if semi < brace {
            semi + 1
        } else {
            block_end(after, 0)
        };
        out.extend(after[..end].chars().filter(|c| *c == '\n'));
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// The source without `//` comments (doc comments included), so a path
/// named in prose is not an import; line breaks kept.
pub fn strip_comments(text: &str) -> String {
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) if !l[..i].contains('"') => &l[..i],
            _ => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn test_items_leave_their_line_breaks() {
        let text = "a\n#[cfg(test)]\nuse x::y;\nb\n#[cfg(test)]\nmod t {\n  fn f() {}\n}\nc\n";
        assert_eq!(without_tests(text), "a\n\n\nb\n\n\n\n\nc\n");
    }

    #[test]
    fn modules_of_files() {
        let src = Path::new("/s");
        assert!(module_of(src, Path::new("/s/lib.rs")).is_empty());
        assert_eq!(module_of(src, Path::new("/s/a/mod.rs")), ["a"]);
        assert_eq!(module_of(src, Path::new("/s/a/b.rs")), ["a", "b"]);
    }
}
