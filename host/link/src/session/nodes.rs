//! What the host knows of each drive node, from its heartbeats and answers.

use triquint_shared::protocol::{CommandAck, State};

/// Drive nodes (node `i + 1` drives axis `i`).
pub const NODES: usize = 3;

/// Node id of index `i` (0-based).
pub(crate) fn node_id(i: usize) -> u8 {
    i as u8 + 1
}

/// Index of node id `node`, if it is one of the drives.
pub(crate) fn node_index(node: u8) -> Option<usize> {
    (1..=NODES as u8).contains(&node).then(|| node as usize - 1)
}

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
    /// Host time (µs) of its latest heartbeat.
    pub heartbeat_at: Option<u64>,
    pub state: Option<State>,
    pub fault: u8,
    pub config_crc: u32,
    pub version: u8,
    /// Its clock follows the host's time sync.
    pub sync_ok: bool,
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
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Nodes(pub [NodeView; NODES]);

impl Nodes {
    pub fn all(&self, f: impl Fn(&NodeView) -> bool) -> bool {
        self.0.iter().all(f)
    }

    pub fn any(&self, f: impl Fn(&NodeView) -> bool) -> bool {
        self.0.iter().any(f)
    }

    /// Each node's answer to the command with `token`.
    pub fn answers_to(&self, token: u8) -> [Option<u8>; NODES] {
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

    /// The first node for which `missing` holds (node 1 if none does).
    pub fn first(&self, missing: impl Fn(&NodeView) -> bool) -> u8 {
        self.0.iter().position(missing).map_or(1, node_id)
    }
}
