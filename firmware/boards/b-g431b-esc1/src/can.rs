//! CAN-FD on FDCAN1 (PA11 RX, PB9 TX on the ESC1): the receive task timestamps
//! frames and runs the node's receive side on them (decoding, segment
//! reassembly and checks, configuration set-up) below the control tick,
//! handing finished items to the tick; the transmit task sends what the node
//! queued (heartbeats, acknowledgements, telemetry, emergencies).

use embassy_futures::select::{Either, select};
use embassy_stm32::can::frame::{FdFrame, Header};
use embassy_stm32::can::{self, CanRx, CanTx};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::channel::Channel;
use heapless::spsc::{Consumer, Producer};
use triquint_firmware::inbox::offer;
use triquint_firmware::{Item, Receiver, RxFrame};
use triquint_shared::protocol::Frame;

use crate::control::{SNAPSHOT, TX_READY};

/// Frames replayed from flash (the kept configuration), received like bus frames.
pub static RESTORE: Channel<CriticalSectionRawMutex, RxFrame, 4> = Channel::new();

fn to_core(f: &FdFrame) -> Option<Frame> {
    let id = match f.id() {
        embedded_can::Id::Standard(s) => s.as_raw(),
        embedded_can::Id::Extended(_) => return None,
    };
    Some(Frame::with_payload(id, f.data(), f.header().fdcan()))
}

fn to_fdcan(f: &Frame) -> Option<FdFrame> {
    let id = embedded_can::StandardId::new(f.id)?;
    let header = if f.fd {
        Header::new_fd(id.into(), f.len, false, true)
    } else {
        Header::new(id.into(), f.len, false)
    };
    FdFrame::new(header, f.payload()).ok()
}

#[embassy_executor::task]
pub async fn receive(
    mut rx: CanRx<'static>,
    mut receiver: Receiver,
    mut to_tick: Producer<'static, Item>,
) {
    loop {
        let frame = match select(rx.read_fd(), RESTORE.receive()).await {
            Either::First(Ok(env)) => to_core(&env.frame).map(|frame| RxFrame {
                frame,
                timestamp_us: env.ts.as_micros(),
            }),
            // Counted by the controller (TEC/REC), which the tick reports.
            Either::First(Err(_bus_error)) => None,
            Either::Second(kept) => Some(kept),
        };
        // Every frame, homed or not: the core refuses motion until homed.
        let Some(frame) = frame else {
            continue;
        };
        let snapshot = critical_section::with(|cs| SNAPSHOT.borrow(cs).get());
        if let Some(item) = receiver.on_frame(&frame, snapshot) {
            hand_off(&mut to_tick, item).await;
        }
    }
}

/// Queues an item for the tick. An ordinary item finding only the reserved
/// slots left is dropped (the host's flow control resends segments); an
/// urgent one (Stop, QuickStop, ClearFault, Emergency) is never dropped: it
/// waits for the tick, which frees a slot every 100 µs.
async fn hand_off(to_tick: &mut Producer<'static, Item>, mut item: Item) {
    loop {
        match offer(to_tick, item) {
            Ok(()) => return,
            Err(back) if back.is_urgent() => {
                item = back;
                embassy_futures::yield_now().await;
            }
            Err(_) => return,
        }
    }
}

#[embassy_executor::task]
pub async fn transmit(mut tx: CanTx<'static>, mut from_tick: Consumer<'static, Frame>) {
    loop {
        TX_READY.wait().await;
        while let Some(f) = from_tick.dequeue() {
            if let Some(fd) = to_fdcan(&f) {
                tx.write_fd(&fd).await;
            }
        }
    }
}

/// Bit rates and CAN-FD with bit-rate switch.
pub fn configure(c: &mut can::CanConfigurator<'static>) {
    c.set_bitrate(crate::board::CAN_BITRATE);
    c.set_fd_data_bitrate(crate::board::CAN_FD_BITRATE, true);
}
