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
/// The FDCAN kernel clock: PLL Q of `clocks()` in main.rs.
pub const FDCAN_CLOCK_HZ: u32 = 85_000_000;

/// A CAN bit in time quanta of the kernel clock over `prescaler`: the
/// sync quantum, `seg1` before the sample point, `seg2` after it.
pub struct BitTiming {
    pub prescaler: u16,
    pub seg1: u8,
    pub seg2: u8,
    pub sjw: u8,
}

impl BitTiming {
    /// Kernel clock periods a bit.
    pub const fn periods(&self) -> u32 {
        self.prescaler as u32 * (1 + self.seg1 as u32 + self.seg2 as u32)
    }

    /// The bit rate from `clock_hz`, if exact.
    pub const fn bitrate(&self, clock_hz: u32) -> Option<u32> {
        if clock_hz.is_multiple_of(self.periods()) {
            Some(clock_hz / self.periods())
        } else {
            None
        }
    }

    /// Sample point (per mille of the bit).
    pub const fn sample_permille(&self) -> u32 {
        1000 * (1 + self.seg1 as u32) / (1 + self.seg1 as u32 + self.seg2 as u32)
    }
}

/// Arbitration: 85 quanta a bit, sampled at 80 %. Written out because
/// embassy's search for a timing (at most 10 quanta a bit at 1 Mbit/s and
/// above) finds none for 5 Mbit/s from 85 MHz (17 quanta, a prime), and
/// `set_fd_data_bitrate` would panic at start-up. One prescaler for both
/// phases, as transceiver delay compensation wants.
pub const CAN_NOMINAL_TIMING: BitTiming = BitTiming {
    prescaler: 1,
    seg1: 67,
    seg2: 17,
    sjw: 17,
};
/// Data phase: 17 quanta a bit, sampled at 82 %; SJW below seg2.
pub const CAN_DATA_TIMING: BitTiming = BitTiming {
    prescaler: 1,
    seg1: 13,
    seg2: 3,
    sjw: 2,
};
const _: () = {
    let (n, d) = (&CAN_NOMINAL_TIMING, &CAN_DATA_TIMING);
    assert!(matches!(n.bitrate(FDCAN_CLOCK_HZ), Some(CAN_BITRATE)));
    assert!(matches!(d.bitrate(FDCAN_CLOCK_HZ), Some(CAN_FD_BITRATE)));
    // The FDCAN's fields: nominal seg1, seg2, SJW 1–128 (embassy's range),
    // data seg1 1–31, seg2 1–15, SJW below seg2, prescalers 1–31.
    assert!(n.seg1 >= 1 && n.seg1 <= 128 && n.seg2 >= 1 && n.seg2 <= 128);
    assert!(n.sjw >= 1 && n.sjw <= n.seg2);
    assert!(d.seg1 >= 1 && d.seg1 <= 31 && d.seg2 >= 1 && d.seg2 <= 15);
    assert!(d.sjw >= 1 && d.sjw < d.seg2);
    assert!(n.prescaler == d.prescaler && d.prescaler >= 1 && d.prescaler <= 31);
    assert!(n.sample_permille() >= 750 && n.sample_permille() <= 875);
    assert!(d.sample_permille() >= 700 && d.sample_permille() <= 875);
};
