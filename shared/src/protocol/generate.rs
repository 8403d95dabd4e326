//! Generators: `docs/triquint.dbc`, the generated tables of
//! `docs/protocol.md`, and `testdata/protocol/golden.txt`, all from the
//! declarations. Tests compare them with the committed files; set
//! `TRIQUINT_BLESS=1` to rewrite the files instead.

extern crate alloc;

use alloc::format;
use alloc::string::String;
use alloc::vec::Vec;
use core::fmt::Write;

use super::compact::{self, CLASSIC_CHUNK, COMPACT_FIELDS, COMPACT_LEN, Compact, DeviationBound};
use super::config::PARAMS;
use super::segment::{
    self, BODY_WORDS, FLAG_FIRST, FLAG_LAST, WORD_LEN, WireSegment, word_fields, words_per_part,
};
use super::wire::{Addr, EnumEntry, MessageDef, WireType};
use super::*;

fn node_suffix(def: &MessageDef, node: u8) -> String {
    match (def.addr, node) {
        (Addr::Broadcast(_), _) => String::new(),
        (Addr::ToNode(_), 0) => String::from("_All"),
        (Addr::FromNodeOrHost(_), 0) => String::from("_Host"),
        (_, n) => format!("_{n}"),
    }
}

fn sender_name(def: &MessageDef, node: u8) -> String {
    match def.addr {
        Addr::FromNode(_) => format!("Node{node}"),
        Addr::FromNodeOrHost(_) if node != 0 => format!("Node{node}"),
        _ => String::from("Host"),
    }
}

fn escape(s: &str) -> String {
    s.trim().replace('"', "'")
}

fn fmt_num(x: f64) -> String {
    if x == 0.0 {
        return String::from("0");
    }
    let s = format!("{x:e}");
    // Plain decimal for simple values, scientific otherwise.
    if libm::trunc(x) == x && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        s
    }
}

struct Sig {
    name: String,
    byte: usize,
    ty: WireType,
    scale: f64,
    unit: &'static str,
    doc: String,
    mux: Option<Option<usize>>, // None: plain, Some(None): multiplexor, Some(Some(m)): multiplexed
    values: Option<&'static [EnumEntry]>,
}

fn signals(def: &MessageDef) -> Vec<Sig> {
    let mut out = Vec::new();
    let plain = |f: &super::wire::FieldDef, mux: Option<Option<usize>>| Sig {
        name: String::from(f.name),
        byte: f.offset,
        ty: f.ty,
        scale: f.scale,
        unit: f.unit,
        doc: escape(f.doc),
        mux,
        values: f.values,
    };
    match def.mux {
        None => {
            for f in def.fields {
                out.push(plain(f, None));
            }
        }
        Some(_) if def.name.starts_with("SegmentPart") => {
            out.push(plain(&def.fields[0], Some(None)));
            out.push(plain(&def.fields[1], None));
            let wpp = words_per_part(def.fd);
            for w in 0..BODY_WORDS {
                let (part, slot) = (w / wpp, w % wpp);
                for f in word_fields(w).into_iter().flatten() {
                    out.push(Sig {
                        name: String::from(f.name),
                        byte: 2 + slot * WORD_LEN + f.offset,
                        ty: f.ty,
                        scale: f.scale,
                        unit: f.unit,
                        doc: escape(f.doc),
                        mux: Some(Some(part)),
                        values: None,
                    });
                }
            }
        }
        Some(_) if def.name.starts_with("SegmentCompact") => {
            // The fields that lie within one part (a classic part carries
            // seven body bytes: fields across two parts are in the body table).
            out.push(plain(&def.fields[0], Some(None)));
            let chunk = if def.fd { COMPACT_LEN } else { CLASSIC_CHUNK };
            for f in COMPACT_FIELDS {
                let (part, at) = (f.offset / chunk, f.offset % chunk);
                if at + f.ty.len() > chunk {
                    continue;
                }
                out.push(Sig {
                    name: String::from(f.name),
                    byte: 1 + at,
                    ty: f.ty,
                    scale: 1.0,
                    unit: f.unit,
                    doc: escape(f.doc),
                    mux: Some(Some(part)),
                    values: None,
                });
            }
        }
        Some(_) => {
            out.push(plain(&def.fields[0], Some(None)));
            for p in PARAMS {
                out.push(Sig {
                    name: String::from(p.name),
                    byte: 1,
                    ty: WireType::F32,
                    scale: 1.0,
                    unit: p.unit,
                    doc: escape(p.doc),
                    mux: Some(Some(p.index as usize)),
                    values: None,
                });
            }
        }
    }
    out
}

fn range(s: &Sig) -> (f64, f64) {
    let bits = 8 * s.ty.len() as i32;
    if s.ty.is_float() {
        (0.0, 0.0)
    } else if s.ty.signed() {
        let m = libm::pow(2.0, (bits - 1) as f64);
        (-m * s.scale, (m - 1.0) * s.scale)
    } else {
        (0.0, (libm::pow(2.0, bits as f64) - 1.0) * s.scale)
    }
}

/// The DBC file (Vector CANdb++ format; cantools reads it).
pub fn dbc() -> String {
    let mut o = String::new();
    o.push_str("VERSION \"triquint-protocol-");
    let _ = write!(o, "{PROTOCOL_VERSION}");
    o.push_str("\"\n\n\nNS_ :\n\tCM_\n\tBA_DEF_\n\tBA_\n\tVAL_\n\tBA_DEF_DEF_\n\tSIG_VALTYPE_\n\nBS_:\n\nBU_: Host Node1 Node2 Node3\n\n");
    let mut comments = String::new();
    let mut attrs = String::new();
    let mut vals = String::new();
    let mut valtypes = String::new();
    for def in all_messages() {
        let sigs = signals(def);
        for &node in def.addr.nodes() {
            let id = def.addr.id(node);
            let _ = writeln!(
                o,
                "BO_ {id} {}{}: {} {}",
                def.name,
                node_suffix(def, node),
                def.len,
                sender_name(def, node)
            );
            for s in &sigs {
                let mux = match s.mux {
                    None => String::new(),
                    Some(None) => String::from(" M"),
                    Some(Some(m)) => format!(" m{m}"),
                };
                let (lo, hi) = range(s);
                let _ = writeln!(
                    o,
                    " SG_ {}{} : {}|{}@1{} ({},0) [{}|{}] \"{}\" Vector__XXX",
                    s.name,
                    mux,
                    s.byte * 8,
                    8 * s.ty.len(),
                    if s.ty.signed() { "-" } else { "+" },
                    fmt_num(s.scale),
                    fmt_num(lo),
                    fmt_num(hi),
                    s.unit
                );
                if !s.doc.is_empty() {
                    let _ = writeln!(comments, "CM_ SG_ {id} {} \"{}\";", s.name, s.doc);
                }
                if s.ty.is_float() {
                    let _ = writeln!(valtypes, "SIG_VALTYPE_ {id} {} : 1;", s.name);
                }
                if let Some(values) = s.values {
                    let _ = write!(vals, "VAL_ {id} {}", s.name);
                    for v in values.iter().rev() {
                        let _ = write!(vals, " {} \"{}\"", v.value, v.name);
                    }
                    vals.push_str(" ;\n");
                }
            }
            o.push('\n');
            let _ = writeln!(comments, "CM_ BO_ {id} \"{}\";", escape(def.doc));
            if def.fd {
                let _ = writeln!(attrs, "BA_ \"VFrameFormat\" BO_ {id} 14;");
            }
        }
    }
    o.push('\n');
    o.push_str(&comments);
    o.push_str("BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"J1939PG\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"StandardCAN_FD\",\"ExtendedCAN_FD\";\n");
    o.push_str("BA_DEF_DEF_ \"VFrameFormat\" \"StandardCAN\";\n");
    o.push_str(&attrs);
    o.push_str(&vals);
    o.push_str(&valtypes);
    o
}

fn ids_text(def: &MessageDef) -> String {
    match def.addr {
        Addr::Broadcast(b) => format!("0x{b:03X}"),
        Addr::FromNode(b) => format!("0x{:03X}–0x{:03X} (0x{b:03X} + node)", b + 1, b + 3),
        Addr::ToNode(b) => format!("0x{b:03X} + node (0x{b:03X} = all)"),
        Addr::FromNodeOrHost(b) => format!("0x{b:03X} + node (0x{b:03X} = host)"),
    }
}

fn enum_table(o: &mut String, title: &str, t: &[EnumEntry]) {
    let _ = writeln!(
        o,
        "#### {title}\n\n| Value | Name | Meaning |\n|---:|---|---|"
    );
    for e in t {
        let _ = writeln!(o, "| {} | {} | {} |", e.value, e.name, e.doc.trim());
    }
    o.push('\n');
}

/// The generated part of docs/protocol.md (between the GENERATED markers).
pub fn markdown() -> String {
    let mut o = String::new();
    o.push_str("### Identifiers (lower = higher priority)\n\n| Message | Identifier | Sender | Bytes | Period | Description |\n|---|---|---|---:|---|---|\n");
    for def in all_messages() {
        let _ = writeln!(
            o,
            "| {} | {} | {} | {} | {} | {} |",
            def.name,
            ids_text(def),
            def.sender,
            def.len,
            def.period,
            def.doc.trim()
        );
    }
    o.push_str(
        "\n### Message layouts\n\nAll fields little-endian; byte offsets within the payload.\n\n",
    );
    for def in all_messages() {
        let _ = writeln!(
            o,
            "#### {} ({}, {} bytes{})\n\n{}\n\n| Byte | Field | Type | Unit | Scale | Description |\n|---:|---|---|---|---|---|",
            def.name,
            ids_text(def),
            def.len,
            if def.fd { ", CAN-FD" } else { "" },
            def.doc.trim()
        );
        for f in def.fields {
            let mut doc = String::from(f.doc.trim());
            if f.values.is_some() {
                doc.push_str(" (code table below)");
            }
            let _ = writeln!(
                o,
                "| {} | {} | {} | {} | {} | {} |",
                f.offset,
                f.name,
                f.ty.name(),
                f.unit,
                fmt_num(f.scale),
                doc
            );
        }
        // Segment parts: the body words after the declared bytes. Parameter
        // frames need no extra row: index and value are declared fields.
        if def.name.starts_with("SegmentCompact") {
            let chunk = if def.fd { COMPACT_LEN } else { CLASSIC_CHUNK };
            let _ = writeln!(
                o,
                "| 1–{chunk} | body | {chunk} bytes | | | Compact body bytes {chunk}·part … {chunk}·part+{} |",
                chunk - 1
            );
        } else if def.mux == Some("part") {
            let wpp = words_per_part(def.fd);
            let _ = writeln!(
                o,
                "| 2–{} | words | {}×6 bytes | | | Body words {}·part … {}·part+{} |",
                1 + wpp * WORD_LEN,
                wpp,
                wpp,
                wpp,
                wpp - 1
            );
        }
        o.push('\n');
    }
    o.push_str("### Segment body (20 words of 6 bytes)\n\n| Word | Byte in body | Field | Type | Unit | Scale | Description |\n|---:|---:|---|---|---|---|---|\n");
    for w in 0..BODY_WORDS {
        for f in word_fields(w).into_iter().flatten() {
            let _ = writeln!(
                o,
                "| {w} | {} | {} | {} | {} | {} | {} |",
                w * WORD_LEN + f.offset,
                f.name,
                f.ty.name(),
                f.unit,
                fmt_num(f.scale),
                f.doc.trim()
            );
        }
    }
    let _ = writeln!(
        o,
        "\n### Compact segment body ({COMPACT_LEN} bytes)\n\n| Byte in body | Field | Type | Unit | Description |\n|---:|---|---|---|---|"
    );
    for f in COMPACT_FIELDS {
        let _ = writeln!(
            o,
            "| {} | {} | {} | {} | {} |",
            f.offset,
            f.name,
            f.ty.name(),
            f.unit,
            f.doc.trim()
        );
    }
    o.push_str("\n### Configuration parameters (ConfigWrite/ConfigValue index)\n\n| Index | Name | Unit | Description |\n|---:|---|---|---|\n");
    for p in PARAMS {
        let _ = writeln!(
            o,
            "| {} | {} | {} | {} |",
            p.index,
            p.name,
            p.unit,
            p.doc.trim()
        );
    }
    o.push_str("\n### Acceptance bounds (applied by every drive)\n\n| Bound | Value | Unit | Meaning |\n|---|---:|---|---|\n");
    for b in super::contract::BOUNDS {
        // f32 constants in decimal units: round away the binary representation error.
        let v = libm::round(b.value * 1e6) / 1e6;
        let _ = writeln!(o, "| {} | {v} | {} | {} |", b.name, b.unit, b.doc);
    }
    o.push_str("\n### Code tables\n\n");
    enum_table(&mut o, "State", State::TABLE);
    enum_table(&mut o, "FaultCode", FaultCode::TABLE);
    enum_table(&mut o, "Reject (SegmentAck.result)", Reject::TABLE);
    enum_table(&mut o, "CommandCode", CommandCode::TABLE);
    o.push_str(
        "#### HeartbeatExt flags

| Bit | Name | Meaning |
|---:|---|---|
",
    );
    for (bit, name, doc) in flags::TABLE {
        let _ = writeln!(o, "| {} | {name} | {doc} |", bit.trailing_zeros());
    }
    o
}

/// What a golden frame decodes to.
#[derive(Clone, Debug, PartialEq)]
pub enum Expect {
    Msg(Msg),
    /// One part of this segment (a compact one: the segment rebuilt from
    /// the full segment before it).
    Part(WireSegment),
}

/// Sample segment of the golden vectors: a real-looking quintic.
pub fn golden_segment() -> WireSegment {
    let q = crate::quintic::Quintic {
        coeffs: [
            [0.376_68, 0.0, 0.0, -0.284_1, 0.426_2, -0.170_5],
            [0.244_16, 0.0, 0.0, -0.289_3, 0.434_0, -0.173_6],
            [0.336_13, 0.0, 0.0, -0.284_1, 0.426_2, -0.170_5],
        ],
        duration: 0.431_250,
    };
    WireSegment::from_quintic(0x0102, &q, FLAG_FIRST | FLAG_LAST).unwrap_or(WireSegment {
        seq: 0,
        duration_us: 0,
        flags: 0,
        coeffs: [[0; 6]; 3],
    })
}

/// Golden frames: (label, frame, what it decodes to).
pub fn golden_frames() -> Vec<(String, Frame, Expect)> {
    let mut v: Vec<(String, Frame, Expect)> = Vec::new();
    let mut add = |label: &str, f: Frame, m: Msg| v.push((String::from(label), f, Expect::Msg(m)));
    let e = Emergency {
        code: FaultCode::Underrun as u8,
        state: State::Stopping as u8,
        ramp_100us: 3_471,
        plan_time_us: 2_345_678,
    };
    add("Emergency_2", e.to_frame(2), Msg::Emergency(e));
    let e = Emergency {
        code: FaultCode::HostEmergency as u8,
        state: State::Fault as u8,
        ramp_100us: 0,
        plan_time_us: 0,
    };
    add("Emergency_Host", e.to_frame(0), Msg::Emergency(e));
    let s = TimeSync {
        seq: 42,
        prev_tx_us: 4_000_100_200,
    };
    add("TimeSync", s.to_frame(0), Msg::TimeSync(s));
    for (label, node, c) in [
        (
            "Command_All Start",
            0,
            Command {
                command: CommandCode::Start as u8,
                token: 7,
                arg: 1_250_000,
                arg2: 0,
            },
        ),
        (
            "Command_1 Arm",
            1,
            Command {
                command: CommandCode::Arm as u8,
                token: 8,
                arg: 0,
                arg2: 0,
            },
        ),
        (
            "Command_5 Home",
            5,
            Command {
                command: CommandCode::Home as u8,
                token: 10,
                arg: 0,
                arg2: 0,
            },
        ),
        (
            "Command_3 ConfigCommit",
            3,
            Command {
                command: CommandCode::ConfigCommit as u8,
                token: 9,
                arg: 0x1234_ABCD,
                arg2: 0,
            },
        ),
    ] {
        add(label, c.to_frame(node), Msg::Command(c));
    }
    add(
        "ConfigWrite_2 kp",
        config_write_frame(2, 18, 2009.5),
        Msg::ConfigWrite {
            index: 18,
            value: 2009.5,
        },
    );
    let a = SegmentAck {
        seq: 258,
        result: Reject::BadCrc as u8,
        depth: 3,
        next_seq: 258,
        capacity: 8,
        reason_count: 1,
    };
    add("SegmentAck_3", a.to_frame(3), Msg::SegmentAck(a));
    let a = CommandAck {
        command: CommandCode::Arm as u8,
        token: 8,
        result: FaultCode::ArmTooFar as u8,
        state: State::Fault as u8,
        value: 0,
    };
    add("CommandAck_1", a.to_frame(1), Msg::CommandAck(a));
    let a = CommandAck {
        command: CommandCode::Arm as u8,
        token: 11,
        result: FaultCode::NotHomed as u8,
        state: State::Loaded as u8,
        value: 0,
    };
    add("CommandAck_6", a.to_frame(6), Msg::CommandAck(a));
    add(
        "ConfigValue_1 lead",
        config_value_frame(1, 12, 0.01),
        Msg::ConfigValue {
            index: 12,
            value: 0.01,
        },
    );
    let h = Heartbeat {
        state: State::Running as u8,
        fault: 0,
        queue_depth: 6,
        protocol_version: PROTOCOL_VERSION,
        config_crc: 0x89AB_CDEF,
    };
    add("Heartbeat_2", h.to_frame(2), Msg::Heartbeat(h));
    let h = HeartbeatExt {
        next_seq: 300,
        rejects: 2,
        tx_errors: 0,
        rx_errors: 1,
        last_reject: Reject::Duplicate as u8,
        flags: flags::SYNCED | flags::HOMED | flags::CONFIGURED,
    };
    add("HeartbeatExt_2", h.to_frame(2), Msg::HeartbeatExt(h));
    let h = HeartbeatExt {
        next_seq: 0,
        rejects: 0,
        tx_errors: 0,
        rx_errors: 0,
        last_reject: 0,
        flags: flags::SYNCED | flags::SWITCH,
    };
    add("HeartbeatExt_15", h.to_frame(15), Msg::HeartbeatExt(h));
    let t = Telemetry {
        position: 0.356_68,
        velocity: -0.125,
    };
    add("Telemetry_1", t.to_frame(1), Msg::Telemetry(t));
    let t = TelemetryExt {
        torque: 0.062_5,
        following_error: 2.5e-6,
    };
    add("TelemetryExt_1", t.to_frame(1), Msg::TelemetryExt(t));
    let seg = golden_segment();
    let (next, rebuilt) = golden_continuation();
    for fd in [false, true] {
        for (p, f) in seg.frames(fd).enumerate() {
            let label = if fd {
                format!("SegmentPartFd part {p}")
            } else {
                format!("SegmentPart part {p}")
            };
            v.push((label, f, Expect::Part(seg)));
        }
        for (p, f) in next.frames(fd).enumerate() {
            let label = if fd {
                format!("SegmentCompactFd part {p}")
            } else {
                format!("SegmentCompact part {p}")
            };
            v.push((label, f, Expect::Part(rebuilt)));
        }
    }
    v
}

/// The golden segment's continuation (the same polynomial for 0.2 s more),
/// compact, and the segment a receiver rebuilds from it.
pub fn golden_continuation() -> (Compact, WireSegment) {
    let seg = golden_segment();
    let h = seg.duration_us as f64 * 1e-6;
    let coeffs = seg.normalised_f64().map(|b| {
        // Back to seconds, then shifted to t = h (Taylor coefficients there).
        let c: [f64; 6] = core::array::from_fn(|k| b[k] / libm::pow(h, k as f64));
        core::array::from_fn(|m| {
            (m..6)
                .map(|k| {
                    let binom = (0..m).fold(1.0, |a, i| a * (k - i) as f64 / (i + 1) as f64);
                    c[k] * binom * libm::pow(h, (k - m) as f64)
                })
                .sum()
        })
    });
    let q = crate::quintic::Quintic {
        coeffs,
        duration: 0.2,
    };
    let next = WireSegment::from_quintic(seg.seq.wrapping_add(1), &q, FLAG_LAST).unwrap_or(seg);
    Compact::continuing(&seg.into(), &next, None, &DeviationBound::DEFAULT)
        .map(|(c, held)| (c, held.segment))
        .unwrap_or((
            Compact {
                seq: 0,
                duration_us: 0,
                flags: 0,
                exp: 0,
                mantissas: [[0; 2]; 3],
                pose: [0; 3],
                crc: 0,
            },
            seg,
        ))
}

/// The golden vector file: one frame per line, `label | id | fd | hex payload`.
pub fn golden_text() -> String {
    let mut o = String::from(
        "# triquint CAN protocol golden vectors (generated; TRIQUINT_BLESS=1 to rewrite)\n\
         # label | identifier (hex) | C(lassic)/F(D) | payload (hex)\n",
    );
    for (label, f, _) in golden_frames() {
        let _ = write!(
            o,
            "{label} | {:03X} | {} | ",
            f.id,
            if f.fd { 'F' } else { 'C' }
        );
        for b in f.payload() {
            let _ = write!(o, "{b:02X}");
        }
        o.push('\n');
    }
    o
}

/// Parses one line of the golden file back into a frame.
pub fn parse_golden_line(line: &str) -> Option<(String, Frame)> {
    let parts: Vec<&str> = line.split('|').map(str::trim).collect();
    if parts.len() != 4 || line.starts_with('#') {
        return None;
    }
    let id = u16::from_str_radix(parts[1], 16).ok()?;
    let fd = parts[2] == "F";
    let hex = parts[3];
    let bytes: Option<Vec<u8>> = (0..hex.len() / 2)
        .map(|i| u8::from_str_radix(hex.get(2 * i..2 * i + 2)?, 16).ok())
        .collect();
    Some((String::from(parts[0]), Frame::with_payload(id, &bytes?, fd)))
}

/// Frames per segment (classic, FD), full and compact, for reports.
pub const FRAMES_PER_SEGMENT: [(usize, usize); 2] = [
    (
        segment::parts_per_segment(false),
        segment::parts_per_segment(true),
    ),
    (
        compact::compact_parts(0, false),
        compact::compact_parts(0, true),
    ),
];

#[cfg(test)]
mod tests {
    use super::*;
    use std::path::PathBuf;

    fn repo_file(rel: &str) -> PathBuf {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
            .join("..")
            .join(rel)
    }

    /// Compares `generated` with the committed file, or rewrites it under TRIQUINT_BLESS=1.
    fn check_or_bless(rel: &str, generated: &str) {
        let path = repo_file(rel);
        if std::env::var_os("TRIQUINT_BLESS").is_some() {
            if let Some(dir) = path.parent() {
                std::fs::create_dir_all(dir).unwrap();
            }
            std::fs::write(&path, generated).unwrap();
            return;
        }
        let committed = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{}: {e} (TRIQUINT_BLESS=1 to generate)", path.display()));
        assert!(
            committed == generated,
            "{rel} is stale: regenerate with TRIQUINT_BLESS=1 cargo test -p triquint-shared protocol"
        );
    }

    const BEGIN: &str = "<!-- BEGIN GENERATED: do not edit, TRIQUINT_BLESS=1 cargo test -p triquint-shared protocol -->\n";
    const END: &str = "<!-- END GENERATED -->";

    #[test]
    fn dbc_is_current() {
        check_or_bless("docs/triquint.dbc", &dbc());
    }

    #[test]
    fn protocol_md_tables_are_current() {
        let path = repo_file("docs/protocol.md");
        let text = std::fs::read_to_string(&path).unwrap();
        let (Some(a), Some(b)) = (text.find(BEGIN), text.find(END)) else {
            panic!("docs/protocol.md lacks the GENERATED markers");
        };
        let expected = std::format!("{}{}{}{}", &text[..a], BEGIN, markdown(), &text[b..]);
        check_or_bless("docs/protocol.md", &expected);
    }

    #[test]
    fn golden_vectors_both_directions() {
        check_or_bless("testdata/protocol/golden.txt", &golden_text());
        // Decode the committed file and compare with the declared samples.
        let text = std::fs::read_to_string(repo_file("testdata/protocol/golden.txt")).unwrap();
        let parsed: Vec<(String, Frame)> = text.lines().filter_map(parse_golden_line).collect();
        let samples = golden_frames();
        assert_eq!(parsed.len(), samples.len());
        let mut rx = SegmentRx::default();
        let mut complete = 0;
        for ((label, frame), (l2, f2, expect)) in parsed.iter().zip(samples.iter()) {
            assert_eq!(label, l2);
            assert_eq!(frame, f2, "{label}: bytes differ");
            let (msg, _) = decode(frame).unwrap();
            match expect {
                Expect::Msg(m) => assert_eq!(msg, *m, "{label}"),
                Expect::Part(seg) => match rx.push(msg.kind(), frame.payload()) {
                    Some(SegmentEvent::Pending) => {}
                    Some(SegmentEvent::Complete { segment, .. }) => {
                        assert_eq!(segment, *seg, "{label}");
                        complete += 1;
                    }
                    e => panic!("{label}: {e:?}"),
                },
            }
        }
        // Full and compact, classic and CAN-FD.
        assert_eq!(complete, 4);
        assert_ne!(
            golden_continuation().0.seq,
            0,
            "the continuation is compact"
        );
    }

    #[test]
    fn dbc_lists_every_identifier_once() {
        let d = dbc();
        let mut n = 0;
        for def in all_messages() {
            for &node in def.addr.nodes() {
                let id = def.addr.id(node);
                assert_eq!(
                    d.matches(&std::format!("\nBO_ {id} ")).count(),
                    1,
                    "{} node {node}",
                    def.name
                );
                n += 1;
            }
        }
        assert_eq!(d.matches("\nBO_ ").count(), n);
    }
}
