//! Every shell example in README.md and docs/ is checked against the code:
//! each block is valid bash, each `triquint` command line names a
//! subcommand that exists and only options its `--help` lists, and each
//! repository path it names exists. Blocks the CI cannot run (`sh
//! needs-can`, `needs-board`, `needs-root`) are only checked this way; the
//! `sh tutorial` blocks also run in `scripts/getting-started.sh`.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The markdown pages: README.md and every docs/*.md.
fn pages() -> Vec<PathBuf> {
    let mut pages = vec![repo().join("README.md")];
    for entry in std::fs::read_dir(repo().join("docs")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "md") {
            pages.push(path);
        }
    }
    pages.sort();
    pages
}

struct Block {
    page: String,
    line: usize,
    info: String,
    text: String,
}

/// Fenced code blocks of a page, with their info strings.
fn blocks(path: &Path) -> Vec<Block> {
    let text = std::fs::read_to_string(path).unwrap();
    let page = path.file_name().unwrap().to_string_lossy().into_owned();
    let mut out = Vec::new();
    let mut open: Option<Block> = None;
    for (i, line) in text.lines().enumerate() {
        if let Some(info) = line.strip_prefix("```") {
            match open.take() {
                None => {
                    open = Some(Block {
                        page: page.clone(),
                        line: i + 1,
                        info: info.trim().to_string(),
                        text: String::new(),
                    })
                }
                Some(b) => out.push(b),
            }
        } else if let Some(b) = open.as_mut() {
            b.text.push_str(line);
            b.text.push('\n');
        }
    }
    assert!(open.is_none(), "{page}: a code block is not closed");
    out
}

const SHELL_KINDS: [&str; 5] = [
    "sh",
    "sh tutorial",
    "sh needs-can",
    "sh needs-board",
    "sh needs-root",
];

fn shell_blocks() -> Vec<Block> {
    pages()
        .iter()
        .flat_map(|p| blocks(p))
        .filter(|b| b.info.split_whitespace().next() == Some("sh"))
        .collect()
}

#[test]
fn every_shell_block_is_marked_and_valid_bash() {
    let blocks = shell_blocks();
    assert!(
        blocks.len() >= 20,
        "only {} shell blocks found",
        blocks.len()
    );
    for b in &blocks {
        assert!(
            SHELL_KINDS.contains(&b.info.as_str()),
            "{}:{}: unknown block kind `{}`",
            b.page,
            b.line,
            b.info
        );
        let out = Command::new("bash")
            .args(["-n", "-c", &b.text])
            .output()
            .unwrap();
        assert!(
            out.status.success(),
            "{}:{}: not valid bash: {}",
            b.page,
            b.line,
            String::from_utf8_lossy(&out.stderr)
        );
    }
}

#[test]
fn the_tutorials_are_marked_to_run() {
    for (page, least) in [("README.md", 4), ("docs/getting-started.md", 1)] {
        let n = blocks(&repo().join(page))
            .iter()
            .filter(|b| b.info == "sh tutorial")
            .count();
        assert!(n >= least, "{page}: {n} `sh tutorial` blocks");
    }
}

/// The words of a command line up to its comment, quotes removed.
fn words(line: &str) -> Vec<String> {
    let code = match line.find(" #") {
        Some(i) => &line[..i],
        None => line,
    };
    code.split_whitespace()
        .map(|w| w.trim_matches(|c| c == '"' || c == '\''))
        .filter(|w| !w.is_empty() && *w != "&")
        .map(str::to_string)
        .collect()
}

/// `triquint SUB --help`, cached.
fn help(cache: &mut BTreeMap<String, String>, sub: &str) -> String {
    cache
        .entry(sub.to_string())
        .or_insert_with(|| {
            let out = Command::new(env!("CARGO_BIN_EXE_triquint"))
                .args([sub, "--help"])
                .output()
                .unwrap();
            assert!(
                out.status.success(),
                "`triquint {sub} --help` failed: is `{sub}` a command?"
            );
            String::from_utf8(out.stdout).unwrap()
        })
        .clone()
}

#[test]
fn every_triquint_command_in_the_docs_has_its_subcommand_and_options() {
    let mut cache = BTreeMap::new();
    let mut checked = 0;
    for b in shell_blocks() {
        for (k, line) in b.text.lines().enumerate() {
            let w = words(line.trim_start());
            let Some(at) = w.iter().position(|x| x == "triquint") else {
                continue;
            };
            let Some(sub) = w.get(at + 1) else { continue };
            let text = help(&mut cache, sub);
            for opt in w[at + 2..].iter().filter(|x| x.starts_with("--")) {
                let name = opt.split('=').next().unwrap();
                assert!(
                    text.contains(&format!("{name} "))
                        || text.contains(&format!("{name}\n"))
                        || text.contains(&format!("{name},")),
                    "{}:{}: `triquint {sub}` has no option {name}",
                    b.page,
                    b.line + 1 + k
                );
            }
            checked += 1;
        }
    }
    assert!(
        checked >= 30,
        "only {checked} triquint command lines checked"
    );
}

/// Repository files named in shell blocks (examples/…, scripts/…,
/// testdata/…, host/…, docs/…) exist.
#[test]
fn every_repository_path_in_a_shell_block_exists() {
    let roots = [
        "examples/",
        "scripts/",
        "testdata/",
        "host/",
        "docs/",
        "firmware/",
        "hil-sim/",
    ];
    for b in shell_blocks() {
        for (k, line) in b.text.lines().enumerate() {
            for w in words(line) {
                let w = w.trim_start_matches("./").trim_end_matches(';');
                let w = w.split('=').next_back().unwrap();
                let file_like = w.rsplit('/').next().is_some_and(|name| name.contains('.'));
                if roots.iter().any(|r| w.starts_with(r)) && file_like && !w.contains(['{', '$']) {
                    assert!(
                        repo().join(w).exists(),
                        "{}:{}: {w} does not exist",
                        b.page,
                        b.line + 1 + k
                    );
                }
            }
        }
    }
}

/// The user's pages keep no unlabelled code block: a reader, rustdoc and
/// these tests all need to know what a block is.
#[test]
fn every_code_block_says_its_language() {
    let users = [
        "README.md",
        "getting-started.md",
        "safety.md",
        "vcan.md",
        "cli.md",
        "planner.md",
        "python.md",
        "web-monitor.md",
        "charts.md",
        "firmware.md",
        "verification.md",
    ];
    for p in pages()
        .into_iter()
        .filter(|p| users.iter().any(|u| p.ends_with(u)))
    {
        for b in blocks(&p) {
            assert!(
                !b.info.is_empty(),
                "{}:{}: code block without a language",
                b.page,
                b.line
            );
        }
    }
}
