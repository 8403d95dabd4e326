//! The building blocks of the message declaration: wire types, field and
//! message descriptors, and the two declaration macros.

/// Fixed-layout wire types. All little-endian and byte-aligned.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WireType {
    U8,
    U16,
    U32,
    I16,
    I32,
    /// Unsigned 24-bit integer (compact segment duration).
    U24,
    /// Signed 24-bit two's complement integer (compact segment mantissas).
    I24,
    /// Signed 48-bit two's complement integer (segment coefficients).
    I48,
    /// IEEE 754 binary32.
    F32,
}

impl WireType {
    pub const fn len(self) -> usize {
        match self {
            WireType::U8 => 1,
            WireType::U16 | WireType::I16 => 2,
            WireType::U24 | WireType::I24 => 3,
            WireType::U32 | WireType::I32 | WireType::F32 => 4,
            WireType::I48 => 6,
        }
    }
    pub const fn is_empty(self) -> bool {
        false
    }
    pub const fn signed(self) -> bool {
        matches!(
            self,
            WireType::I16 | WireType::I24 | WireType::I32 | WireType::I48 | WireType::F32
        )
    }
    pub const fn is_float(self) -> bool {
        matches!(self, WireType::F32)
    }
    /// Name used in docs/protocol.md.
    pub const fn name(self) -> &'static str {
        match self {
            WireType::U8 => "u8",
            WireType::U16 => "u16",
            WireType::U32 => "u32",
            WireType::I16 => "i16",
            WireType::I32 => "i32",
            WireType::U24 => "u24",
            WireType::I24 => "i24",
            WireType::I48 => "i48",
            WireType::F32 => "f32",
        }
    }
}

/// A Rust type that travels as one [`WireType`].
pub trait Wire: Copy {
    const TYPE: WireType;
    /// Writes `self` little-endian at `off`. `buf` must be long enough
    /// (guaranteed by the declaration tests); short buffers write nothing.
    fn put(self, buf: &mut [u8], off: usize);
    /// Reads little-endian at `off`; missing bytes read as zero.
    fn get(buf: &[u8], off: usize) -> Self;
}

fn put_bytes<const N: usize>(bytes: [u8; N], buf: &mut [u8], off: usize) {
    if let Some(dst) = buf.get_mut(off..off + N) {
        dst.copy_from_slice(&bytes);
    }
}

fn get_bytes<const N: usize>(buf: &[u8], off: usize) -> [u8; N] {
    let mut out = [0u8; N];
    for (i, b) in out.iter_mut().enumerate() {
        *b = buf.get(off + i).copied().unwrap_or(0);
    }
    out
}

macro_rules! impl_wire {
    ($t:ty, $w:ident, $n:literal) => {
        impl Wire for $t {
            const TYPE: WireType = WireType::$w;
            fn put(self, buf: &mut [u8], off: usize) {
                put_bytes::<$n>(self.to_le_bytes(), buf, off)
            }
            fn get(buf: &[u8], off: usize) -> Self {
                <$t>::from_le_bytes(get_bytes::<$n>(buf, off))
            }
        }
    };
}
impl_wire!(u8, U8, 1);
impl_wire!(u16, U16, 2);
impl_wire!(u32, U32, 4);
impl_wire!(i16, I16, 2);
impl_wire!(i32, I32, 4);
impl_wire!(f32, F32, 4);

/// Writes the low 48 bits of `v` little-endian.
pub fn put_i48(v: i64, buf: &mut [u8], off: usize) {
    let b = v.to_le_bytes();
    put_bytes::<6>([b[0], b[1], b[2], b[3], b[4], b[5]], buf, off)
}

/// Reads a sign-extended 48-bit integer.
pub fn get_i48(buf: &[u8], off: usize) -> i64 {
    let b = get_bytes::<6>(buf, off);
    let raw = i64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], 0, 0]);
    (raw << 16) >> 16
}

/// Largest magnitude an i48 holds.
pub const I48_MAX: i64 = (1 << 47) - 1;

/// The spec's prose (what a message, field, code or parameter means): kept
/// where the DBC and docs are generated, empty in the drives' images, whose
/// flash it would otherwise fill through the tables the codec references.
#[cfg(any(feature = "alloc", test))]
macro_rules! spec_text {
    ($($s:literal),* $(,)?) => {
        concat!($($s),*)
    };
}
#[cfg(not(any(feature = "alloc", test)))]
macro_rules! spec_text {
    ($($s:literal),* $(,)?) => {
        ""
    };
}
pub(crate) use spec_text;

/// One named value of a code enumeration (state, fault, reject reason, command).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct EnumEntry {
    pub value: u8,
    pub name: &'static str,
    pub doc: &'static str,
}

/// One field of a message.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FieldDef {
    pub name: &'static str,
    /// Byte offset in the payload.
    pub offset: usize,
    pub ty: WireType,
    /// Physical value = raw × scale.
    pub scale: f64,
    pub unit: &'static str,
    pub doc: &'static str,
    /// For code fields: the enumeration the value is taken from.
    pub values: Option<&'static [EnumEntry]>,
}

/// Highest node id: ids 1–15 share the bus (node 0 is the host or "all").
pub const MAX_NODE_ID: u8 = 15;
const ALL_NODES: [u8; MAX_NODE_ID as usize + 1] =
    [0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15];
const NODE_IDS: [u8; MAX_NODE_ID as usize] = [1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 12, 13, 14, 15];

/// How a message's identifier depends on the node.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Addr {
    /// One identifier for everybody.
    Broadcast(u16),
    /// Sent by node n (1–15) on `base + n`.
    FromNode(u16),
    /// Sent by the host to node n on `base + n`, or to all nodes on `base + 0`.
    ToNode(u16),
    /// Sent by node n on `base + n`, or by the host on `base + 0`.
    FromNodeOrHost(u16),
}

impl Addr {
    pub const fn base(self) -> u16 {
        match self {
            Addr::Broadcast(b) | Addr::FromNode(b) | Addr::ToNode(b) | Addr::FromNodeOrHost(b) => b,
        }
    }
    /// Identifier for node `node` (0 = host/broadcast).
    pub const fn id(self, node: u8) -> u16 {
        match self {
            Addr::Broadcast(b) => b,
            _ => self.base() + node as u16,
        }
    }
    /// Node numbers this message exists for (0 = host or broadcast).
    pub const fn nodes(self) -> &'static [u8] {
        match self {
            Addr::Broadcast(_) => &[0],
            Addr::FromNode(_) => &NODE_IDS,
            Addr::ToNode(_) | Addr::FromNodeOrHost(_) => &ALL_NODES,
        }
    }
    /// Does `id` belong to this message? Returns the node number.
    pub const fn matches(self, id: u16) -> Option<u8> {
        let base = self.base();
        if id < base {
            return None;
        }
        let n = id - base;
        match self {
            Addr::Broadcast(_) if n == 0 => Some(0),
            Addr::FromNode(_) if n >= 1 && n <= MAX_NODE_ID as u16 => Some(n as u8),
            Addr::ToNode(_) | Addr::FromNodeOrHost(_) if n <= MAX_NODE_ID as u16 => Some(n as u8),
            _ => None,
        }
    }
}

/// Declaration of one message: everything the codec, the DBC and the spec need.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MessageDef {
    pub name: &'static str,
    pub addr: Addr,
    /// Payload length (bytes); DLC on classic CAN.
    pub len: usize,
    pub sender: &'static str,
    pub period: &'static str,
    pub doc: &'static str,
    /// Byte 0 is a multiplexor (part or parameter index); the multiplexed
    /// layouts are described by the segment or config tables.
    pub mux: Option<&'static str>,
    /// Sent as a CAN-FD frame.
    pub fd: bool,
    pub fields: &'static [FieldDef],
}

/// Declares a `u8` code enumeration with its documentation table.
macro_rules! code_enum {
    (
        $(#[doc = $doc:literal])*
        $name:ident { $( $(#[doc = $vdoc:literal])* $v:ident = $n:literal ),* $(,)? }
    ) => {
        $(#[doc = $doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        #[repr(u8)]
        pub enum $name { $( $(#[doc = $vdoc])* $v = $n ),* }

        impl $name {
            /// Every value with its name and meaning (for the spec and the DBC).
            pub const TABLE: &'static [$crate::protocol::wire::EnumEntry] = &[
                $( $crate::protocol::wire::EnumEntry {
                    value: $n, name: stringify!($v), doc: $crate::protocol::wire::spec_text!($($vdoc),*)
                } ),*
            ];
            pub const fn from_u8(x: u8) -> Option<Self> {
                match x { $( $n => Some(Self::$v), )* _ => None }
            }
            pub const fn name(self) -> &'static str {
                match self { $( Self::$v => stringify!($v), )* }
            }
        }
    };
}

/// Declares fixed-layout messages: a struct per message with `encode`,
/// `decode` and a `DEF` descriptor, and the list `SIMPLE_MESSAGES`.
macro_rules! messages {
    ($(
        $(#[doc = $doc:literal])*
        $name:ident = $addr:expr, len $len:literal, from $sender:literal, every $period:literal {
            $(
                $(#[doc = $fdoc:literal])*
                $field:ident : $ty:ident @ $off:literal [$unit:literal, $scale:literal $(, $enum:ident)?]
            ),* $(,)?
        }
    )*) => {
        $(
            $(#[doc = $doc])*
            #[derive(Clone, Copy, Debug, PartialEq, Default)]
            pub struct $name { $( $(#[doc = $fdoc])* pub $field: $ty, )* }

            impl $name {
                pub const DEF: $crate::protocol::wire::MessageDef = $crate::protocol::wire::MessageDef {
                    name: stringify!($name),
                    addr: $addr,
                    len: $len,
                    sender: $sender,
                    period: $period,
                    doc: $crate::protocol::wire::spec_text!($($doc),*),
                    mux: None,
                    fd: false,
                    fields: &[ $( $crate::protocol::wire::FieldDef {
                        name: stringify!($field),
                        offset: $off,
                        ty: <$ty as $crate::protocol::wire::Wire>::TYPE,
                        scale: $scale,
                        unit: $unit,
                        doc: $crate::protocol::wire::spec_text!($($fdoc),*),
                        values: messages!(@values $($enum)?),
                    } ),* ],
                };
                /// Payload bytes (length `DEF.len`).
                pub fn encode(&self) -> [u8; $len] {
                    let mut buf = [0u8; $len];
                    $( $crate::protocol::wire::Wire::put(self.$field, &mut buf, $off); )*
                    buf
                }
                /// Decodes a payload; missing bytes read as zero (callers check the length).
                pub fn decode(buf: &[u8]) -> Self {
                    Self { $( $field: $crate::protocol::wire::Wire::get(buf, $off), )* }
                }
                $( messages!(@code $field $($enum)?); )*
            }
        )*
        /// Every fixed-layout message, in identifier order.
        pub const SIMPLE_MESSAGES: &[&$crate::protocol::wire::MessageDef] = &[ $( &$name::DEF ),* ];
    };
    (@code $field:ident) => {};
    (@code $field:ident $enum:ident) => {
        /// This code field decoded to its table; `Err(raw)` for a value not in it.
        pub const fn $field(&self) -> Result<$enum, u8> {
            match $enum::from_u8(self.$field) {
                Some(v) => Ok(v),
                None => Err(self.$field),
            }
        }
    };
    (@values) => { None };
    (@values $enum:ident) => { Some($enum::TABLE) };
}

pub(crate) use code_enum;
pub(crate) use messages;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn i48_round_trip() {
        let mut buf = [0u8; 8];
        for v in [
            0i64,
            1,
            -1,
            I48_MAX,
            -I48_MAX - 1,
            123_456_789_012,
            -98_765_432_109,
        ] {
            put_i48(v, &mut buf, 1);
            assert_eq!(get_i48(&buf, 1), v);
        }
    }

    #[test]
    fn addr_matching() {
        let a = Addr::FromNode(0x700);
        assert_eq!(a.matches(0x700), None);
        assert_eq!(a.matches(0x702), Some(2));
        assert_eq!(a.matches(0x70F), Some(15));
        assert_eq!(a.matches(0x710), None);
        assert_eq!(Addr::ToNode(0x30).matches(0x30), Some(0));
        assert_eq!(Addr::Broadcast(0x20).matches(0x21), None);
    }
}
