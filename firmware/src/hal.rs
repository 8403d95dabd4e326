//! The hardware the core needs, as traits. The simulator (`triquint-sim`)
//! implements them in memory; a board crate implements them on its timer,
//! encoder interface, PWM/current loop and CAN controller.

use triquint_shared::protocol::Frame;

/// Position feedback: a signed counter (counts; scale and sign in the configuration).
pub trait Encoder {
    fn read_counts(&mut self) -> i64;
}

/// The axis's limit (home) switch on a capture input: the encoder count at
/// the switch's edge is latched by hardware, so homing does not depend on
/// when the tick looks.
pub trait LimitSwitch {
    /// Is the switch active now?
    fn active(&mut self) -> bool;
    /// The encoder count latched at the latest inactive → active edge, once
    /// (`None` until the next edge).
    fn take_edge(&mut self) -> Option<i64>;
}

/// No switch wired: never active, no edge (homing ends in
/// `HomeSwitchNeverTriggered`).
#[derive(Clone, Copy, Debug, Default)]
pub struct NoSwitch;

impl LimitSwitch for NoSwitch {
    fn active(&mut self) -> bool {
        false
    }
    fn take_edge(&mut self) -> Option<i64> {
        None
    }
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
pub trait CanBus {
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
