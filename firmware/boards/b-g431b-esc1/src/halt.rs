//! What the board does when its code cannot go on (a panic, a HardFault,
//! an interrupt or exception nothing handles):
//! the power stage off first, then nothing, until the independent watchdog
//! resets the board (`watchdog.rs`). A halt that only looped would leave
//! the current loop's interrupt running the motor on its last command.
//! Neither returns, so neither is a level of `scripts/stack_check.py`'s
//! bound: what they stack, even past the stack's end, is never read again.

use core::panic::PanicInfo;

use cortex_m_rt::{ExceptionFrame, exception};
use embassy_stm32::pac;

/// TIM1's main output enable off: every gate driver output to its idle
/// (off) level at once, whatever the timer and the current loop do next.
fn power_stage_off() {
    pac::TIM1.bdtr().modify(|w| w.set_moe(false));
}

#[panic_handler]
fn panic(_: &PanicInfo) -> ! {
    cortex_m::interrupt::disable();
    power_stage_off();
    loop {
        cortex_m::asm::nop();
    }
}

#[exception]
unsafe fn HardFault(_: &ExceptionFrame) -> ! {
    power_stage_off();
    loop {
        cortex_m::asm::nop();
    }
}

#[exception]
unsafe fn DefaultHandler(_irqn: i16) -> ! {
    power_stage_off();
    loop {
        cortex_m::asm::nop();
    }
}
