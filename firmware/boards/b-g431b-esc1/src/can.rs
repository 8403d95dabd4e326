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
use triquint_firmware::handoff::{HandOff, RxFifo};
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
    let mut handoff = HandOff::new();
    loop {
        let (frame, kept) = match select(rx.read_fd(), RESTORE.receive()).await {
            Either::First(Ok(env)) => (
                to_core(&env.frame).map(|frame| RxFrame {
                    frame,
                    timestamp_us: env.ts.as_micros(),
                }),
                false,
            ),
            // Counted by the controller (TEC/REC), which the tick reports.
            Either::First(Err(_bus_error)) => (None, false),
            Either::Second(kept) => (Some(kept), true),
        };
        // Every frame, homed or not: the core refuses motion until homed.
        let Some(frame) = frame else {
            continue;
        };
        let snapshot = critical_section::with(|cs| SNAPSHOT.borrow(cs).get());
        // The kept configuration is the board's own: not held to the
        // ceiling lock as a host's commit is.
        let item = if kept {
            receiver.on_kept_frame(&frame, snapshot)
        } else {
            receiver.on_frame(&frame, snapshot)
        };
        if let Some(item) = item {
            hand_off(&mut handoff, &mut to_tick, &mut rx, &mut receiver, item).await;
        }
    }
}

/// The controller's receive FIFO read without waiting (the read is
/// cancel-safe: a pending poll registers the waker and takes nothing).
struct Fifo<'a>(&'a mut CanRx<'static>);

impl RxFifo for Fifo<'_> {
    fn try_take(&mut self) -> Option<RxFrame> {
        loop {
            match embassy_futures::poll_once(self.0.read_fd()) {
                core::task::Poll::Ready(Ok(env)) => {
                    if let Some(frame) = to_core(&env.frame) {
                        return Some(RxFrame {
                            frame,
                            timestamp_us: env.ts.as_micros(),
                        });
                    }
                }
                core::task::Poll::Ready(Err(_bus_error)) => {}
                core::task::Poll::Pending => return None,
            }
        }
    }
}

/// Queues an item for the tick through the core's [`HandOff`]: an urgent
/// item finding the inbox full waits for the tick, which frees a slot
/// every 100 µs, and the receive FIFO is drained meanwhile so no later
/// Stop or Emergency is lost in the controller.
async fn hand_off(
    handoff: &mut HandOff,
    to_tick: &mut Producer<'static, Item>,
    rx: &mut CanRx<'static>,
    receiver: &mut Receiver,
    item: Item,
) {
    handoff.accept(to_tick, item);
    while handoff.waiting() {
        embassy_futures::yield_now().await;
        handoff.service(to_tick, &mut Fifo(rx), |f| {
            let snapshot = critical_section::with(|cs| SNAPSHOT.borrow(cs).get());
            receiver.on_frame(f, snapshot)
        });
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

/// Bit rates and CAN-FD with bit-rate switch, from the board's timings
/// (`board::CAN_NOMINAL_TIMING`, `board::CAN_DATA_TIMING`).
pub fn configure(c: &mut can::CanConfigurator<'static>) {
    use crate::board::{CAN_DATA_TIMING as D, CAN_NOMINAL_TIMING as N};
    use can::config::{DataBitTiming, FrameTransmissionConfig, NominalBitTiming};
    use core::num::{NonZeroU8, NonZeroU16};
    // Non-zero by the board's compile-time checks.
    let u8nz = |x: u8| NonZeroU8::new(x).unwrap_or(NonZeroU8::MIN);
    let u16nz = |x: u16| NonZeroU16::new(x).unwrap_or(NonZeroU16::MIN);
    let mut config = c
        .config()
        .set_nominal_bit_timing(NominalBitTiming {
            prescaler: u16nz(N.prescaler),
            seg1: u8nz(N.seg1),
            seg2: u8nz(N.seg2),
            sync_jump_width: u8nz(N.sjw),
        })
        .set_data_bit_timing(DataBitTiming {
            transceiver_delay_compensation: true,
            prescaler: u16nz(D.prescaler),
            seg1: u8nz(D.seg1),
            seg2: u8nz(D.seg2),
            sync_jump_width: u8nz(D.sjw),
        });
    config.frame_transmit = FrameTransmissionConfig::AllowFdCanAndBRS;
    c.set_config(config);
}
