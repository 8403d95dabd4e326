//! The limit switch (PB8, J8 "Z": index or limit-switch input) as the
//! core's `LimitSwitch`: every rising edge latches the encoder count of that
//! moment; the level is kept for the drive's "switch active" check. Homing
//! itself (on the host's Home command, all axes together) runs in the core,
//! as in the simulator; the power stage and the CAN side do not wait for it.

use core::sync::atomic::{AtomicBool, AtomicI32, Ordering};

use embassy_stm32::exti::ExtiInput;
use embassy_stm32::mode::Async;
use triquint_firmware::LimitSwitch;

use crate::encoder::RAW;

/// Count latched at the latest rising edge (low 32 bits of the extended count).
static EDGE_RAW: AtomicI32 = AtomicI32::new(0);
/// A rising edge not yet taken by the tick.
static EDGE: AtomicBool = AtomicBool::new(false);
/// The input's level.
static ACTIVE: AtomicBool = AtomicBool::new(false);

#[embassy_executor::task]
pub async fn watch(mut input: ExtiInput<'static, Async>) {
    ACTIVE.store(input.is_high(), Ordering::Release);
    loop {
        input.wait_for_any_edge().await;
        let high = input.is_high();
        if high && !ACTIVE.load(Ordering::Acquire) {
            // The count of the latest tick: at most one tick (100 µs) old,
            // 2.5 µm at the default homing speed.
            EDGE_RAW.store(RAW.load(Ordering::Relaxed), Ordering::Relaxed);
            EDGE.store(true, Ordering::Release);
        }
        ACTIVE.store(high, Ordering::Release);
    }
}

/// The tick's view of the switch.
pub struct Switch;

impl LimitSwitch for Switch {
    fn active(&mut self) -> bool {
        ACTIVE.load(Ordering::Acquire)
    }
    fn take_edge(&mut self) -> Option<i64> {
        EDGE.swap(false, Ordering::AcqRel)
            .then(|| crate::encoder::extend(EDGE_RAW.load(Ordering::Relaxed)))
    }
}
