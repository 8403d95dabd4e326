//! `Encoder` on TIM4's quadrature mode (PB6 = A, PB7 = B on the J8 connector):
//! the 16-bit hardware count extended to 64 bits in software (read at 10 kHz,
//! far more often than 32 768 counts can pass), minus the homing zero.

use core::sync::atomic::{AtomicBool, AtomicI32, Ordering};

use embassy_stm32::peripherals::TIM4;
use embassy_stm32::timer::qei::Qei;
use triquint_firmware::Encoder;

/// Raw count latched by the homing input (low 32 bits of the extended count).
pub static HOME_RAW: AtomicI32 = AtomicI32::new(0);
pub static HOMED: AtomicBool = AtomicBool::new(false);
/// Latest extended raw count, for the homing task and the electrical angle.
pub static RAW: AtomicI32 = AtomicI32::new(0);

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
        self.total - HOME_RAW.load(Ordering::Relaxed) as i64
    }
}
