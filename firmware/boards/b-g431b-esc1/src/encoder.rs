//! `Encoder` on TIM4's quadrature mode (PB6 = A, PB7 = B on the J8 connector):
//! the 16-bit hardware count extended to 64 bits in software (read at 10 kHz,
//! far more often than 32 768 counts can pass). The axis zero is the core's
//! (homing).

use core::sync::atomic::{AtomicI32, Ordering};

use embassy_stm32::peripherals::TIM4;
use embassy_stm32::timer::qei::Qei;
use triquint_firmware::Encoder;

/// Latest extended count (low 32 bits), for the switch latch.
pub static RAW: AtomicI32 = AtomicI32::new(0);
/// Latest extended count (high 32 bits).
static RAW_HIGH: AtomicI32 = AtomicI32::new(0);

/// A latched low 32-bit count extended with the latest high half (the
/// latch is at most a tick old, so the high half has not moved by more
/// than one wrap, which the signed difference resolves).
pub fn extend(low: i32) -> i64 {
    let now = (i64::from(RAW_HIGH.load(Ordering::Relaxed)) << 32)
        | i64::from(RAW.load(Ordering::Relaxed) as u32);
    now + i64::from(low.wrapping_sub(now as i32))
}

pub struct QuadratureEncoder {
    qei: Qei<'static, TIM4>,
    last: u16,
    total: i64,
}

impl QuadratureEncoder {
    pub fn new(qei: Qei<'static, TIM4>) -> Self {
        let last = qei.count();
        Self {
            qei,
            last,
            total: 0,
        }
    }
}

impl Encoder for QuadratureEncoder {
    fn read_counts(&mut self) -> i64 {
        let now = self.qei.count();
        self.total += now.wrapping_sub(self.last) as i16 as i64;
        self.last = now;
        RAW.store(self.total as i32, Ordering::Relaxed);
        RAW_HIGH.store((self.total >> 32) as i32, Ordering::Relaxed);
        self.total
    }
}
