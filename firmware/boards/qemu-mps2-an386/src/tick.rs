//! The control tick as the boards run it, behind un-mangled, never-inlined
//! entry points: the ELF check (scripts/elf_check.py) walks the call graph
//! from these symbols and rejects f64 soft-float and panic paths.

use triquint_firmware::{Encoder, MotorOutput, Node, RxFrame};

/// Encoder of the test image: the recorded count.
pub struct Counts(pub i64);
impl Encoder for Counts {
    fn read_counts(&mut self) -> i64 {
        self.0
    }
}

/// Motor of the test image: the last command.
#[derive(Default)]
pub struct Motor {
    pub torque: f32,
    pub enabled: bool,
}
impl MotorOutput for Motor {
    fn set_torque(&mut self, t: f32) {
        self.torque = t;
    }
    fn enable(&mut self, on: bool) {
        self.enabled = on;
    }
}

/// One control tick.
#[unsafe(no_mangle)]
#[inline(never)]
pub extern "Rust" fn triquint_control_tick(
    node: &mut Node,
    now_us: u64,
    enc: &mut Counts,
    motor: &mut Motor,
) {
    node.tick(now_us, enc, motor);
    #[cfg(feature = "bad-tick")]
    bad(node, motor);
}

/// One received frame handed from the CAN task to the node.
#[unsafe(no_mangle)]
#[inline(never)]
pub extern "Rust" fn triquint_can_rx(node: &mut Node, rx: &RxFrame) {
    node.on_frame(rx);
}

/// What the check must catch: an f64 operation and a reachable panic.
#[cfg(feature = "bad-tick")]
#[inline(never)]
fn bad(node: &mut Node, motor: &mut Motor) {
    let t = core::hint::black_box(motor.torque as f64);
    motor.torque = (t * 1.000_000_1) as f32;
    let i = core::hint::black_box(node.queue_depth());
    let table = core::hint::black_box([0u8; 4]);
    motor.enabled = table[i] != 0;
}
