//! What the host knows of each drive node, from its heartbeats and answers.

use triquint_shared::protocol::{CommandAck, Heartbeat, HeartbeatExt, State, flags};

use crate::Drive;

/// Drives of a robot (index `i` drives axis `i + 1`; its node id is
/// configured, by default `i + 1`).
pub const AXES: usize = 3;

/// A node's answer to a command (its latest CommandAck).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CommandAnswer {
    pub command: u8,
    pub token: u8,
    /// 0: done; else a fault code (or a configuration CRC mismatch).
    pub result: u8,
    /// The node's configuration CRC for ConfigCommit.
    pub value: u32,
}

impl From<CommandAck> for CommandAnswer {
    fn from(a: CommandAck) -> Self {
        Self {
            command: a.command,
            token: a.token,
            result: a.result,
            value: a.value,
        }
    }
}

/// One node as the host last heard it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct NodeView {
    /// Its node id.
    pub id: u8,
    /// Host time (µs) of its latest heartbeat.
    pub heartbeat_at: Option<u64>,
    pub state: Option<State>,
    pub fault: u8,
    pub config_crc: u32,
    pub version: u8,
    /// Its clock follows the host's time sync.
    pub sync_ok: bool,
    /// Its position is absolute (homed).
    pub homed: bool,
    /// HeartbeatExt `flags` as received.
    pub flags: u8,
    /// CAN transmit and receive error counters, rejects and the last reason.
    pub tx_errors: u8,
    pub rx_errors: u8,
    pub rejects: u16,
    pub last_reject: u8,
    /// Joint position (m) from its latest Telemetry, in its own frame.
    pub position: Option<f32>,
    /// Host time (µs) of its latest extended heartbeat (sync status).
    pub sync_seen_at: Option<u64>,
    /// The next segment sequence number it expects.
    pub next_seq: u16,
    /// Segments in its queue, and how many it holds.
    pub depth: u8,
    pub capacity: u8,
    pub last_answer: Option<CommandAnswer>,
}

impl NodeView {
    /// Takes in a Heartbeat received at host time `t_us`.
    pub fn heartbeat(&mut self, h: &Heartbeat, t_us: u64) {
        self.heartbeat_at = Some(t_us);
        self.state = State::from_u8(h.state);
        self.fault = h.fault;
        self.config_crc = h.config_crc;
        self.version = h.protocol_version;
        self.depth = h.queue_depth;
    }

    /// Takes in a HeartbeatExt received at host time `t_us`.
    pub fn heartbeat_ext(&mut self, h: &HeartbeatExt, t_us: u64) {
        self.sync_ok = h.has(flags::SYNCED);
        self.homed = h.has(flags::HOMED);
        self.flags = h.flags;
        self.sync_seen_at = Some(t_us);
        self.next_seq = h.next_seq;
        self.tx_errors = h.tx_errors;
        self.rx_errors = h.rx_errors;
        self.rejects = h.rejects;
        self.last_reject = h.last_reject;
    }

    /// Its answer (result) to the command with `token`, if it gave one.
    pub fn answer_to(&self, token: u8) -> Option<u8> {
        self.last_answer
            .filter(|a| a.token == token)
            .map(|a| a.result)
    }

    /// Highest sequence number (exclusive) it can take now: what it expects
    /// next, less what is queued, plus its capacity (1 before it said).
    pub fn credit(&self) -> usize {
        let cap = if self.capacity == 0 {
            1
        } else {
            self.capacity as usize
        };
        (self.next_seq as usize).saturating_sub(self.depth as usize) + cap
    }
}

/// The views of every node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Nodes(pub [NodeView; AXES]);

impl Default for Nodes {
    fn default() -> Self {
        Self::new(triquint_shared::protocol::NODES)
    }
}

impl Nodes {
    /// The drives of axes 1–3 on node ids `ids`.
    pub fn new(ids: [u8; AXES]) -> Self {
        Self(ids.map(|id| NodeView {
            id,
            ..NodeView::default()
        }))
    }

    /// Node id of index `i`.
    pub fn id(&self, i: usize) -> u8 {
        self.0.get(i).map_or(0, |v| v.id)
    }

    /// The drive of index `i`, as messages name it.
    pub fn drive(&self, i: usize) -> Drive {
        Drive {
            axis: i + 1,
            node: self.id(i),
        }
    }

    /// The drive of node id `node` (axis 0 for one that is not a drive).
    pub fn drive_of(&self, node: u8) -> Drive {
        Drive {
            axis: self.index(node).map_or(0, |i| i + 1),
            node,
        }
    }

    /// Index of node id `node`, if it is one of the drives.
    pub fn index(&self, node: u8) -> Option<usize> {
        (node != 0).then(|| self.0.iter().position(|v| v.id == node))?
    }

    pub fn all(&self, f: impl Fn(&NodeView) -> bool) -> bool {
        self.0.iter().all(f)
    }

    pub fn any(&self, f: impl Fn(&NodeView) -> bool) -> bool {
        self.0.iter().any(f)
    }

    /// Each node's answer to the command with `token`.
    pub fn answers_to(&self, token: u8) -> [Option<u8>; AXES] {
        self.0.map(|v| v.answer_to(token))
    }

    /// Highest sequence number (exclusive) every node can take now.
    pub fn credit(&self) -> usize {
        self.0.iter().map(NodeView::credit).min().unwrap_or(0)
    }

    /// The smallest queue capacity reported (0 before every node said).
    pub fn min_capacity(&self) -> usize {
        self.0
            .iter()
            .map(|v| v.capacity as usize)
            .min()
            .unwrap_or(0)
    }

    /// The first drive for which `missing` holds (the first if none does).
    pub fn first(&self, missing: impl Fn(&NodeView) -> bool) -> Drive {
        let i = self.0.iter().position(missing).unwrap_or(0);
        self.drive(i)
    }
}
