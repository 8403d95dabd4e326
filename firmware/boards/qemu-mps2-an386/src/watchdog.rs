//! The CMSDK APB watchdog of mps2-an386, fed by the core's feed policy
//! (`triquint_firmware::watchdog`): the golden replay checks the tick and
//! the CAN side in as it runs them, so the watchdog never fires; the
//! `watchdog-test` image stops the tick and expects the watchdog's first
//! expiry, which raises NMI on this machine (the second would reset).

use core::cell::Cell;
use core::sync::atomic::{AtomicBool, Ordering};

use cortex_m::interrupt::Mutex;
use cortex_m_rt::exception;
use cortex_m_semihosting::{debug, hprintln};
use triquint_firmware::watchdog::{FeedPolicy, TIMEOUT_US};

const BASE: usize = 0x4000_8000;
const LOAD: usize = BASE;
const CONTROL: usize = BASE + 0x08;
const INTCLR: usize = BASE + 0x0C;
const LOCK: usize = BASE + 0xC00;
const UNLOCK: u32 = 0x1ACC_E551;
/// INTEN | RESEN.
const ENABLE: u32 = 0b11;
/// WDOGCLK, Hz.
const WDOGCLK_HZ: u64 = 25_000_000;
/// Counts to the first expiry.
pub const LOAD_COUNTS: u32 = (WDOGCLK_HZ * TIMEOUT_US as u64 / 1_000_000) as u32;

/// Set by the `watchdog-test` image when it stops the tick: an NMI before
/// that is a failure.
pub static TICK_STOPPED: AtomicBool = AtomicBool::new(false);

static POLICY: Mutex<Cell<FeedPolicy>> = Mutex::new(Cell::new(FeedPolicy::new()));
static STARTED: Mutex<Cell<bool>> = Mutex::new(Cell::new(false));

fn write(addr: usize, v: u32) {
    // SAFETY: a register of the CMSDK watchdog on this machine's memory map.
    unsafe { core::ptr::write_volatile(addr as *mut u32, v) }
}

/// Loads the timeout and enables the interrupt and the reset.
pub fn start() {
    write(LOCK, UNLOCK);
    write(LOAD, LOAD_COUNTS);
    write(CONTROL, ENABLE);
    write(LOCK, 0);
    cortex_m::interrupt::free(|cs| STARTED.borrow(cs).set(true));
}

pub fn started() -> bool {
    cortex_m::interrupt::free(|cs| STARTED.borrow(cs).get())
}

fn with(f: impl FnOnce(&mut FeedPolicy) -> bool) -> bool {
    cortex_m::interrupt::free(|cs| {
        let cell = POLICY.borrow(cs);
        let mut p = cell.get();
        let r = f(&mut p);
        cell.set(p);
        r
    })
}

pub fn tick_checked_in() {
    with(|p| {
        p.tick_checked_in();
        false
    });
}

pub fn can_checked_in() {
    with(|p| {
        p.can_checked_in();
        false
    });
}

/// Feeds (clears and reloads the counter) when the policy says so.
pub fn offer_feed() {
    if with(|p| p.take_feed()) {
        write(LOCK, UNLOCK);
        write(INTCLR, 1);
        write(LOCK, 0);
    }
}

pub fn feeds() -> u32 {
    cortex_m::interrupt::free(|cs| POLICY.borrow(cs).get().feeds())
}

// SAFETY: the handler touches only semihosting and the atomics above; it
// never returns into the interrupted code.
#[exception]
unsafe fn NonMaskableInt() {
    if cfg!(feature = "watchdog-test") && TICK_STOPPED.load(Ordering::SeqCst) {
        hprintln!(
            "watchdog: NMI after the tick stopped (fed {} times before)",
            feeds()
        );
        hprintln!("PASS");
        debug::exit(debug::EXIT_SUCCESS);
    } else {
        hprintln!("FAIL: the watchdog fired (fed {} times)", feeds());
        debug::exit(debug::EXIT_FAILURE);
    }
    loop {
        cortex_m::asm::bkpt();
    }
}

/// The `watchdog-test` image: healthy rounds (tick and CAN side check in)
/// for twice the timeout, which must not fire, then the tick stops while
/// the CAN side keeps checking in: the NMI must come (it exits); running
/// on for four timeouts without it is a failure.
#[cfg(feature = "watchdog-test")]
#[cortex_m_rt::entry]
fn main() -> ! {
    // Instructions per round here are a few dozen; under -icount shift=10
    // one instruction is 1024 ns.
    const HEALTHY_ROUNDS: u32 = 20_000;
    const STOPPED_ROUNDS: u32 = 200_000;
    start();
    for _ in 0..HEALTHY_ROUNDS {
        tick_checked_in();
        can_checked_in();
        offer_feed();
    }
    hprintln!(
        "watchdog: {} feeds while healthy, no NMI; the tick stops",
        feeds()
    );
    TICK_STOPPED.store(true, Ordering::SeqCst);
    for _ in 0..STOPPED_ROUNDS {
        can_checked_in();
        offer_feed();
    }
    hprintln!(
        "FAIL: no NMI after the tick stopped (timeout {} µs)",
        TIMEOUT_US
    );
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::bkpt();
    }
}
