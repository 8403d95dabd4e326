//! Reader for long via-point paths: one point `x, y, z` per line.
//!
//! Values are separated by commas, whitespace (spaces, tabs) or both
//! (`1, 2, 3`, `1 2 3`, `1,2,3`, `1\t2\t3`). `#` starts a comment (whole line
//! or trailing); blank lines are ignored; CRLF line ends and a leading byte
//! order mark are tolerated. The first non-blank, non-comment line may be a
//! header (`x,y,z`, `x_mm y_mm z_mm`): it is a header when none of its
//! fields reads as a number or starts like one (digit, sign or point). Numbers are Rust `f64` literals (`1`, `-2.5`,
//! `.5`, `1e-3`); `nan`/`inf` and values that overflow are rejected. Every
//! error names its 1-based line and is one line long.

use triquint_shared::readable::readable;

/// The largest number of points a file may hold.
pub const MAX_POINTS: usize = 1_000_000;

/// Longest piece of offending text quoted in an error, in characters.
const QUOTE_MAX: usize = 32;

/// Why a points file was rejected.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PointsFileError {
    /// A point line without exactly three values.
    #[error("line {line}: expected 3 values (x, y, z), found {found}")]
    WrongCount { line: usize, found: usize },
    /// Two commas with nothing between them, or a comma at an end of the line.
    #[error("line {line}: empty value between commas")]
    EmptyField { line: usize },
    /// A value that is not a number (`nan` and `inf` included).
    #[error("line {line}: {} is not a number", quoted(.text))]
    NotANumber { line: usize, text: String },
    /// A number too large for f64, such as `1e999`.
    #[error("line {line}: {} is out of range (reads as {})", quoted(.text), readable(*.value))]
    NotFinite {
        line: usize,
        text: String,
        value: f64,
    },
    /// A header-like line (no numeric field) after the first content line.
    #[error("line {line}: a header is allowed only as the first line")]
    HeaderNotFirst { line: usize },
    /// More than `MAX_POINTS` (a million) points.
    #[error("line {line}: more than {max} points")]
    TooMany { line: usize, max: usize },
    /// No point at all.
    #[error("no points in the file")]
    Empty,
}

impl PointsFileError {
    /// The 1-based line the error is about, if any.
    pub fn line(&self) -> Option<usize> {
        match *self {
            Self::WrongCount { line, .. }
            | Self::EmptyField { line }
            | Self::NotANumber { line, .. }
            | Self::NotFinite { line, .. }
            | Self::HeaderNotFirst { line }
            | Self::TooMany { line, .. } => Some(line),
            Self::Empty => None,
        }
    }
}

/// `text` in quotes with control characters escaped, cut to [`QUOTE_MAX`]
/// characters, so that a message stays on one line and short.
fn quoted(text: &str) -> String {
    match text.char_indices().nth(QUOTE_MAX) {
        Some((cut, _)) => format!("{:?}…", &text[..cut]),
        None => format!("{text:?}"),
    }
}

/// The fields of a line (comment already removed), or `None` if a comma
/// leaves a field empty.
fn fields(content: &str) -> Option<Vec<&str>> {
    let mut out = Vec::new();
    let has_comma = content.contains(',');
    for part in content.split(',') {
        let before = out.len();
        out.extend(part.split_whitespace());
        if has_comma && out.len() == before {
            return None;
        }
    }
    Some(out)
}

/// A header field: not a number (nor `nan`/`inf`) and not starting like one
/// (so `1;2;3` is a malformed point, not a header).
fn looks_like_header(field: &str) -> bool {
    field.parse::<f64>().is_err()
        && !field.starts_with(|c: char| c.is_ascii_digit() || matches!(c, '+' | '-' | '.'))
}

/// Parses a points file; see the module documentation for the format.
///
/// # Errors
/// The first problem found, with its line; [`PointsFileError::Empty`] if
/// the file holds no point.
pub fn parse_points(text: &str) -> Result<Vec<[f64; 3]>, PointsFileError> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut points = Vec::new();
    let mut seen_content = false;
    for (index, raw) in text.lines().enumerate() {
        let line = index + 1;
        let content = raw.split_once('#').map_or(raw, |(before, _)| before);
        if content.trim().is_empty() {
            continue;
        }
        let first = !seen_content;
        seen_content = true;
        let Some(fields) = fields(content) else {
            return Err(PointsFileError::EmptyField { line });
        };
        if fields.iter().all(|f| looks_like_header(f)) {
            if first {
                continue; // the header
            }
            return Err(PointsFileError::HeaderNotFirst { line });
        }
        let mut xyz = [0.0; 3];
        for (i, field) in fields.iter().enumerate() {
            let value = match field.parse::<f64>() {
                Ok(v) if v.is_finite() => v,
                Ok(v) if field.bytes().any(|b| b.is_ascii_digit()) => {
                    return Err(PointsFileError::NotFinite {
                        line,
                        text: (*field).to_owned(),
                        value: v,
                    });
                }
                _ => {
                    return Err(PointsFileError::NotANumber {
                        line,
                        text: (*field).to_owned(),
                    });
                }
            };
            if let Some(slot) = xyz.get_mut(i) {
                *slot = value;
            }
        }
        if fields.len() != 3 {
            return Err(PointsFileError::WrongCount {
                line,
                found: fields.len(),
            });
        }
        if points.len() == MAX_POINTS {
            return Err(PointsFileError::TooMany {
                line,
                max: MAX_POINTS,
            });
        }
        points.push(xyz);
    }
    if points.is_empty() {
        return Err(PointsFileError::Empty);
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use PointsFileError as E;

    #[test]
    fn separators_comments_header_crlf() {
        let want = vec![
            [1.0, 2.0, 3.0],
            [-4.5, 0.5, 6e-3],
            [7.0, 8.0, 9.0],
            [1.0, 0.0, -0.0],
        ];
        for text in [
            "1, 2, 3\n-4.5, .5, 6e-3\n7,8,9\n1 0 -0\n",
            "x,y,z\n1 2 3\n-4.5\t.5\t6e-3\n7 ,8, 9\n1,0,-0",
            "# path\n\nx_mm y_mm z_mm # header\r\n1 2 3 # first\r\n\r\n  # note\r\n-4.5,0.5,0.006\r\n7\t, 8 ,\t9\r\n+1 0. -0\r\n",
            "\u{feff}1,2,3\n-4.5 0.5 6E-3\n7 8 9\n1 0 -0\n#",
        ] {
            assert_eq!(parse_points(text), Ok(want.clone()), "{text:?}");
        }
        assert_eq!(parse_points("1 2 3"), Ok(vec![[1.0, 2.0, 3.0]]));
        assert_eq!(
            parse_points("1e300 -1e-300 0"),
            Ok(vec![[1e300, -1e-300, 0.0]])
        );
    }

    #[test]
    fn errors_name_their_line() {
        let cases: Vec<(&str, PointsFileError)> = vec![
            ("1,,2,3", E::EmptyField { line: 1 }),
            ("0 0 0\n1,2,3,", E::EmptyField { line: 2 }),
            (",1,2,3", E::EmptyField { line: 1 }),
            (
                "1e999,0,0",
                E::NotFinite {
                    line: 1,
                    text: "1e999".into(),
                    value: f64::INFINITY,
                },
            ),
            (
                "0 0 0\n-1e400 0 0",
                E::NotFinite {
                    line: 2,
                    text: "-1e400".into(),
                    value: f64::NEG_INFINITY,
                },
            ),
            ("1 2", E::WrongCount { line: 1, found: 2 }),
            ("x y z\n\n1 2 3 4", E::WrongCount { line: 3, found: 4 }),
            ("#", E::Empty),
            ("", E::Empty),
            ("x,y,z\n# nothing\n", E::Empty),
            ("x,y,z\nx,y,z\n1,2,3", E::HeaderNotFirst { line: 2 }),
            ("1,2,3\nx y z", E::HeaderNotFirst { line: 2 }),
            (
                "nan 0 0",
                E::NotANumber {
                    line: 1,
                    text: "nan".into(),
                },
            ),
            (
                "0 0 0\n0 inf 0",
                E::NotANumber {
                    line: 2,
                    text: "inf".into(),
                },
            ),
            (
                "0 0 -Infinity",
                E::NotANumber {
                    line: 1,
                    text: "-Infinity".into(),
                },
            ),
            (
                "1 2 x",
                E::NotANumber {
                    line: 1,
                    text: "x".into(),
                },
            ),
            (
                "1;2;3",
                E::NotANumber {
                    line: 1,
                    text: "1;2;3".into(),
                },
            ),
            (
                "-x -y -z\n1 2 3",
                E::NotANumber {
                    line: 1,
                    text: "-x".into(),
                },
            ),
            (
                "1 2 3\n\n 4 5 0x6",
                E::NotANumber {
                    line: 3,
                    text: "0x6".into(),
                },
            ),
        ];
        for (text, want) in cases {
            let got = parse_points(text).unwrap_err();
            assert_eq!(got, want, "{text:?}");
            let msg = got.to_string();
            assert!(!msg.contains('\n'), "{msg}");
            if let Some(line) = got.line() {
                assert!(msg.starts_with(&format!("line {line}: ")), "{msg}");
            }
        }
    }

    #[test]
    fn messages() {
        let e = |t: &str| parse_points(t).unwrap_err().to_string();
        assert_eq!(e("1 2"), "line 1: expected 3 values (x, y, z), found 2");
        assert_eq!(
            e("1e999 0 0"),
            "line 1: \"1e999\" is out of range (reads as inf)"
        );
        assert_eq!(e("0 0 nan"), "line 1: \"nan\" is not a number");
        assert_eq!(e("0 0 a\u{1}b"), "line 1: \"a\\u{1}b\" is not a number");
        let long = format!("0 0 {}", "z".repeat(100));
        assert_eq!(
            e(&long),
            format!("line 1: \"{}\"… is not a number", "z".repeat(32))
        );
        assert_eq!(e("\n\n"), "no points in the file");
    }

    #[test]
    fn too_many_points() {
        let text = "0 0 0\n".repeat(MAX_POINTS);
        assert_eq!(parse_points(&text).map(|p| p.len()), Ok(MAX_POINTS));
        let text = format!("x y z\n{text}1 1 1\n");
        assert_eq!(
            parse_points(&text),
            Err(E::TooMany {
                line: MAX_POINTS + 2,
                max: MAX_POINTS
            })
        );
    }
}
