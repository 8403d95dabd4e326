//! Copies the code linked into `.ccmram_text` (the control tick) from flash
//! to CCM SRAM before RAM is initialised: at 170 MHz flash has 4 wait states,
//! CCM none. In assembly: no Rust may run before `.data`/`.bss` exist.

core::arch::global_asm!(
    ".section .text.__pre_init,\"ax\"",
    ".global __pre_init",
    ".type __pre_init,%function",
    ".thumb_func",
    "__pre_init:",
    "    ldr r0, =__sccm_text",
    "    ldr r1, =__eccm_text",
    "    ldr r2, =__siccm_text",
    "1:  cmp r0, r1",
    "    bhs 2f",
    "    ldr r3, [r2], #4",
    "    str r3, [r0], #4",
    "    b 1b",
    "2:  bx lr",
);
