//! The bus the operations run over: interface, frames, the drives' node
//! ids, their control rate and how long one may stay silent.

/// A bus, validated (the commands build it from their options, the tests
/// directly).
#[derive(Clone, Debug, PartialEq)]
pub struct Bus {
    /// SocketCAN interface (can0, vcan0).
    pub iface: String,
    /// CAN-FD: 64-byte segment frames.
    pub fd: bool,
    /// Node ids of the drives of axes 1, 2, 3.
    pub ids: [u8; 3],
    /// Control tick rate the drives are configured for (Hz).
    pub rate: f64,
    /// How long a node may stay silent before an upload fails (s).
    pub timeout_s: f64,
}
