//! The 10 kHz control tick: TIM6's update interrupt, above the CAN tasks and
//! below the current loop. It owns the node's drive (control side): the CAN
//! receive task decodes, reassembles and validates frames and hands finished
//! items over through a lock-free queue; the tick takes at most two of them,
//! runs, and its frames go out through the other queue.

use core::cell::{Cell, RefCell};
use core::sync::atomic::{AtomicPtr, AtomicU32, Ordering};

use critical_section::Mutex;
use embassy_stm32::interrupt;
use embassy_stm32::pac;
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use heapless::spsc::{Consumer, Producer};
use triquint_firmware::{Drive, Item, TickSnapshot};
use triquint_shared::protocol::{Frame, PARAM_COUNT};

use crate::encoder::QuadratureEncoder;
use crate::homing::Switch;
use crate::motor::TorqueToCurrent;

/// Raised by the tick when it queued frames; the CAN transmit task waits
/// on it. Kept here, with the tick that raises it, so the CAN task uses
/// the tick and not the other way round.
pub static TX_READY: Signal<CriticalSectionRawMutex, ()> = Signal::new();

/// Everything the tick owns.
pub struct Tick {
    pub drive: Drive,
    pub encoder: QuadratureEncoder,
    pub motor: TorqueToCurrent,
    /// Finished items from the CAN receive task.
    pub inbox: Consumer<'static, Item>,
    pub tx: Producer<'static, Frame>,
    /// The FDCAN's error counters, into every HeartbeatExt.
    pub can: embassy_stm32::can::Properties,
}

/// Handed to the interrupt once, at start-up (a `StaticCell`, never moved);
/// from then on only the interrupt touches it.
pub static TICK: AtomicPtr<Tick> = AtomicPtr::new(core::ptr::null_mut());
/// A committed configuration to keep in flash: values and CRC.
pub type Kept = ([f32; PARAM_COUNT], u32);
/// Committed configuration the storage task should keep in flash.
pub static TO_STORE: Mutex<RefCell<Option<Kept>>> = Mutex::new(RefCell::new(None));
/// What the receive side needs to know of the drive, published every tick.
pub static SNAPSHOT: Mutex<Cell<TickSnapshot>> = Mutex::new(Cell::new(TickSnapshot::INITIAL));
/// Ticks run, for the heartbeat LED and debugging.
pub static TICKS: AtomicU32 = AtomicU32::new(0);

pub fn now_us() -> u64 {
    embassy_time::Instant::now().as_micros()
}

#[interrupt]
#[unsafe(link_section = ".ccmram_text")]
fn TIM6_DAC() {
    static mut LAST_CRC: u32 = 0;
    pac::TIM6.sr().modify(|w| w.set_uif(false));
    // SAFETY: set once from a `StaticCell` before this interrupt was enabled;
    // this handler is its only user and does not re-enter itself.
    let Some(t) = (unsafe { TICK.load(Ordering::Acquire).as_mut() }) else {
        return;
    };
    // Hand-off from the CAN receive task.
    t.drive.take_from(&mut t.inbox);
    let errors = (t.can.tx_error_count(), t.can.rx_error_count());
    t.drive.set_error_counters(errors);
    t.drive
        .tick_with_switch(now_us(), &mut t.encoder, &mut t.motor, &mut Switch);
    crate::watchdog::tick_checked_in();
    let snapshot = t.drive.snapshot();
    critical_section::with(|cs| SNAPSHOT.borrow(cs).set(snapshot));
    while let Some(f) = t.drive.peek_tx() {
        if t.tx.enqueue(f).is_err() {
            break;
        }
        t.drive.pop_tx();
    }
    TX_READY.signal(());
    let crc = snapshot.config_crc;
    if crc != *LAST_CRC {
        *LAST_CRC = crc;
        if let Some(cfg) = t.drive.config() {
            // Iq = τ / Kt with the configured torque constant.
            t.motor.kt = cfg.torque_constant;
            let v = cfg.to_values();
            critical_section::with(|cs| TO_STORE.borrow(cs).replace(Some((v, crc))));
        }
    }
    TICKS.fetch_add(1, Ordering::Relaxed);
}
