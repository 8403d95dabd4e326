//! The `crate::` and `super::` paths a source names, use trees expanded.

use crate::sources::Module;

/// A path a source names, resolved from the crate root.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct CratePath {
    /// Line number (from 1) of its `crate::` or `super::`.
    pub line: usize,
    /// Written `crate::…` (not `super::…`).
    pub from_crate: bool,
    /// Its segments from the crate root.
    pub path: Module,
}

/// Parses a use tree at `s[*i..]` (just after `crate::`): its paths.
fn use_tree(s: &[u8], i: &mut usize) -> Vec<Module> {
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
/// module `module`), from the crate root. `$crate::` (a macro's) and
/// `other_crate::…::crate` are not this crate's.
pub fn crate_paths(text: &str, module: &[String]) -> Vec<CratePath> {
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
        let word_start =
            at == 0 || !(s[at - 1].is_ascii_alphanumeric() || b"_:$".contains(&s[at - 1]));
        let mut i = at;
        let mut base = Vec::new();
        let from_crate = text[at..].starts_with("crate::");
        if from_crate {
            i += "crate::".len();
        } else {
            base = module.to_vec();
            while text[i..].starts_with("super::") {
                base.pop();
                i += "super::".len();
            }
        }
        if word_start {
            let line = 1 + text[..at].matches('\n').count();
            for p in use_tree(s, &mut i) {
                let mut path = base.clone();
                path.extend(p);
                paths.push(CratePath {
                    line,
                    from_crate,
                    path,
                });
            }
        }
        from = i.max(at + 1);
    }
    paths
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names(text: &str, module: &[&str]) -> Vec<(usize, bool, String)> {
        let module: Module = module.iter().map(|s| s.to_string()).collect();
        crate_paths(text, &module)
            .into_iter()
            .map(|p| (p.line, p.from_crate, p.path.join("::")))
            .collect()
    }

    #[test]
    fn grouped_nested_and_relative_paths() {
        let text = "use crate::{x, b::{T, u}};\nfn f() { super::super::c::g(); $crate::m::n(); }\n";
        assert_eq!(
            names(text, &["a", "d"]),
            [
                (1, true, "x".to_string()),
                (1, true, "b::T".to_string()),
                (1, true, "b::u".to_string()),
                (2, false, "c::g".to_string()),
            ]
        );
    }
}
