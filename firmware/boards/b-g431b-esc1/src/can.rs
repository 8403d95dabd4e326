//! CAN-FD on FDCAN1 (PA11 RX, PB9 TX on the ESC1): the receive task timestamps
//! frames and hands them to the control tick; the transmit task sends what
//! the node queued (heartbeats, acknowledgements, telemetry, emergencies).

use embassy_stm32::can::frame::{FdFrame, Header};
use embassy_stm32::can::{self, CanRx, CanTx};
use embassy_sync::blocking_mutex::raw::CriticalSectionRawMutex;
use embassy_sync::signal::Signal;
use heapless::spsc::{Consumer, Producer};
use triquint_firmware::RxFrame;
use triquint_shared::protocol::Frame;

/// Raised by the tick when it queued frames.
pub static TX_READY: Signal<CriticalSectionRawMutex, ()> = Signal::new();

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
pub async fn receive(mut rx: CanRx<'static>, mut to_tick: Producer<'static, RxFrame>) {
    loop {
        match rx.read_fd().await {
            Ok(env) => {
                if let Some(frame) = to_core(&env.frame) {
                    let rx = RxFrame {
                        frame,
                        timestamp_us: env.ts.as_micros(),
                    };
                    // A full queue drops the frame: the host's flow control resends.
                    let _ = to_tick.enqueue(rx);
                }
            }
            Err(_bus_error) => {}
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
