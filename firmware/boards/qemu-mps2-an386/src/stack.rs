//! The stack's deepest use, measured: the RAM below the stack pointer is
//! painted before the replay and read after it, against the stack pointer
//! at the calls into the two entry points. `scripts/qemu-test.sh` holds it
//! to the static bound `scripts/stack_check.py` gives for them, a check of
//! that bound on real execution.

/// What no frame writes by chance.
const PAINT: u32 = 0xA5A5_A5A5;
/// Painted below the painter's own frame: far more than any path needs.
const SPAN: usize = 32 * 1024;
/// Left unpainted below the stack pointer: the painter's callees.
const SKIP: usize = 256;

/// The stack pointer here (the caller's frame).
#[inline(always)]
pub fn here() -> usize {
    cortex_m::register::msp::read() as usize
}

/// The painted span, [bottom, top), below a stack pointer `sp` of the
/// caller's frame.
fn span(sp: usize) -> (usize, usize) {
    let top = (sp - SKIP) & !3;
    (top - SPAN, top)
}

/// Paints the span below `sp` (the caller's [`here`]); the calls measured
/// must come from frames at or below it.
#[inline(never)]
pub fn paint(sp: usize) {
    let (bottom, top) = span(sp);
    for a in (bottom..top).step_by(4) {
        // SAFETY: RAM below the live stack (this function's frame is
        // smaller than SKIP), which nothing else uses: no interrupt runs in
        // the replay, and the span stays inside the 4 MB.
        unsafe { (a as *mut u32).write_volatile(PAINT) }
    }
}

/// The lowest address written since [`paint`] with the same `sp`.
#[inline(never)]
pub fn lowest_written(sp: usize) -> usize {
    let (bottom, top) = span(sp);
    (bottom..top)
        .step_by(4)
        // SAFETY: as in `paint`.
        .find(|&a| unsafe { (a as *const u32).read_volatile() } != PAINT)
        .unwrap_or(top)
}
