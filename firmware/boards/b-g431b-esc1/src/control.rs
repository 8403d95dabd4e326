//! The 10 kHz control tick: TIM6's update interrupt, above the CAN tasks and
//! below the current loop. It owns the node: frames the CAN task handed over
//! come in through a lock-free queue, are fed to the node, then the node's
//! tick runs and its frames go out through the other queue.

use core::cell::RefCell;
use core::sync::atomic::{AtomicPtr, AtomicU32, Ordering};

use critical_section::Mutex;
use embassy_stm32::interrupt;
use embassy_stm32::pac;
use heapless::spsc::{Consumer, Producer};
use triquint_firmware::{Node, RxFrame};
use triquint_shared::protocol::{Frame, PARAM_COUNT};

use crate::encoder::QuadratureEncoder;
use crate::motor::TorqueToCurrent;

/// Everything the tick owns.
pub struct Tick {
    pub node: Node,
    pub encoder: QuadratureEncoder,
    pub motor: TorqueToCurrent,
    pub rx: Consumer<'static, RxFrame>,
    /// The kept configuration, replayed after homing.
    pub restore: Consumer<'static, RxFrame>,
    pub tx: Producer<'static, Frame>,
}

/// Handed to the interrupt once, at start-up (a `StaticCell`, never moved);
/// from then on only the interrupt touches it.
pub static TICK: AtomicPtr<Tick> = AtomicPtr::new(core::ptr::null_mut());
/// A committed configuration to keep in flash: values and CRC.
pub type Kept = ([f32; PARAM_COUNT], u32);
/// Committed configuration the storage task should keep in flash.
pub static TO_STORE: Mutex<RefCell<Option<Kept>>> = Mutex::new(RefCell::new(None));
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
    // Hand-off from the CAN and flash tasks. Until the axis is homed the node
    // stays unconfigured (motor off, heartbeat without a configuration).
    let homed = crate::encoder::HOMED.load(Ordering::Acquire);
    while let Some(rx) = t.restore.dequeue() {
        t.node.on_frame(&rx);
    }
    while let Some(rx) = t.rx.dequeue() {
        if homed {
            t.node.on_frame(&rx);
        }
    }
    t.node.tick(now_us(), &mut t.encoder, &mut t.motor);
    while let Some(f) = t.node.peek_tx() {
        if t.tx.enqueue(f).is_err() {
            break;
        }
        t.node.pop_tx();
    }
    crate::can::TX_READY.signal(());
    let crc = t.node.config_crc();
    if crc != *LAST_CRC {
        *LAST_CRC = crc;
        if let Some(cfg) = t.node.config() {
            let v = cfg.to_values();
            critical_section::with(|cs| TO_STORE.borrow(cs).replace(Some((v, crc))));
        }
    }
    TICKS.fetch_add(1, Ordering::Relaxed);
}
