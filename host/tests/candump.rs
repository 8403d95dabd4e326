//! `candump -L` logs of full uploads recorded on vcan by the HIL suite
//! (`scripts/hil.sh`, Case I, classic CAN and CAN-FD; `testdata/hil/`):
//! the protocol decoder reads every line, the decoded form matches the stored
//! one (`TRIQUINT_BLESS=1` rewrites it), every frame encodes back to the same
//! bytes from its physical values, and the segments reassembled from the wire
//! are exactly the plan's.

use std::path::PathBuf;

use triquint_shared::plan::Plan;
use triquint_shared::protocol::describe::describe;
use triquint_shared::protocol::segment::{FLAG_FIRST, FLAG_LAST};
use triquint_shared::protocol::{
    CommandCode, Frame, Msg, PartEvent, Reassembler, WireSegment, decode,
};

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("..")
        .join(rel)
}

/// One `candump -L` line: `(1795387919.559027) vcan0 020#0100000000`, or
/// `110##5<hex>` for CAN-FD (the digit is the FD flags nibble).
fn parse(line: &str) -> Result<(f64, Frame), String> {
    let mut it = line.split_whitespace();
    let ts = it.next().ok_or("no timestamp")?;
    let t: f64 = ts
        .trim_start_matches('(')
        .trim_end_matches(')')
        .parse()
        .map_err(|_| format!("timestamp `{ts}`"))?;
    let _iface = it.next().ok_or("no interface")?;
    let body = it.next().ok_or("no frame")?;
    let (id, rest) = body.split_once('#').ok_or("no #")?;
    let id = u16::from_str_radix(id, 16).map_err(|_| format!("identifier `{id}`"))?;
    let (fd, hex) = match rest.strip_prefix('#') {
        Some(r) => (true, r.get(1..).ok_or("no FD flags")?),
        None => (false, rest),
    };
    if hex.len() % 2 != 0 {
        return Err(format!("odd payload `{hex}`"));
    }
    let bytes = (0..hex.len())
        .step_by(2)
        .map(|i| u8::from_str_radix(&hex[i..i + 2], 16).map_err(|_| format!("payload `{hex}`")))
        .collect::<Result<Vec<u8>, _>>()?;
    Ok((t, Frame::with_payload(id, &bytes, fd)))
}

fn check_log(name: &str, fd: bool) {
    let log = std::fs::read_to_string(repo(&format!("testdata/hil/{name}.candump.log")))
        .expect("recorded log");
    let plan: Plan = serde_json::from_str(
        &std::fs::read_to_string(repo("testdata/hil/paper-case1.json")).expect("plan"),
    )
    .expect("plan file");
    let mut decoded = String::new();
    let mut asm = Reassembler::default();
    let mut segments: Vec<WireSegment> = Vec::new();
    // Start, and its resends to a drive that had not answered (same token and time).
    let mut starts: Vec<(u8, u32)> = Vec::new();
    let mut lines = 0;
    for (i, line) in log.lines().enumerate() {
        let (_, frame) = parse(line).unwrap_or_else(|e| panic!("line {}: {e}: {line}", i + 1));
        let d = describe(&frame).unwrap_or_else(|e| panic!("line {}: {e}: {line}", i + 1));
        let back = d.encode(frame.len as usize, frame.fd);
        assert_eq!(back.id, frame.id, "line {}", i + 1);
        assert_eq!(back.payload(), frame.payload(), "line {}: {d}", i + 1);
        decoded.push_str(&format!("{d}\n"));
        lines += 1;
        match decode(&frame) {
            Ok((Msg::SegmentPart | Msg::SegmentPartFd, _)) => {
                assert_eq!(frame.fd, fd, "line {}", i + 1);
                if let PartEvent::Complete(w) = asm.push(frame.payload(), frame.fd)
                    && w.seq as usize == segments.len()
                {
                    segments.push(w);
                }
            }
            Ok((Msg::Command(c), _)) if c.command == CommandCode::Start as u8 => {
                starts.push((c.token, c.arg))
            }
            _ => {}
        }
    }
    assert!(lines > 500, "{lines} lines: not a whole upload");
    assert!(!starts.is_empty(), "no Start");
    assert!(
        starts.iter().all(|s| *s == starts[0]),
        "one Start per upload (resends repeat it): {starts:?}"
    );
    let n = plan.segments.len();
    assert_eq!(segments.len(), n);
    for (i, (w, s)) in segments.iter().zip(&plan.segments).enumerate() {
        let flags = if i == 0 { FLAG_FIRST } else { 0 } | if i + 1 == n { FLAG_LAST } else { 0 };
        let want = WireSegment::from_quintic(i as u16, &s.quintic(), flags).expect("segment");
        assert_eq!(*w, want, "segment {i}");
    }
    let stored = repo(&format!("testdata/hil/{name}.decoded.txt"));
    if std::env::var_os("TRIQUINT_BLESS").is_some() {
        std::fs::write(&stored, &decoded).expect("bless");
    }
    let want = std::fs::read_to_string(&stored).expect("stored decoded form");
    assert!(
        want == decoded,
        "{} is stale: TRIQUINT_BLESS=1 cargo test -p triquint-host --test candump",
        stored.display()
    );
}

#[test]
fn classic_upload_log_decodes() {
    check_log("case1-classic", false);
}

#[test]
fn fd_upload_log_decodes() {
    check_log("case1-fd", true);
}

#[test]
fn candump_lines_parse() {
    let (t, f) = parse("(1795387919.559027) vcan0 020#0100000000").unwrap();
    assert!((t - 1795387919.559027).abs() < 1e-6);
    assert_eq!(
        (f.id, f.fd, f.payload()),
        (0x020, false, &[1u8, 0, 0, 0, 0][..])
    );
    let (_, f) = parse("(1.0) vcan0 110##5AABB").unwrap();
    assert_eq!(
        (f.id, f.fd, f.payload()),
        (0x110, true, &[0xAAu8, 0xBB][..])
    );
    assert!(parse("(1.0) vcan0 110#ABC").is_err());
    assert!(parse("vcan0 110#AB").is_err());
}
