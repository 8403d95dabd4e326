//! Option values both binaries parse the same way: finite numbers, triples
//! `a,b,c`, node lists and the control rate. Errors are bad input (exit 2)
//! naming the option and the text.

use nalgebra::Vector3;

use crate::exit::{CliError, CliResult};

/// The control tick rates the drives accept (Hz), for `triquint simulate`,
/// `upload`, `move-to` and `triquint-sim`: 1 kHz (the paper's rate) to
/// 10 kHz. The simulator's rate must be the one the host configures, so
/// the two share one range.
pub const RATE_HZ: std::ops::RangeInclusive<f64> = 1000.0..=10000.0;

/// The default node ids of the drives of axes 1–3 (the protocol's).
pub use triquint_shared::protocol::NODES;
/// Node ids the drives may have (the protocol's; 0 addresses them all).
pub const NODE_IDS: std::ops::RangeInclusive<u8> = 1..=triquint_shared::protocol::MAX_NODE_ID;

/// Parses one finite number, naming what it is on error.
pub fn finite(what: &str, text: &str) -> CliResult<f64> {
    match text.parse::<f64>() {
        Ok(x) if x.is_finite() => Ok(x),
        Ok(x) => Err(CliError::bad_input(format!(
            "{what}: `{text}` is {x}, not a finite number"
        ))),
        Err(_) => Err(CliError::bad_input(format!(
            "{what}: `{text}` is not a number"
        ))),
    }
}

/// Parses "a,b,c" into three finite numbers, naming the option on error.
pub fn parse_triple(option: &str, text: &str) -> CliResult<Vector3<f64>> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    if parts.len() != 3 {
        return Err(CliError::bad_input(format!(
            "{option}: expected three comma-separated numbers, got {} in `{text}`",
            parts.len()
        )));
    }
    let mut v = Vector3::zeros();
    for (i, p) in parts.iter().enumerate() {
        v[i] = finite(&format!("{option} value {}", i + 1), p)?;
    }
    Ok(v)
}

/// Parses a comma-separated list of at most three distinct node ids
/// (1–15), in axis order: the first drives axis 1.
pub fn parse_nodes(option: &str, text: &str) -> CliResult<Vec<u8>> {
    let mut nodes = Vec::new();
    for p in text.split(',').map(str::trim) {
        match p.parse::<u8>() {
            Ok(n) if NODE_IDS.contains(&n) && !nodes.contains(&n) => nodes.push(n),
            _ => {
                return Err(CliError::bad_input(format!(
                    "{option}: `{p}` in `{text}` is not a distinct node id 1 to 15"
                )));
            }
        }
    }
    if nodes.len() > 3 {
        return Err(CliError::bad_input(format!(
            "{option}: `{text}` lists {} nodes; a robot has three axes",
            nodes.len()
        )));
    }
    Ok(nodes)
}

/// Parses the node ids of the drives of axes 1, 2, 3 (`--nodes A,B,C`).
pub fn parse_axis_nodes(option: &str, text: &str) -> CliResult<[u8; 3]> {
    match parse_nodes(option, text)?.as_slice() {
        [a, b, c] => Ok([*a, *b, *c]),
        other => Err(CliError::bad_input(format!(
            "{option}: `{text}` lists {} node ids; give one per axis, axis 1 first (e.g. 1,2,3)",
            other.len()
        ))),
    }
}

/// Checks a control rate against [`RATE_HZ`].
pub fn check_rate(option: &str, hz: f64) -> CliResult<f64> {
    if RATE_HZ.contains(&hz) {
        Ok(hz)
    } else {
        Err(CliError::bad_input(format!(
            "{option} {hz}: must be {} to {} Hz",
            RATE_HZ.start(),
            RATE_HZ.end()
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exit::Status;

    #[test]
    fn triples_nodes_and_rates() {
        assert_eq!(
            parse_triple("--start", "-90, 90,680").unwrap(),
            Vector3::new(-90.0, 90.0, 680.0)
        );
        for bad in ["1,2", "1,2,x", "1,2,inf", "1,2,3,4"] {
            let e = parse_triple("--start", bad).unwrap_err();
            assert_eq!(e.status, Status::BadInput);
            assert!(e.message.starts_with("--start"), "{}", e.message);
        }
        assert_eq!(parse_nodes("--nodes", "3,1").unwrap(), vec![3, 1]);
        assert_eq!(parse_axis_nodes("--nodes", "4,5,6").unwrap(), [4, 5, 6]);
        for bad in ["1,16", "1,1", "", "0", "1,2,3,4"] {
            assert!(parse_nodes("--nodes", bad).is_err(), "{bad}");
        }
        for bad in ["1,2", "4,5,x"] {
            assert!(parse_axis_nodes("--nodes", bad).is_err(), "{bad}");
        }
        assert_eq!(check_rate("--rate", 1000.0).unwrap(), 1000.0);
        assert_eq!(check_rate("--rate", 10000.0).unwrap(), 10000.0);
        for bad in [999.0, 100.0, 10001.0, f64::NAN] {
            let e = check_rate("--rate", bad).unwrap_err();
            assert!(e.message.contains("1000 to 10000 Hz"), "{}", e.message);
        }
    }
}
