//! Instruction counting on QEMU: with `-icount shift=10` every instruction
//! advances virtual time by 1024 ns, and SysTick on the 25 MHz core clock
//! counts that time. The ratio is calibrated at start on a loop of known
//! length, so the figures do not rest on the clock constants.

use cortex_m::peripheral::SYST;
use cortex_m::peripheral::syst::SystClkSource;

const RELOAD: u32 = 0x00FF_FFFF;

pub struct Counter {
    syst: SYST,
    /// SysTick counts per 1024 instructions (calibrated).
    per_k: u32,
    /// Counts of an empty measurement.
    overhead: u32,
}

impl Counter {
    pub fn new(mut syst: SYST) -> Self {
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_counter();
        let mut c = Self {
            syst,
            per_k: 1,
            overhead: 0,
        };
        c.overhead = c.raw(|| ());
        // 4096 more iterations of `subs; bne` = 8192 more instructions.
        let n = c.raw(|| spin(8192)).saturating_sub(c.raw(|| spin(4096)));
        c.per_k = (n / 8).max(1);
        c
    }

    #[inline(always)]
    fn now(&self) -> u32 {
        SYST::get_current()
    }

    #[inline(always)]
    fn raw<R>(&self, f: impl FnOnce() -> R) -> u32 {
        let a = self.now();
        let r = f();
        let b = self.now();
        core::hint::black_box(r);
        a.wrapping_sub(b) & RELOAD
    }

    /// Instructions `f` executes (measurement overhead removed).
    #[inline(always)]
    pub fn instructions<R>(&self, f: impl FnOnce() -> R) -> (R, u32) {
        let a = self.now();
        let r = f();
        let b = self.now();
        let n = (a.wrapping_sub(b) & RELOAD).saturating_sub(self.overhead);
        (r, (n as u64 * 1024 / self.per_k as u64) as u32)
    }

    /// SysTick counts per 1024 instructions: 25 600 under `-icount shift=10`
    /// on a 25 MHz core clock; anything else means the figures are not instructions.
    pub fn per_k(&self) -> u32 {
        self.per_k
    }

    pub fn release(self) -> SYST {
        self.syst
    }
}

#[inline(never)]
fn spin(n: u32) {
    // SAFETY: a register-only countdown loop.
    unsafe {
        core::arch::asm!(
            "1:",
            "subs {0}, {0}, #1",
            "bne 1b",
            inout(reg) n => _,
            options(nomem, nostack)
        );
    }
}
