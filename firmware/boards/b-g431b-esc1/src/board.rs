//! Constants of the board and the motor that the CAN configuration does not
//! carry (the protocol's DriveConfig has the node id, gains, direction, Kt,
//! encoder scale, limits and soft limits; not the current sensing or the
//! motor's poles).

use triquint_shared::machine::boards;

/// Node id when flash holds none (1–15); `TRIQUINT_NODE_ID=2 cargo run --release`
/// programs another, which is then kept in flash. A committed configuration
/// with another `node_id` renumbers the board from its next start. Anything
/// but 1–15 is node 1.
pub const DEFAULT_NODE_ID: u8 = match option_env!("TRIQUINT_NODE_ID") {
    Some(s) => match s.as_bytes() {
        [d @ b'1'..=b'9'] => *d - b'0',
        [b'1', d @ b'0'..=b'5'] => 10 + (*d - b'0'),
        _ => 1,
    },
    None => 1,
};
/// |Iq| limit (A); the ESC1 is rated 40 A peak.
pub const MAX_CURRENT: f32 = boards::B_G431B_ESC1_MAX_CURRENT;
/// Motor pole pairs.
pub const POLE_PAIRS: f32 = 7.0;
/// Encoder counts per motor revolution (quadrature edges); the machine
/// file's `counts_per_rev` must say the same.
pub const COUNTS_PER_REV: f32 = boards::B_G431B_ESC1_COUNTS_PER_REV as f32;
/// Phase current per ADC count: 3 mΩ shunt, op-amp gain 9.14, 12 bit on 3.3 V.
pub const AMPS_PER_COUNT: f32 = 3.3 / 4096.0 / (0.003 * 9.14);
/// ADC count at zero current (1.65 V bias).
pub const ZERO_CURRENT: f32 = 2048.0;
/// Current-loop PI (V/V per A) at 20 kHz.
pub const CURRENT_KP: f32 = 0.02;
pub const CURRENT_KI_DT: f32 = 0.002;
/// Rotor alignment before the first enable: d-current (A) and duration (PWM periods).
pub const ALIGN_CURRENT: f32 = 3.0;
pub const ALIGN_PERIODS: u32 = 10_000;
/// Control tick and PWM rates (Hz).
pub const TICK_HZ: u32 = 10_000;
pub const PWM_HZ: u32 = 20_000;
/// CAN bit rates (bit/s): arbitration and CAN-FD data phase.
pub const CAN_BITRATE: u32 = 1_000_000;
pub const CAN_FD_BITRATE: u32 = 5_000_000;
