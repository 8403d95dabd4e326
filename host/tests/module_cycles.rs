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

use std::collections::BTreeSet;
use std::fs;
use std::path::{Path, PathBuf};

use triquint_module_graph::{find_cycle, graph, rust_files, show, strip_comments};

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
    let files = rust_files(&ops);
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
