//! The independent watchdog (IWDG, on its own LSI clock), fed by the core's
//! feed policy (`triquint_firmware::watchdog`): the control tick checks in
//! from its interrupt, the CAN side from this task, which runs on the same
//! executor as the CAN receive and transmit tasks, so a stuck receive task
//! (or a stuck executor) stops it too. The timeout is above the longest
//! flash-erase stall of the configuration store (storage.rs).

use core::cell::Cell;

use critical_section::Mutex;
use embassy_stm32::Peri;
use embassy_stm32::peripherals::IWDG;
use embassy_stm32::wdg::IndependentWatchdog;
use embassy_time::Timer;
use triquint_firmware::watchdog::{FEED_PERIOD_US, FeedPolicy, TIMEOUT_US};

static POLICY: Mutex<Cell<FeedPolicy>> = Mutex::new(Cell::new(FeedPolicy::new()));

/// Called by the control tick.
pub fn tick_checked_in() {
    critical_section::with(|cs| {
        let cell = POLICY.borrow(cs);
        let mut p = cell.get();
        p.tick_checked_in();
        cell.set(p);
    });
}

#[embassy_executor::task]
pub async fn feed(iwdg: Peri<'static, IWDG>) {
    let mut wd = IndependentWatchdog::new(iwdg, TIMEOUT_US);
    wd.unleash();
    loop {
        Timer::after_micros(u64::from(FEED_PERIOD_US)).await;
        let feed = critical_section::with(|cs| {
            let cell = POLICY.borrow(cs);
            let mut p = cell.get();
            p.can_checked_in();
            let feed = p.take_feed();
            cell.set(p);
            feed
        });
        if feed {
            wd.pet();
        }
    }
}
