//! The receive task's hand-off of finished items to the tick when the inbox
//! is full. An urgent item ([`Item::is_urgent`]) is never dropped: it waits
//! for the tick to free a slot. While it waits, the CAN controller keeps
//! receiving into its own receive FIFO, which holds only [`RX_FIFO_DEPTH`]
//! frames and loses what arrives beyond them. So a waiting hand-off keeps
//! draining that FIFO through the receive side ([`HandOff::service`]): the
//! urgent items among the drained frames wait too, in order, and the
//! ordinary ones are dropped as [`offer`] drops them when only the reserved
//! slots are left (the host's flow control resends segments). A Stop or an
//! Emergency arriving behind a full inbox therefore reaches the tick.

use heapless::Deque;
use triquint_shared::protocol::CommandCode;

use crate::hal::RxFrame;
use crate::inbox::{Item, Sink, offer};

/// Frames the CAN controller's receive FIFO holds (FDCAN FIFO 0 of the
/// STM32G4); a frame arriving at a full FIFO is lost in hardware.
pub const RX_FIFO_DEPTH: usize = 3;

/// Urgent items a hand-off holds while the inbox is full.
pub const HELD_ITEMS: usize = 4;

/// The CAN controller's receive FIFO, read without waiting.
pub trait RxFifo {
    /// The oldest frame the controller holds, if any.
    fn try_take(&mut self) -> Option<RxFrame>;
}

/// An item that stops the axis (Emergency, Stop, QuickStop): of the urgent
/// items, the ones a full hold never gives up.
fn stops(item: &Item) -> bool {
    match item {
        Item::Emergency { .. } => true,
        Item::Command { command, .. } => matches!(
            command.command(),
            Ok(CommandCode::Stop | CommandCode::QuickStop)
        ),
        _ => false,
    }
}

/// Urgent items waiting for room in the inbox, in arrival order.
#[derive(Debug, Default)]
pub struct HandOff {
    held: Deque<Item, HELD_ITEMS>,
    dropped: u32,
}

impl HandOff {
    pub const fn new() -> Self {
        Self {
            held: Deque::new(),
            dropped: 0,
        }
    }

    /// Urgent items wait for the tick: the caller lets it run (yields) and
    /// calls [`HandOff::service`] until this is false.
    pub fn waiting(&self) -> bool {
        !self.held.is_empty()
    }

    /// Items given up so far: ordinary ones behind a full inbox, and urgent
    /// ones that a full hold could not keep (see [`HandOff::accept`]).
    pub fn dropped(&self) -> u32 {
        self.dropped
    }

    /// Hands `item` to the tick: straight into the inbox when nothing waits
    /// and there is room, else an urgent item is held behind those waiting
    /// and an ordinary one is dropped. A full hold keeps every stopping
    /// item: it gives up its oldest other urgent item for a new one, and a
    /// new item when it holds only stopping items (a stop is then already
    /// on its way, and it overrides whatever follows).
    // Never inlined: the ESC1 image's ELF check (scripts/elf_check.py
    // --calls) finds the receive side's hand-off through this symbol.
    #[inline(never)]
    pub fn accept(&mut self, sink: &mut impl Sink, item: Item) {
        let item = if self.held.is_empty() {
            match offer(sink, item) {
                Ok(()) => return,
                Err(back) => back,
            }
        } else {
            item
        };
        if !item.is_urgent() {
            self.dropped += 1;
            return;
        }
        if self.held.is_full() {
            self.dropped += 1;
            if !self.give_up_one_not_stopping() {
                return;
            }
        }
        let _ = self.held.push_back(item);
    }

    /// Removes the oldest held item that does not stop the axis.
    fn give_up_one_not_stopping(&mut self) -> bool {
        let Some(k) = self.held.iter().position(|i| !stops(i)) else {
            return false;
        };
        // In place, the others keeping their order (a second queue would be
        // a few hundred bytes of stack an item): the front comes off and each
        // item before the k-th moves one place back, the k-th falling out.
        let Some(mut carried) = self.held.pop_front() else {
            return false;
        };
        for slot in self.held.iter_mut().take(k) {
            carried = core::mem::replace(slot, carried);
        }
        true
    }

    /// One retry while waiting: offers the held items, then drains the
    /// receive FIFO, each frame through `receive` (the receive side), so
    /// the controller never runs full while the tick catches up.
    pub fn service(
        &mut self,
        sink: &mut impl Sink,
        fifo: &mut impl RxFifo,
        mut receive: impl FnMut(&RxFrame) -> Option<Item>,
    ) {
        self.flush(sink);
        while let Some(frame) = fifo.try_take() {
            if let Some(item) = receive(&frame) {
                self.accept(sink, item);
            }
        }
        self.flush(sink);
    }

    /// Offers the held items in order while the inbox takes them.
    fn flush(&mut self, sink: &mut impl Sink) {
        while let Some(item) = self.held.pop_front() {
            if let Err(back) = offer(sink, item) {
                let _ = self.held.push_front(back);
                return;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use std::vec::Vec;

    use triquint_shared::protocol::{Command, CommandCode, Emergency, Frame};

    use super::*;
    use crate::inbox::{Inbox, Source, TickSnapshot};
    use crate::receiver::Receiver;

    const NODE: u8 = 2;

    /// The controller's receive FIFO: [`RX_FIFO_DEPTH`] frames, a frame
    /// arriving at a full FIFO is lost.
    #[derive(Default)]
    struct ModelFifo {
        frames: Deque<RxFrame, RX_FIFO_DEPTH>,
        lost: Vec<Frame>,
    }

    impl ModelFifo {
        fn arrive(&mut self, frame: Frame, t: u64) {
            let rx = RxFrame {
                frame,
                timestamp_us: t,
            };
            if self.frames.push_back(rx).is_err() {
                self.lost.push(frame);
            }
        }
    }

    impl RxFifo for ModelFifo {
        fn try_take(&mut self) -> Option<RxFrame> {
            self.frames.pop_front()
        }
    }

    fn command(c: CommandCode, token: u8) -> Frame {
        Command {
            command: c as u8,
            token,
            arg: 0,
            arg2: 0,
        }
        .to_frame(NODE)
    }

    fn is_stop(item: &Item) -> bool {
        matches!(item, Item::Command { command, .. }
            if command.command() == Ok(CommandCode::Stop))
    }

    fn is_emergency(item: &Item) -> bool {
        matches!(item, Item::Emergency { .. })
    }

    /// The traffic behind a full inbox: a FeedHold that must wait, then
    /// ordinary commands (one frame per 100 µs step), then a Stop and a
    /// host Emergency; the tick is stalled for `stall` steps, then takes one
    /// item per step.
    fn traffic() -> Vec<Frame> {
        let mut v = std::vec![command(CommandCode::FeedHold, 1)];
        for k in 0..6 {
            v.push(command(CommandCode::Arm, 10 + k));
        }
        v.push(command(CommandCode::Stop, 20));
        v.push(Emergency::host_stop());
        v
    }

    /// What reached the tick, and what the FIFO lost, with the receive
    /// task's step given as `receive_step(receiver, inbox, fifo, waiting)`.
    fn run(
        stall: usize,
        mut step: impl FnMut(&mut Receiver, &mut Inbox, &mut ModelFifo),
    ) -> (Vec<Item>, Vec<Frame>) {
        let mut receiver = Receiver::new(NODE);
        let mut inbox = Inbox::new();
        // The inbox full of urgent items the tick has not taken yet.
        let filler = RxFrame {
            frame: command(CommandCode::Resume, 0),
            timestamp_us: 0,
        };
        while inbox.len() < inbox.capacity() {
            let item = receiver
                .on_frame(&filler, TickSnapshot::INITIAL)
                .expect("an item");
            inbox.enqueue(item).unwrap();
        }
        let mut fifo = ModelFifo::default();
        let mut reached = Vec::new();
        let frames = traffic();
        for t in 0..200 {
            if let Some(f) = frames.get(t) {
                fifo.arrive(*f, t as u64 * 100);
            }
            step(&mut receiver, &mut inbox, &mut fifo);
            if t >= stall {
                if let Some(i) = inbox.front() {
                    reached.push(*i);
                }
                inbox.pop_front();
            }
        }
        (reached, fifo.lost)
    }

    /// The receive task's new loop: one blocking read when nothing waits,
    /// one [`HandOff::service`] per retry while something does.
    fn with_hand_off(stall: usize) -> (Vec<Item>, Vec<Frame>) {
        let mut h = HandOff::new();
        run(stall, move |receiver, inbox, fifo| {
            if h.waiting() {
                h.service(inbox, fifo, |f| receiver.on_frame(f, TickSnapshot::INITIAL));
            } else if let Some(f) = fifo.try_take()
                && let Some(item) = receiver.on_frame(&f, TickSnapshot::INITIAL)
            {
                h.accept(inbox, item);
            }
        })
    }

    /// The board's old loop: an urgent item is offered again and again,
    /// and the FIFO is not read until it is in.
    fn old_loop(stall: usize) -> (Vec<Item>, Vec<Frame>) {
        let mut waiting: Option<Item> = None;
        run(stall, move |receiver, inbox, fifo| {
            if let Some(item) = waiting.take() {
                if let Err(back) = offer(inbox, item) {
                    waiting = Some(back);
                }
                return;
            }
            if let Some(f) = fifo.try_take()
                && let Some(item) = receiver.on_frame(&f, TickSnapshot::INITIAL)
                && let Err(back) = offer(inbox, item)
                && back.is_urgent()
            {
                waiting = Some(back);
            }
        })
    }

    #[test]
    fn the_old_loop_loses_a_stop_in_the_receive_fifo() {
        let (reached, lost) = old_loop(20);
        assert!(!reached.iter().any(is_stop), "the Stop reached the tick");
        assert!(!reached.iter().any(is_emergency));
        assert!(lost.contains(&command(CommandCode::Stop, 20)));
    }

    #[test]
    fn a_stop_and_an_emergency_behind_a_full_inbox_reach_the_tick() {
        for stall in [0, 1, 5, 20, 100] {
            let (reached, lost) = with_hand_off(stall);
            assert!(lost.is_empty(), "stall {stall}: FIFO lost {lost:?}");
            let stop = reached.iter().position(is_stop);
            let emergency = reached.iter().position(is_emergency);
            assert!(stop.is_some(), "stall {stall}: Stop lost");
            assert!(emergency.is_some(), "stall {stall}: Emergency lost");
            // In arrival order, after the FeedHold that waited first.
            let hold = reached.iter().position(|i| {
                matches!(i, Item::Command { command, .. }
                    if command.command() == Ok(CommandCode::FeedHold))
            });
            assert!(hold < stop && stop < emergency, "stall {stall}");
        }
    }

    #[test]
    fn a_full_hold_keeps_every_stopping_item() {
        let mut receiver = Receiver::new(NODE);
        let mut item = |f: Frame| {
            let rx = RxFrame {
                frame: f,
                timestamp_us: 0,
            };
            receiver.on_frame(&rx, TickSnapshot::INITIAL).unwrap()
        };
        let mut inbox = Inbox::new();
        while inbox.len() < inbox.capacity() {
            inbox
                .enqueue(item(command(CommandCode::Resume, 0)))
                .unwrap();
        }
        let mut h = HandOff::new();
        h.accept(&mut inbox, item(command(CommandCode::FeedHold, 1)));
        h.accept(&mut inbox, item(command(CommandCode::Stop, 2)));
        h.accept(&mut inbox, item(command(CommandCode::Override, 3)));
        h.accept(&mut inbox, item(command(CommandCode::QuickStop, 4)));
        // Full: the FeedHold gives way to the Emergency, then the
        // Override to the second Stop; a Resume finds only stops.
        h.accept(&mut inbox, item(Emergency::host_stop()));
        h.accept(&mut inbox, item(command(CommandCode::Stop, 5)));
        h.accept(&mut inbox, item(command(CommandCode::Resume, 6)));
        // An ordinary item behind waiting ones is dropped.
        h.accept(&mut inbox, item(command(CommandCode::Arm, 7)));
        assert_eq!(h.dropped(), 4);
        let held: Vec<Item> = h.held.iter().copied().collect();
        assert_eq!(held.len(), HELD_ITEMS);
        assert!(held.iter().all(stops));
        let tokens: Vec<u8> = held
            .iter()
            .filter_map(|i| match i {
                Item::Command { command, .. } => Some(command.token),
                _ => None,
            })
            .collect();
        assert_eq!(tokens, [2, 4, 5]);
    }
}
