//! The control tick and the CAN receive side as the boards run them, behind
//! un-mangled, never-inlined entry points: the ELF check
//! (scripts/elf_check.py) walks the call graph from these symbols and
//! rejects f64 soft-float and panic paths.

use triquint_firmware::inbox::Inbox;
use triquint_firmware::{Drive, Encoder, Item, MotorOutput, Receiver, RxFrame, TickSnapshot};

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

/// One control tick: the hand-off (items the receive side finished, from
/// the lock-free queue) and the tick itself.
#[unsafe(no_mangle)]
#[inline(never)]
pub extern "Rust" fn triquint_control_tick(
    drive: &mut Drive,
    inbox: &mut Inbox,
    now_us: u64,
    enc: &mut Counts,
    motor: &mut Motor,
) {
    drive.take_from(inbox);
    drive.tick(now_us, enc, motor);
    #[cfg(feature = "bad-tick")]
    bad(drive, motor);
}

/// One received frame in the CAN receive context: decode, reassembly,
/// validation; the finished item goes into the queue to the tick.
#[unsafe(no_mangle)]
#[inline(never)]
pub extern "Rust" fn triquint_can_rx(
    receiver: &mut Receiver,
    rx: &RxFrame,
    snapshot: TickSnapshot,
) -> Option<Item> {
    receiver.on_frame(rx, snapshot)
}

/// What the check must catch: an f64 operation and a reachable panic.
#[cfg(feature = "bad-tick")]
#[inline(never)]
fn bad(node: &mut Drive, motor: &mut Motor) {
    let t = core::hint::black_box(motor.torque as f64);
    motor.torque = (t * 1.000_000_1) as f32;
    let i = core::hint::black_box(node.queue_depth());
    let table = core::hint::black_box([0u8; 4]);
    motor.enabled = table[i] != 0;
}
