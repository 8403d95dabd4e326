//! Configuration: every node's configuration written and committed (a
//! commit refused or unanswered is sent again, configuration and all, up to
//! `setup_resends` times), then checked against each node's heartbeat CRC;
//! a node whose CRC differs is read back, parameter by parameter, to name
//! what differs.

use triquint_shared::protocol::{
    CommandCode, DriveConfig, PARAM_COUNT, PARAMS, config_write_frame,
};

use super::nodes::{NODES, NodeView, Nodes};
use super::outbox::Outbox;
use super::{SessionOptions, UploadError};

/// The latest ConfigCommit to one node.
#[derive(Clone, Copy, Debug, Default)]
struct Commit {
    token: u8,
    sent_at: u64,
    /// Attempts before this one.
    resends: u32,
}

/// A node's configuration being read back.
#[derive(Clone, Copy, Debug)]
struct Readback {
    node: u8,
    values: [Option<f32>; PARAM_COUNT],
}

#[derive(Debug)]
pub(crate) struct Configuration {
    configs: [DriveConfig; NODES],
    commits: [Commit; NODES],
    readback: Option<Readback>,
}

fn is_commit(v: &NodeView) -> bool {
    v.last_answer
        .is_some_and(|a| a.command == CommandCode::ConfigCommit as u8)
}

impl Configuration {
    pub fn new(configs: [DriveConfig; NODES]) -> Self {
        Self {
            configs,
            commits: [Commit::default(); NODES],
            readback: None,
        }
    }

    /// Node id of index `i` (its configuration's).
    fn id(&self, i: usize) -> u8 {
        self.configs[i].node_id as u8
    }

    /// Writes every node's configuration, then commits each.
    pub fn start(&mut self, now: u64, out: &mut Outbox) {
        for i in 0..NODES {
            self.write(i, out);
        }
        for i in 0..NODES {
            self.commit(i, now, 0, out);
        }
    }

    fn write(&self, i: usize, out: &mut Outbox) {
        for (k, val) in self.configs[i].to_values().iter().enumerate() {
            out.push_back(config_write_frame(self.id(i), k as u8, *val));
        }
    }

    fn commit(&mut self, i: usize, now: u64, resends: u32, out: &mut Outbox) {
        let token = out.command(self.id(i), CommandCode::ConfigCommit, self.configs[i].crc());
        self.commits[i] = Commit {
            token,
            sent_at: now,
            resends,
        };
    }

    /// `Ok(true)` once every node committed its configuration; resends
    /// what was refused or not answered.
    pub fn committed(
        &mut self,
        now: u64,
        nodes: &Nodes,
        opts: &SessionOptions,
        out: &mut Outbox,
    ) -> Result<bool, UploadError> {
        let mut done = 0;
        for i in 0..NODES {
            let c = self.commits[i];
            let can_resend = c.resends < opts.setup_resends;
            let answer = nodes.0[i]
                .last_answer
                .filter(|a| a.command == CommandCode::ConfigCommit as u8);
            match answer {
                Some(a) if a.result == 0 => done += 1,
                // The latest commit was refused.
                Some(a) if a.token == c.token => {
                    if !can_resend {
                        return Err(UploadError::ConfigCrc {
                            node: self.id(i),
                            node_crc: a.value,
                            plan_crc: self.configs[i].crc(),
                        });
                    }
                    self.resend(i, now, c.resends + 1, out);
                }
                _ if can_resend && now.saturating_sub(c.sent_at) > opts.setup_retry_us => {
                    self.resend(i, now, c.resends + 1, out);
                }
                _ => {}
            }
        }
        Ok(done == NODES)
    }

    fn resend(&mut self, i: usize, now: u64, resends: u32, out: &mut Outbox) {
        self.write(i, out);
        self.commit(i, now, resends, out);
    }

    /// Which node has not answered a commit (for the timeout).
    pub fn uncommitted(nodes: &Nodes) -> u8 {
        nodes.first(|v| !is_commit(v))
    }

    /// The first node whose active configuration CRC is not its plan's.
    pub fn differing(&self, nodes: &Nodes) -> Option<usize> {
        (0..NODES).find(|&i| nodes.0[i].config_crc != self.configs[i].crc())
    }

    /// Asks node index `i` for its configuration, value by value.
    pub fn read_back(&mut self, i: usize, out: &mut Outbox) {
        let node = self.id(i);
        self.readback = Some(Readback {
            node,
            values: [None; PARAM_COUNT],
        });
        out.command(node, CommandCode::ReadConfig, 0);
    }

    /// A ConfigValue from `node`.
    pub fn value(&mut self, node: u8, index: u8, value: f32) {
        if let Some(r) = &mut self.readback
            && r.node == node
            && let Some(slot) = r.values.get_mut(index as usize)
        {
            *slot = Some(value);
        }
    }

    /// Once every value is back: the error naming the first parameter that
    /// differs, or, with the same values and yet another CRC, that the
    /// node did not commit them.
    pub fn read_back_error(&self, nodes: &Nodes) -> Option<UploadError> {
        let r = self.readback?;
        if !r.values.iter().all(Option::is_some) {
            return None;
        }
        let i = r.node as usize - 1;
        let want = self.configs[i].to_values();
        for (k, p) in PARAMS.iter().enumerate() {
            let got = r.values[k].unwrap_or(f32::NAN);
            if got.to_bits() != want[k].to_bits() {
                return Some(UploadError::ConfigMismatch {
                    node: r.node,
                    param: p.name,
                    node_value: got,
                    plan_value: want[k],
                });
            }
        }
        Some(UploadError::ConfigCrc {
            node: r.node,
            node_crc: nodes.0[i].config_crc,
            plan_crc: self.configs[i].crc(),
        })
    }
}
