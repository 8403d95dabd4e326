//! Homing: the first rising edge on the index / limit-switch input (PB8, J8
//! "Z") sets the axis zero. Until then the power stage stays off, so an
//! un-homed axis never moves; the node's arm check (start pose within the arm
//! tolerance) then guards the first motion.

use core::sync::atomic::Ordering;

use embassy_stm32::exti::ExtiInput;
use embassy_stm32::mode::Async;

use crate::encoder::{HOME_RAW, HOMED, RAW};

#[embassy_executor::task]
pub async fn home(mut input: ExtiInput<'static, Async>) {
    input.wait_for_rising_edge().await;
    HOME_RAW.store(RAW.load(Ordering::Relaxed), Ordering::Relaxed);
    HOMED.store(true, Ordering::Release);
}
