//! docs/cli.md's synopsis stays the command line's: every `triquint`
//! subcommand has an entry, every option its `--help` lists is in that
//! entry (the options every command shares are in their own section), and
//! the entry names no option the command lacks. No `--help` shows a Rust
//! path where a default should be.

use std::collections::BTreeMap;
use std::path::Path;
use std::process::Command;

fn triquint(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_triquint"))
        .args(args)
        .output()
        .unwrap();
    assert!(out.status.success(), "triquint {args:?} failed");
    String::from_utf8(out.stdout).unwrap()
}

/// The subcommands `triquint --help` lists.
fn subcommands() -> Vec<String> {
    let help = triquint(&["--help"]);
    let list = help
        .split("Commands:")
        .nth(1)
        .and_then(|s| s.split("Options:").next())
        .expect("a Commands: section");
    list.lines()
        .filter_map(|l| l.split_whitespace().next())
        .filter(|s| *s != "help")
        .map(str::to_string)
        .collect()
}

/// The synopsis block of docs/cli.md, one entry per `triquint SUB` line
/// with the lines indented under it.
fn synopsis() -> BTreeMap<String, String> {
    let page = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/cli.md");
    let text = std::fs::read_to_string(page).unwrap();
    let block = text
        .split("## Synopsis")
        .nth(1)
        .and_then(|s| s.split("```text\n").nth(1))
        .and_then(|s| s.split("```").next())
        .expect("a text block under ## Synopsis");
    let mut entries = BTreeMap::new();
    let mut current: Option<String> = None;
    for line in block.lines() {
        if let Some(rest) = line.strip_prefix("triquint ") {
            current = rest.split_whitespace().next().map(str::to_string);
        } else if line.starts_with("triquint-sim") || line.starts_with('#') {
            current = None;
        }
        if let Some(sub) = &current {
            let e: &mut String = entries.entry(sub.clone()).or_default();
            e.push_str(line);
            e.push('\n');
        }
    }
    entries
}

/// `--long` options in `text`, with the short form where `--help` gives
/// one (`-o, --output`).
fn options(text: &str) -> Vec<(String, Option<String>)> {
    let mut out = Vec::new();
    for line in text.lines() {
        let t = line.trim_start();
        let (short, rest) = match t.strip_prefix('-') {
            Some(r) if !r.starts_with('-') && t.get(2..4) == Some(", ") => {
                (Some(t[..2].to_string()), &t[4..])
            }
            _ => (None, t),
        };
        if let Some(name) = rest.strip_prefix("--") {
            let name: String = name
                .chars()
                .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                .collect();
            out.push((format!("--{name}"), short));
        }
    }
    out
}

/// Options documented once for every command, under "Options every
/// command shares", or that clap adds.
const SHARED: [&str; 4] = ["--help", "--version", "--machine", "--robot"];

fn names(text: &str, opt: &str) -> bool {
    text.match_indices(opt).any(|(i, _)| {
        let after = text[i + opt.len()..].chars().next();
        !after.is_some_and(|c| c.is_ascii_alphanumeric() || c == '-')
    })
}

#[test]
fn every_subcommand_and_option_is_in_the_synopsis() {
    let entries = synopsis();
    let subs = subcommands();
    assert!(
        subs.len() >= 15,
        "only {} subcommands: {subs:?}",
        subs.len()
    );
    for sub in &subs {
        let entry = entries
            .get(sub)
            .unwrap_or_else(|| panic!("docs/cli.md's synopsis has no `triquint {sub}`"));
        let help = triquint(&[sub, "--help"]);
        for (opt, short) in options(&help) {
            if SHARED.contains(&opt.as_str()) {
                continue;
            }
            let shown = names(entry, &opt) || short.as_deref().is_some_and(|s| names(entry, s));
            assert!(
                shown,
                "docs/cli.md: `triquint {sub}` lacks {opt}, which its --help lists"
            );
        }
        // And the other way: what the entry names exists.
        for word in entry.split(|c: char| c.is_whitespace() || "[]()|,`".contains(c)) {
            if let Some(name) = word.strip_prefix("--") {
                let opt: String = name
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '-')
                    .collect();
                let opt = format!("--{opt}");
                assert!(
                    names(&help, &opt),
                    "docs/cli.md: `triquint {sub}` names {opt}, which its --help does not list"
                );
            }
        }
    }
    let page =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/cli.md"))
            .unwrap();
    let shared = page
        .split("## Options every command shares")
        .nth(1)
        .expect("a section of shared options");
    for opt in ["--machine", "--robot", "--rate"] {
        assert!(
            names(shared, opt),
            "docs/cli.md: the shared options section lacks {opt}"
        );
    }
}

#[test]
fn no_help_shows_a_rust_path() {
    for sub in subcommands() {
        let help = triquint(&[&sub, "--help"]);
        let paths: Vec<&str> = help.lines().filter(|l| l.contains("::")).collect();
        assert!(
            paths.is_empty(),
            "`triquint {sub} --help` shows a Rust path: {paths:?}"
        );
    }
}

/// A command that reads the machine file takes its drives' node ids from
/// it unless `--nodes` says otherwise: `status --machine` of a machine on
/// nodes 4, 5, 6 must not listen for 1, 2, 3.
#[test]
fn nodes_default_to_the_machine_files_where_a_command_reads_it() {
    for sub in subcommands() {
        let help = triquint(&[&sub, "--help"]);
        if !(names(&help, "--nodes") && names(&help, "--machine")) {
            continue;
        }
        let nodes: String = help
            .split("--nodes")
            .nth(1)
            .unwrap()
            .split("\n      -")
            .next()
            .unwrap()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        assert!(
            nodes.contains("[default: the machine file's `axis.N.node_id`]"),
            "`triquint {sub} --help`: --nodes does not default to the machine file's: {nodes}"
        );
    }
}
