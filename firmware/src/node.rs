//! A whole drive node in one context: the receive side and the control side
//! together, each frame filed at once. What simulators and host-side tests
//! run; a board runs the two parts in two contexts instead (see the crate doc).

use core::ops::{Deref, DerefMut};

use crate::drive::{Drive, QUEUE_CAPACITY};
use crate::hal::{CanBus, RxFrame};
use crate::receiver::Receiver;

/// One drive node with a segment queue of capacity `Q`. Derefs to its
/// [`Drive`] (state, tick, transmit queue, statistics).
#[derive(Clone)]
pub struct Node<const Q: usize = QUEUE_CAPACITY> {
    pub receiver: Receiver,
    pub drive: Drive<Q>,
}

impl<const Q: usize> Node<Q> {
    /// A node with number `node_id` (1–15), Idle, unconfigured, motor off.
    pub fn new(node_id: u8) -> Self {
        Self {
            receiver: Receiver::new(node_id),
            drive: Drive::new(node_id),
        }
    }

    /// A node after power-on whose position is unknown until it is homed.
    pub fn new_unhomed(node_id: u8) -> Self {
        Self {
            receiver: Receiver::new(node_id),
            drive: Drive::new_unhomed(node_id),
        }
    }

    /// Handles one received frame: receive side, then the drive takes the item.
    pub fn on_frame(&mut self, rx: &RxFrame) {
        if let Some(item) = self.receiver.on_frame(rx, self.drive.snapshot()) {
            self.drive.take(&item);
        }
    }
}

/// Runs one communication pass: every received frame into the node, the
/// controller's error counters into its heartbeat, then as many queued
/// frames as the controller takes.
pub fn service<P: CanBus, const Q: usize>(node: &mut Node<Q>, port: &mut P) {
    while let Some(rx) = port.receive() {
        node.on_frame(&rx);
    }
    node.drive.set_error_counters(port.error_counters());
    while let Some(f) = node.drive.peek_tx() {
        if !port.transmit(&f) {
            break;
        }
        node.drive.pop_tx();
    }
}

impl<const Q: usize> Deref for Node<Q> {
    type Target = Drive<Q>;
    fn deref(&self) -> &Drive<Q> {
        &self.drive
    }
}

impl<const Q: usize> DerefMut for Node<Q> {
    fn deref_mut(&mut self) -> &mut Drive<Q> {
        &mut self.drive
    }
}
