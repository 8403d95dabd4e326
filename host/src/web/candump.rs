//! `candump -L` log lines: `(1796183865.524882) vcan0 702#0000000200000000`,
//! CAN-FD as `ID##F DATA` (F: the flags nibble).

use triquint_shared::protocol::Frame;

/// One logged frame: its time (µs since the epoch of the log) and the frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Logged {
    pub t_us: u64,
    pub frame: Frame,
}

fn hex_bytes(s: &str) -> Option<Vec<u8>> {
    if s.len() % 2 != 0 || s.len() > 128 {
        return None;
    }
    (0..s.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(s.get(i..i + 2)?, 16).ok())
        .collect()
}

/// One line; `None` for a blank line, an extended identifier, a remote
/// frame or anything else that is not a standard data frame.
pub fn parse_line(line: &str) -> Option<Logged> {
    let mut it = line.split_whitespace();
    let t = it.next()?.strip_prefix('(')?.strip_suffix(')')?;
    let _iface = it.next()?;
    let frame = it.next()?;
    let (secs, frac) = t.split_once('.')?;
    let secs: u64 = secs.parse().ok()?;
    if frac.is_empty() || frac.len() > 9 || !frac.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    let frac_us = format!("{frac:0<6}").get(..6)?.parse::<u64>().ok()?;
    let (id, rest) = frame.split_once('#')?;
    if id.len() != 3 {
        return None;
    }
    let id = u16::from_str_radix(id, 16).ok()?;
    let (fd, data) = match rest.strip_prefix('#') {
        Some(r) => (true, r.get(1..)?),
        None => (false, rest),
    };
    if data.starts_with('R') {
        return None;
    }
    let data = hex_bytes(data)?;
    if (!fd && data.len() > 8) || id > 0x7FF {
        return None;
    }
    Some(Logged {
        t_us: secs.checked_mul(1_000_000)?.checked_add(frac_us)?,
        frame: Frame::with_payload(id, &data, fd),
    })
}

/// Every frame of a log in time order (a log interleaves the interfaces'
/// timestamps slightly out of order), times made relative to its first
/// frame; errors name the first line that is not a frame.
pub fn parse_log(text: &str) -> Result<Vec<Logged>, String> {
    let mut out = Vec::new();
    for (n, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        match parse_line(line) {
            Some(l) => out.push(l),
            None => return Err(format!("line {}: not a candump -L frame: {line:?}", n + 1)),
        }
    }
    out.sort_by_key(|l| l.t_us);
    let Some(t0) = out.first().map(|l| l.t_us) else {
        return Err("no frames".into());
    };
    for l in &mut out {
        l.t_us = l.t_us.saturating_sub(t0);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn classic_and_fd_lines() {
        let l = parse_line("(1796183865.524882) vcan0 702#0000000200000000").unwrap();
        assert_eq!(l.t_us, 1_796_183_865_524_882);
        assert_eq!(l.frame.id, 0x702);
        assert!(!l.frame.fd);
        assert_eq!(l.frame.payload(), &[0, 0, 0, 2, 0, 0, 0, 0]);
        let l = parse_line("(1.5) vcan0 100##1AABB").unwrap();
        assert_eq!(l.t_us, 1_500_000);
        assert!(l.frame.fd);
        assert_eq!(l.frame.payload(), &[0xAA, 0xBB]);
        for bad in [
            "",
            "(1.0) vcan0 12345678#00",
            "(1.0) vcan0 702#R",
            "(x) vcan0 702#00",
            "(1.0) vcan0 702#0",
            "(1.0) vcan0 702#000000000000000000",
        ] {
            assert_eq!(parse_line(bad), None, "{bad}");
        }
    }

    #[test]
    fn the_recorded_logs_parse() {
        for text in [
            include_str!("../../../testdata/hil/case1-classic.candump.log"),
            include_str!("../../../testdata/hil/case1-fd.candump.log"),
        ] {
            let log = parse_log(text).unwrap();
            assert!(log.len() > 2000);
            assert_eq!(log[0].t_us, 0);
            assert!(log.windows(2).all(|w| w[0].t_us <= w[1].t_us));
        }
    }
}
