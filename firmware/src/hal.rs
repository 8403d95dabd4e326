//! The hardware the core needs, as traits. The simulator (`triquint-sim`)
//! implements them in memory; a board crate implements them on its timer,
//! encoder interface, PWM/current loop and CAN controller.

use triquint_shared::protocol::Frame;

/// Position feedback: a signed counter (counts; scale and sign in the configuration).
pub trait Encoder {
    fn read_counts(&mut self) -> i64;
}

/// The torque (current) loop of the motor.
pub trait MotorOutput {
    /// Motor torque command (N·m), already clamped by the caller.
    fn set_torque(&mut self, torque_nm: f32);
    /// Power stage on (brake released) or off (brake applied).
    fn enable(&mut self, on: bool);
}

/// A received frame with the local receive timestamp (µs).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RxFrame {
    pub frame: Frame,
    pub timestamp_us: u64,
}

/// The CAN controller.
pub trait CanPort {
    /// Queues a frame for transmission; `false` when the mailboxes are full
    /// (the core keeps it and tries again).
    fn transmit(&mut self, frame: &Frame) -> bool;
    /// The next received frame, if any.
    fn receive(&mut self) -> Option<RxFrame>;
    /// (transmit, receive) error counters of the controller.
    fn error_counters(&self) -> (u8, u8) {
        (0, 0)
    }
}
