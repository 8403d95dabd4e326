//! `MotorOutput` of the board: the position loop's torque becomes the q-axis
//! current reference Iq = τ/Kt for the current loop, handed over through
//! atomics (the current loop interrupts the control tick).

use core::sync::atomic::{AtomicBool, AtomicU32, Ordering};

use triquint_firmware::MotorOutput;

/// Iq reference (A), f32 bits.
pub static IQ_REF: AtomicU32 = AtomicU32::new(0);
/// Power stage requested on by the node.
pub static ENABLE: AtomicBool = AtomicBool::new(false);

/// Torque → current with the motor's torque constant and current limit.
pub struct TorqueToCurrent {
    /// Kt (N·m/A).
    pub kt: f32,
    /// |Iq| limit (A).
    pub max_current: f32,
}

impl MotorOutput for TorqueToCurrent {
    fn set_torque(&mut self, torque_nm: f32) {
        let iq = (torque_nm / self.kt)
            .max(-self.max_current)
            .min(self.max_current);
        IQ_REF.store(iq.to_bits(), Ordering::Relaxed);
    }

    fn enable(&mut self, on: bool) {
        if !on {
            IQ_REF.store(0, Ordering::Relaxed);
        }
        ENABLE.store(on, Ordering::Relaxed);
    }
}

pub fn iq_ref() -> f32 {
    f32::from_bits(IQ_REF.load(Ordering::Relaxed))
}
