//! Any protocol frame as named fields with units, read from the declaration
//! itself (the monitor, logs, captures), and back to bytes.

extern crate alloc;

use alloc::vec::Vec;
use core::fmt;

use super::wire::{FieldDef, MessageDef, WireType, get_i48, put_i48};
use super::{DecodeError, Frame, PARAMS, all_messages, decode};

/// A field's value in physical units.
#[derive(Clone, Debug, PartialEq)]
pub enum Value {
    Unsigned(u64),
    Signed(i64),
    Float(f64),
    /// A code with its name from the code table (`None`: not in the table).
    Code(u8, Option<&'static str>),
    /// Opaque bytes (the body words of a segment part).
    Bytes(Vec<u8>),
}

/// One field of a described frame.
#[derive(Clone, Debug, PartialEq)]
pub struct Field {
    pub name: &'static str,
    pub value: Value,
    pub unit: &'static str,
}

/// A frame in the declaration's terms.
#[derive(Clone, Debug, PartialEq)]
pub struct Described {
    pub def: &'static MessageDef,
    /// Node number in the identifier (0 = host or all nodes).
    pub node: u8,
    pub fields: Vec<Field>,
}

fn read(ty: WireType, p: &[u8], off: usize) -> (u64, i64, f64) {
    let b = |i: usize| p.get(off + i).copied().unwrap_or(0);
    match ty {
        WireType::U8 => (b(0) as u64, b(0) as i64, 0.0),
        WireType::U16 => {
            let v = u16::from_le_bytes([b(0), b(1)]);
            (v as u64, v as i64, 0.0)
        }
        WireType::U32 => {
            let v = u32::from_le_bytes([b(0), b(1), b(2), b(3)]);
            (v as u64, v as i64, 0.0)
        }
        WireType::I16 => {
            let v = i16::from_le_bytes([b(0), b(1)]);
            (v as u64, v as i64, 0.0)
        }
        WireType::I32 => {
            let v = i32::from_le_bytes([b(0), b(1), b(2), b(3)]);
            (v as u64, v as i64, 0.0)
        }
        WireType::U24 => {
            let v = u32::from_le_bytes([b(0), b(1), b(2), 0]);
            (v as u64, v as i64, 0.0)
        }
        WireType::I24 => {
            let v = i32::from_le_bytes([b(0), b(1), b(2), 0]) << 8 >> 8;
            (v as u64, v as i64, 0.0)
        }
        WireType::I48 => {
            let v = get_i48(p, off);
            (v as u64, v, 0.0)
        }
        WireType::F32 => (0, 0, f32::from_le_bytes([b(0), b(1), b(2), b(3)]) as f64),
    }
}

fn field_value(f: &FieldDef, p: &[u8]) -> Value {
    let (u, i, x) = read(f.ty, p, f.offset);
    if let Some(table) = f.values {
        let name = table.iter().find(|e| e.value as u64 == u).map(|e| e.name);
        return Value::Code(u as u8, name);
    }
    match f.ty {
        WireType::F32 => Value::Float(x * f.scale),
        _ if f.scale != 1.0 => Value::Float(i as f64 * f.scale),
        WireType::U8 | WireType::U16 | WireType::U24 | WireType::U32 => Value::Unsigned(u),
        _ => Value::Signed(i),
    }
}

/// Where the body bytes of a segment part begin: after its declared fields.
fn body_at(def: &MessageDef) -> usize {
    def.fields
        .iter()
        .map(|f| f.offset + f.ty.len())
        .max()
        .unwrap_or(0)
}

/// Describes a frame: the message, the node, every field with its unit.
/// Configuration frames name the parameter and give its unit; segment parts
/// give the part index, the sequence byte and the body words.
pub fn describe(frame: &Frame) -> Result<Described, DecodeError> {
    let (_, node) = decode(frame)?;
    let def = all_messages()
        .into_iter()
        .find(|d| d.addr.matches(frame.id).is_some())
        .ok_or(DecodeError::UnknownId(frame.id))?;
    let p = frame.payload();
    let mut fields: Vec<Field> = Vec::new();
    match def.mux {
        Some("index") => {
            let (u, _, _) = read(WireType::U8, p, 0);
            let param = PARAMS.get(u as usize);
            let (_, _, x) = read(WireType::F32, p, 1);
            fields.push(Field {
                name: "index",
                value: Value::Code(u as u8, param.map(|q| q.name)),
                unit: "",
            });
            fields.push(Field {
                name: "value",
                value: Value::Float(x),
                unit: param.map_or("", |q| q.unit),
            });
        }
        _ => {
            for f in def.fields {
                fields.push(Field {
                    name: f.name,
                    value: field_value(f, p),
                    unit: f.unit,
                });
            }
            if def.mux == Some("part") {
                fields.push(Field {
                    name: "words",
                    value: Value::Bytes(p.get(body_at(def)..).unwrap_or(&[]).to_vec()),
                    unit: "",
                });
            }
        }
    }
    Ok(Described { def, node, fields })
}

fn put(ty: WireType, v: &Value, scale: f64, buf: &mut [u8], off: usize) {
    let raw_i = |x: f64| libm::round(x / scale) as i64;
    let int = match v {
        Value::Unsigned(u) => *u as i64,
        Value::Signed(i) => *i,
        Value::Code(c, _) => *c as i64,
        Value::Float(x) if ty != WireType::F32 => raw_i(*x),
        Value::Float(_) | Value::Bytes(_) => 0,
    };
    let mut w = |bytes: &[u8]| {
        if let Some(dst) = buf.get_mut(off..off + bytes.len()) {
            dst.copy_from_slice(bytes);
        }
    };
    match ty {
        WireType::U8 => w(&[int as u8]),
        WireType::U16 | WireType::I16 => w(&(int as u16).to_le_bytes()),
        WireType::U32 | WireType::I32 => w(&(int as u32).to_le_bytes()),
        WireType::U24 | WireType::I24 => w(&(int as u32).to_le_bytes()[..3]),
        WireType::I48 => put_i48(int, buf, off),
        WireType::F32 => {
            let x = match v {
                Value::Float(x) => *x / scale,
                _ => int as f64,
            };
            w(&(x as f32).to_le_bytes())
        }
    }
}

impl Described {
    /// The frame again, from the physical values (the inverse of [`describe`]).
    pub fn encode(&self, len: usize, fd: bool) -> Frame {
        let mut f = Frame::new(self.def.addr.id(self.node), len, fd);
        let get = |name: &str| self.fields.iter().find(|x| x.name == name);
        if self.def.mux == Some("index") {
            if let (Some(i), Some(v)) = (get("index"), get("value")) {
                put(WireType::U8, &i.value, 1.0, &mut f.data, 0);
                put(WireType::F32, &v.value, 1.0, &mut f.data, 1);
            }
            return f;
        }
        for d in self.def.fields {
            if let Some(x) = get(d.name) {
                put(d.ty, &x.value, d.scale, &mut f.data, d.offset);
            }
        }
        if let Some(Field {
            value: Value::Bytes(b),
            ..
        }) = get("words")
        {
            let at = body_at(self.def);
            let n = b.len().min(f.data.len().saturating_sub(at));
            f.data[at..at + n].copy_from_slice(&b[..n]);
        }
        f
    }
}

impl fmt::Display for Value {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Value::Unsigned(u) => write!(f, "{u}"),
            Value::Signed(i) => write!(f, "{i}"),
            Value::Float(x) => write!(f, "{x}"),
            Value::Code(c, Some(n)) => write!(f, "{n}({c})"),
            Value::Code(c, None) => write!(f, "?({c})"),
            Value::Bytes(b) => {
                for x in b {
                    write!(f, "{x:02X}")?;
                }
                Ok(())
            }
        }
    }
}

impl fmt::Display for Described {
    /// `Heartbeat[2] state=Running(3) fault=None(0) … config_crc=0x89ABCDEF`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}[{}]", self.def.name, self.node)?;
        for x in &self.fields {
            match (&x.value, x.name.ends_with("crc")) {
                (Value::Unsigned(u), true) => write!(f, " {}=0x{u:08X}", x.name)?,
                (v, _) if x.unit.is_empty() => write!(f, " {}={v}", x.name)?,
                (v, _) => write!(f, " {}={v} {}", x.name, x.unit)?,
            }
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::generate::golden_frames;

    #[test]
    fn every_golden_frame_is_described_and_encoded_back() {
        for (label, frame, _) in golden_frames() {
            let d = describe(&frame).unwrap_or_else(|e| panic!("{label}: {e}"));
            let back = d.encode(frame.len as usize, frame.fd);
            assert_eq!(back.payload(), frame.payload(), "{label}: {d}");
            assert_eq!(back.id, frame.id, "{label}");
        }
    }

    #[test]
    fn names_units_and_codes() {
        use crate::protocol::{Heartbeat, Telemetry, config_write_frame};
        let t = describe(
            &Telemetry {
                position: 0.5,
                velocity: -0.25,
            }
            .to_frame(3),
        )
        .unwrap();
        assert_eq!(
            alloc::format!("{t}"),
            "Telemetry[3] position=0.5 m velocity=-0.25 m/s"
        );
        let h = describe(
            &Heartbeat {
                state: 3,
                fault: 99,
                queue_depth: 2,
                protocol_version: 1,
                config_crc: 0xDEAD_BEEF,
            }
            .to_frame(1),
        )
        .unwrap();
        let text = alloc::format!("{h}");
        assert!(text.contains("state=Running(3)"), "{text}");
        assert!(text.contains("fault=?(99)"), "{text}");
        assert!(text.contains("config_crc=0xDEADBEEF"), "{text}");
        let c = describe(&config_write_frame(2, 12, 0.01)).unwrap();
        assert_eq!(c.node, 2);
        assert_eq!(c.fields[0].value, Value::Code(12, Some(PARAMS[12].name)));
        assert_eq!(c.fields[1].unit, PARAMS[12].unit);
    }
}
