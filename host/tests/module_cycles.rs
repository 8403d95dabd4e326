//! Modules import one way: no cycle of `crate::` and `super::` paths between the modules
//! of the `triquint` binary (host/src) or of a board image
//! (firmware/boards/*/src). A cycle means two modules each need the other,
//! so neither can be read, tested or moved alone; shared logic belongs in a
//! module both use (host/src/ops for the host's bus operations).
//!
//! And a subcommand (host/src/cli) uses no other subcommand.
//!
//! A module is a source file (`mod.rs` stands for its directory). Every
//! `crate::` or `super::` path in a file, in `use` declarations or inline
//! (the inline test module excepted), is resolved
//! to the longest module prefix it names; the file's module then depends
//! on that module. Comments are skipped.

use std::collections::{BTreeMap, BTreeSet};
use std::fs;
use std::path::{Path, PathBuf};

/// Module path (segments from the crate root) → the modules it imports.
type Graph = BTreeMap<Vec<String>, BTreeSet<Vec<String>>>;

/// Every `.rs` file under `dir`.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.expect("directory entry").path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The module a file under `src` defines.
fn module_of(src: &Path, file: &Path) -> Vec<String> {
    let rel = file.strip_prefix(src).expect("file under src");
    let mut segs: Vec<String> = rel
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

/// The source without `//` comments (doc comments included), so a path
/// named in prose is not an import.
fn strip_comments(text: &str) -> String {
    text.lines()
        .map(|l| match l.find("//") {
            Some(i) if !l[..i].contains('"') => &l[..i],
            _ => l,
        })
        .collect::<Vec<_>>()
        .join("\n")
}

/// Parses a use tree at the start of `s` (just after `crate::`): its paths.
fn use_tree(s: &[u8], i: &mut usize) -> Vec<Vec<String>> {
    let skip_ws = |i: &mut usize| {
        while *i < s.len() && s[*i].is_ascii_whitespace() {
            *i += 1;
        }
    };
    let mut prefix = Vec::new();
    loop {
        skip_ws(i);
        if *i < s.len() && s[*i] == b'{' {
            *i += 1;
            let mut paths = Vec::new();
            loop {
                skip_ws(i);
                if *i >= s.len() {
                    break;
                }
                if s[*i] == b'}' {
                    *i += 1;
                    break;
                }
                if s[*i] == b',' {
                    *i += 1;
                    continue;
                }
                let before = *i;
                for p in use_tree(s, i) {
                    let mut full = prefix.clone();
                    full.extend(p);
                    paths.push(full);
                }
                if *i == before {
                    *i += 1;
                }
            }
            return paths;
        }
        let start = *i;
        while *i < s.len() && (s[*i].is_ascii_alphanumeric() || s[*i] == b'_' || s[*i] == b'*') {
            *i += 1;
        }
        if *i == start {
            return vec![prefix];
        }
        prefix.push(String::from_utf8_lossy(&s[start..*i]).into_owned());
        skip_ws(i);
        if s[*i..].starts_with(b"::") {
            *i += 2;
        } else {
            return vec![prefix];
        }
    }
}

/// Every path named after `crate::` or `super::` in `text` (a file of
/// module `module`), from the crate root.
fn crate_paths(text: &str, module: &[String]) -> Vec<Vec<String>> {
    let s = text.as_bytes();
    let mut paths = Vec::new();
    let mut from = 0;
    while let Some(k) = text[from..]
        .find("crate::")
        .into_iter()
        .chain(text[from..].find("super::"))
        .min()
    {
        let at = from + k;
        let word_start = at == 0
            || !(s[at - 1].is_ascii_alphanumeric() || s[at - 1] == b'_' || s[at - 1] == b':');
        let mut i = at;
        let mut base = Vec::new();
        if text[at..].starts_with("crate::") {
            i += "crate::".len();
        } else {
            base = module.to_vec();
            while text[i..].starts_with("super::") {
                base.pop();
                i += "super::".len();
            }
        }
        if word_start {
            for p in use_tree(s, &mut i) {
                let mut full = base.clone();
                full.extend(p);
                paths.push(full);
            }
        }
        from = i.max(at + 1);
    }
    paths
}

/// The file's text before its inline test module, whose `super::` is the
/// file's own module.
fn without_tests(text: &str) -> &str {
    match text.find("#[cfg(test)]\nmod ") {
        Some(i) => &text[..i],
        None => text,
    }
}

/// The import graph of the crate whose sources are under `src`.
fn graph(src: &Path) -> Graph {
    let mut files = Vec::new();
    rust_files(src, &mut files);
    let modules: BTreeSet<Vec<String>> = files.iter().map(|f| module_of(src, f)).collect();
    let mut g = Graph::new();
    for f in &files {
        let from = module_of(src, f);
        let text = fs::read_to_string(f).expect("source readable");
        let text = strip_comments(without_tests(&text));
        let deps = g.entry(from.clone()).or_default();
        for p in crate_paths(&text, &from) {
            let to = (0..=p.len())
                .rev()
                .map(|n| p[..n].to_vec())
                .find(|m| modules.contains(m))
                .unwrap_or_default();
            if to != from && !to.is_empty() {
                deps.insert(to);
            }
        }
    }
    g
}

/// One cycle of `g`, if any, as the modules along it (first repeated last).
fn find_cycle(g: &Graph) -> Option<Vec<Vec<String>>> {
    #[derive(Clone, Copy, PartialEq)]
    enum Mark {
        Open,
        Done,
    }
    fn visit(
        g: &Graph,
        m: &Vec<String>,
        marks: &mut BTreeMap<Vec<String>, Mark>,
        stack: &mut Vec<Vec<String>>,
    ) -> Option<Vec<Vec<String>>> {
        match marks.get(m) {
            Some(Mark::Done) => return None,
            Some(Mark::Open) => {
                let at = stack.iter().position(|s| s == m).expect("open on stack");
                let mut cycle = stack[at..].to_vec();
                cycle.push(m.clone());
                return Some(cycle);
            }
            None => {}
        }
        marks.insert(m.clone(), Mark::Open);
        stack.push(m.clone());
        for d in g.get(m).into_iter().flatten() {
            if let Some(c) = visit(g, d, marks, stack) {
                return Some(c);
            }
        }
        stack.pop();
        marks.insert(m.clone(), Mark::Done);
        None
    }
    let mut marks = BTreeMap::new();
    for m in g.keys() {
        if let Some(c) = visit(g, m, &mut marks, &mut Vec::new()) {
            return Some(c);
        }
    }
    None
}

fn show(cycle: &[Vec<String>]) -> String {
    cycle
        .iter()
        .map(|m| format!("crate::{}", m.join("::")))
        .collect::<Vec<_>>()
        .join(" -> ")
}

fn assert_acyclic(src: &Path) {
    let g = graph(src);
    assert!(g.len() > 1, "{}: no modules found", src.display());
    if let Some(c) = find_cycle(&g) {
        panic!(
            "{}: import cycle {}: move what both need into a module both use",
            src.display(),
            show(&c)
        );
    }
}

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("host/ is inside the workspace")
        .to_path_buf()
}

#[test]
fn host_modules_import_one_way() {
    assert_acyclic(&root().join("host/src"));
}

/// The operations are a library under the commands and the web page:
/// they use neither.
#[test]
fn ops_use_neither_the_commands_nor_the_web_page() {
    let g = graph(&root().join("host/src"));
    let mut wrong = Vec::new();
    for (from, deps) in g
        .iter()
        .filter(|(m, _)| m.first().is_some_and(|s| s == "ops"))
    {
        for to in deps {
            if to.first().is_some_and(|s| s == "cli" || s == "web") {
                wrong.push(format!(
                    "{} -> {}",
                    show(std::slice::from_ref(from)),
                    show(std::slice::from_ref(to))
                ));
            }
        }
    }
    assert!(
        wrong.is_empty(),
        "ops imports the commands or the web page: {wrong:?}"
    );
}

/// The operations neither draw nor read a terminal (no progress bar, no
/// stdin, no terminal modes): the commands watch a run through
/// `ops::run::RunWatch`.
#[test]
fn ops_neither_draw_nor_read_a_terminal() {
    let ops = root().join("host/src/ops");
    let mut files = Vec::new();
    rust_files(&ops, &mut files);
    assert!(files.len() > 1, "{}: no sources found", ops.display());
    let mut wrong = Vec::new();
    for f in &files {
        let text = strip_comments(&fs::read_to_string(f).expect("source readable"));
        for name in ["indicatif", "termios", "stdin"] {
            let named = text.match_indices(name).any(|(i, _)| {
                let before = text[..i].chars().next_back();
                let after = text[i + name.len()..].chars().next();
                let ident = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
                !ident(before) && !ident(after)
            });
            if named {
                wrong.push(format!("{} names {name}", f.display()));
            }
        }
    }
    assert!(wrong.is_empty(), "ops reaches the terminal: {wrong:?}");
}

/// The subcommands (the modules whose `…Args` main.rs parses).
fn subcommands(main: &str) -> BTreeSet<String> {
    main.match_indices("(cli::")
        .filter_map(|(i, _)| {
            let rest = &main[i + "(cli::".len()..];
            let (module, after) = rest.split_once("::")?;
            let ty: String = after
                .chars()
                .take_while(|c| c.is_alphanumeric() || *c == '_')
                .collect();
            ty.ends_with("Args").then(|| module.to_string())
        })
        .collect()
}

/// A subcommand imports no other subcommand: what two commands share lives
/// in `ops` (the machine) or a shared `cli` module (the terminal).
fn subcommand_imports(src: &Path) -> Vec<String> {
    let main = fs::read_to_string(src.join("main.rs")).expect("host/src/main.rs");
    let commands = subcommands(&main);
    let is_command = |m: &Vec<String>| m.len() == 2 && m[0] == "cli" && commands.contains(&m[1]);
    let mut wrong = Vec::new();
    for (from, deps) in graph(src).iter().filter(|(m, _)| is_command(m)) {
        for to in deps.iter().filter(|m| is_command(m)) {
            wrong.push(format!(
                "{} -> {}",
                show(std::slice::from_ref(from)),
                show(std::slice::from_ref(to))
            ));
        }
    }
    wrong
}

#[test]
fn subcommands_use_no_other_subcommand() {
    let src = root().join("host/src");
    assert!(
        subcommands(&fs::read_to_string(src.join("main.rs")).unwrap()).len() > 10,
        "main.rs names the subcommands' Args"
    );
    let wrong = subcommand_imports(&src);
    assert!(wrong.is_empty(), "a subcommand imports another: {wrong:?}");
}

#[test]
fn the_checker_sees_a_subcommand_using_another() {
    let dir = std::env::temp_dir().join(format!("subcommands-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(dir.join("cli")).unwrap();
    fs::write(
        dir.join("main.rs"),
        "enum Command { Up(cli::up::UpArgs), Go(cli::go::GoArgs) }
",
    )
    .unwrap();
    fs::write(
        dir.join("cli/mod.rs"),
        "pub mod go;
pub mod shown;
pub mod up;
",
    )
    .unwrap();
    fs::write(dir.join("cli/shown.rs"), "\n").unwrap();
    fs::write(
        dir.join("cli/up.rs"),
        "use crate::cli::shown::x;
",
    )
    .unwrap();
    fs::write(
        dir.join("cli/go.rs"),
        "use crate::cli::{shown::y, up::report};
",
    )
    .unwrap();
    let wrong = subcommand_imports(&dir);
    fs::remove_dir_all(&dir).unwrap();
    assert_eq!(wrong, ["crate::cli::go -> crate::cli::up"]);
}

#[test]
fn board_modules_import_one_way() {
    let boards = root().join("firmware/boards");
    let mut n = 0;
    for b in fs::read_dir(&boards).expect("firmware/boards") {
        let src = b.expect("entry").path().join("src");
        if src.is_dir() {
            assert_acyclic(&src);
            n += 1;
        }
    }
    assert!(n >= 2, "expected the board images under firmware/boards");
}

#[test]
fn the_checker_sees_a_cycle_through_a_grouped_import() {
    let dir = std::env::temp_dir().join(format!("module-cycles-{}", std::process::id()));
    let _ = fs::remove_dir_all(&dir);
    fs::create_dir_all(dir.join("a")).unwrap();
    fs::write(dir.join("main.rs"), "mod a;\nmod b;\n").unwrap();
    fs::write(dir.join("a/mod.rs"), "pub mod c;\n").unwrap();
    fs::write(
        dir.join("a/c.rs"),
        "// crate::b is only named here\nuse crate::{x, b::{Thing, other}};\n",
    )
    .unwrap();
    fs::write(dir.join("b.rs"), "fn f() { crate::a::c::g(); }\n").unwrap();
    fs::write(
        dir.join("a/d.rs"),
        "use super::c::X;\n#[cfg(test)]\nmod tests {\n    use super::super::b;\n}\n",
    )
    .unwrap();
    let c = find_cycle(&graph(&dir)).map(|c| show(&c));
    fs::remove_dir_all(&dir).unwrap();
    assert_eq!(c.as_deref(), Some("crate::a::c -> crate::b -> crate::a::c"));
}
