//! Configuration: every node's configuration written and committed (a
//! commit refused or unanswered is sent again, configuration and all, up to
//! `setup_resends` times), then checked against each node's heartbeat CRC;
//! a node whose CRC differs is read back, parameter by parameter, to name
//! what differs.

use triquint_shared::protocol::{
    CommandCode, DriveConfig, FaultCode, PARAM_COUNT, PARAMS, config_write_frame,
};

use super::nodes::{AXES, NodeView, Nodes};
use super::outbox::Outbox;
use super::{SessionOptions, UploadError};
use crate::Drive;

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
    /// Its index (axis) and node id: ids need not be 1, 2, 3 in order.
    i: usize,
    node: u8,
    values: [Option<f32>; PARAM_COUNT],
}

#[derive(Clone, Debug)]
pub(crate) struct Configuration {
    configs: [DriveConfig; AXES],
    commits: [Commit; AXES],
    readback: Option<Readback>,
    /// The maintenance windows were asked for.
    unlock: bool,
}

fn is_commit(v: &NodeView) -> bool {
    v.last_answer
        .is_some_and(|a| a.command == CommandCode::ConfigCommit as u8)
}

impl Configuration {
    pub fn new(configs: [DriveConfig; AXES]) -> Self {
        Self {
            configs,
            commits: [Commit::default(); AXES],
            readback: None,
            unlock: false,
        }
    }

    /// Node id of index `i` (its configuration's).
    fn id(&self, i: usize) -> u8 {
        self.configs[i].node_id as u8
    }

    /// The drive of index `i`, as messages name it.
    fn drive(&self, i: usize) -> Drive {
        Drive {
            axis: i + 1,
            node: self.id(i),
        }
    }

    /// Writes every node's configuration, then commits each; with
    /// `unlock`, each configured node's maintenance window is opened first
    /// (its key: the CRC it reports running, from `nodes`).
    pub fn start(&mut self, now: u64, nodes: &Nodes, unlock: bool, out: &mut Outbox) {
        self.unlock = unlock;
        for (i, v) in nodes.0.iter().enumerate() {
            if unlock && v.config_crc != 0 {
                out.command(self.id(i), CommandCode::UnlockCeilings, v.config_crc);
            }
        }
        for i in 0..AXES {
            self.write(i, out);
        }
        for i in 0..AXES {
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
        for i in 0..AXES {
            let c = self.commits[i];
            let can_resend = c.resends < opts.setup_resends;
            let answer = nodes.0[i]
                .last_answer
                .filter(|a| a.command == CommandCode::ConfigCommit as u8);
            match answer {
                Some(a) if a.result == 0 => done += 1,
                // A locked bound widened: the answer names it.
                Some(a) if a.token == c.token && a.result == FaultCode::CeilingsLocked as u8 => {
                    let values = self.configs[i].to_values();
                    let k = a.value as usize;
                    return Err(UploadError::CeilingsLocked {
                        node: self.drive(i),
                        param: PARAMS.get(k).map(|p| p.name),
                        plan_value: values.get(k).copied().unwrap_or(f32::NAN),
                        unlocked: self.unlock,
                    });
                }
                // The latest commit was refused.
                // Refused for its state (not Idle), not for its values.
                Some(a)
                    if a.token == c.token
                        && a.result != FaultCode::ConfigMismatch as u8
                        && a.result != 0 =>
                {
                    return Err(UploadError::Refused {
                        node: self.drive(i),
                        command: CommandCode::ConfigCommit,
                        code: FaultCode::from_u8(a.result),
                    });
                }
                Some(a) if a.token == c.token => {
                    if !can_resend {
                        return Err(UploadError::ConfigCrc {
                            node: self.drive(i),
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
        Ok(done == AXES)
    }

    fn resend(&mut self, i: usize, now: u64, resends: u32, out: &mut Outbox) {
        self.write(i, out);
        self.commit(i, now, resends, out);
    }

    /// The node id being read back, if any (for the timeout).
    pub fn reading_back(&self) -> Option<u8> {
        self.readback.map(|r| r.node)
    }

    /// Which node has not answered a commit (for the timeout).
    pub fn uncommitted(nodes: &Nodes) -> Drive {
        nodes.first(|v| !is_commit(v))
    }

    /// The first node whose active configuration CRC is not its plan's.
    pub fn differing(&self, nodes: &Nodes) -> Option<usize> {
        (0..AXES).find(|&i| nodes.0[i].config_crc != self.configs[i].crc())
    }

    /// Asks node index `i` for its configuration, value by value.
    pub fn read_back(&mut self, i: usize, out: &mut Outbox) {
        let node = self.id(i);
        self.readback = Some(Readback {
            i,
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
        let i = r.i;
        let want = self.configs[i].to_values();
        for (k, p) in PARAMS.iter().enumerate() {
            let got = r.values[k].unwrap_or(f32::NAN);
            if got.to_bits() != want[k].to_bits() {
                return Some(UploadError::ConfigMismatch {
                    node: self.drive(i),
                    param: p.name,
                    node_value: got,
                    plan_value: want[k],
                });
            }
        }
        Some(UploadError::ConfigCrc {
            node: self.drive(i),
            node_crc: nodes.0[i].config_crc,
            plan_crc: self.configs[i].crc(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::session::nodes::CommandAnswer;

    /// Configurations of nodes `ids` (axis i on `ids[i]`), otherwise alike.
    fn configs(ids: [u8; AXES]) -> [DriveConfig; AXES] {
        ids.map(|id| {
            let mut c = DriveConfig::from_values(&[0.5; PARAM_COUNT]);
            c.node_id = f32::from(id);
            c
        })
    }

    /// Node index `i` reads back `values` while its heartbeat reports `crc`.
    fn read_back(
        ids: [u8; AXES],
        i: usize,
        values: [f32; PARAM_COUNT],
        crc: u32,
    ) -> Option<UploadError> {
        let cfgs = configs(ids);
        let mut nodes = Nodes::new(ids);
        for (k, v) in nodes.0.iter_mut().enumerate() {
            v.config_crc = cfgs[k].crc();
        }
        nodes.0[i].config_crc = crc;
        let mut c = Configuration::new(cfgs);
        assert_eq!(c.differing(&nodes), Some(i));
        c.read_back(i, &mut Outbox::default());
        assert_eq!(c.reading_back(), Some(ids[i]));
        for (k, v) in values.iter().enumerate() {
            c.value(ids[i], k as u8, *v);
        }
        c.read_back_error(&nodes)
    }

    #[test]
    fn read_back_finds_the_node_by_id_not_by_number() {
        for ids in [[4, 5, 6], [2, 1, 3], [1, 2, 3]] {
            for i in 0..AXES {
                let plan = configs(ids)[i];
                // Same values, another CRC: the node did not commit them.
                let e = read_back(ids, i, plan.to_values(), 0xDEAD_BEEF);
                match e {
                    Some(UploadError::ConfigCrc {
                        node,
                        node_crc,
                        plan_crc,
                    }) => {
                        assert_eq!(node, Drive::of(ids, i));
                        assert_eq!(node_crc, 0xDEAD_BEEF);
                        assert_eq!(plan_crc, plan.crc());
                    }
                    e => panic!("ids {ids:?} index {i}: {e:?}"),
                }
                // One value differs: named, with this node's plan value.
                let mut v = plan.to_values();
                v[0] = 7.0;
                match read_back(ids, i, v, 0xDEAD_BEEF) {
                    Some(UploadError::ConfigMismatch {
                        node,
                        param,
                        node_value,
                        plan_value,
                    }) => {
                        assert_eq!((node, param), (Drive::of(ids, i), PARAMS[0].name));
                        assert_eq!((node_value, plan_value), (7.0, 0.5));
                    }
                    e => panic!("ids {ids:?} index {i}: {e:?}"),
                }
            }
        }
    }

    #[test]
    fn values_of_another_node_are_not_taken() {
        let ids = [2, 1, 3];
        let cfgs = configs(ids);
        let mut nodes = Nodes::new(ids);
        nodes.0[0].config_crc = 1;
        let mut c = Configuration::new(cfgs);
        c.read_back(0, &mut Outbox::default());
        for k in 0..PARAM_COUNT {
            c.value(1, k as u8, 0.0);
        }
        assert!(c.read_back_error(&nodes).is_none());
    }

    #[test]
    fn a_commit_refused_with_the_plans_crc_is_not_called_a_crc_difference() {
        let ids = [4, 5, 6];
        let cfgs = configs(ids);
        let opts = SessionOptions::default();
        for (result, want) in [
            (FaultCode::WrongState, "WrongState"),
            (FaultCode::ConfigMismatch, ""),
        ] {
            let mut c = Configuration::new(cfgs);
            let mut out = Outbox::default();
            c.start(0, &Nodes::new(ids), false, &mut out);
            let mut nodes = Nodes::new(ids);
            for (k, v) in nodes.0.iter_mut().enumerate() {
                v.last_answer = Some(CommandAnswer {
                    command: CommandCode::ConfigCommit as u8,
                    token: c.commits[k].token,
                    result: if k == 1 { result as u8 } else { 0 },
                    value: cfgs[k].crc(),
                });
            }
            let mut last = Ok(false);
            for _ in 0..=opts.setup_resends {
                last = c.committed(0, &nodes, &opts, &mut out);
                nodes.0[1].last_answer.as_mut().unwrap().token = c.commits[1].token;
                if last.is_err() {
                    break;
                }
            }
            let e = last.unwrap_err();
            let msg = e.to_string();
            assert!(msg.contains("node 5"), "{msg}");
            assert!(!msg.contains("differs"), "{msg}");
            if want.is_empty() {
                assert!(e.is_config(), "{msg}");
            } else {
                assert!(e.is_refusal() && msg.contains(want), "{msg}");
            }
        }
    }

    #[test]
    fn unlocking_opens_each_configured_nodes_window_with_its_crc_first() {
        use triquint_shared::protocol::{Msg, decode};
        let ids = [4, 5, 6];
        let mut nodes = Nodes::new(ids);
        // Node 6 has no configuration yet: its first one sets its bounds.
        (nodes.0[0].config_crc, nodes.0[1].config_crc) = (0xAB, 0xCD);
        for unlock in [false, true] {
            let mut c = Configuration::new(configs(ids));
            let mut out = Outbox::default();
            c.start(0, &nodes, unlock, &mut out);
            let commands: Vec<(u8, u8, u32)> = out
                .frames()
                .filter_map(|f| match decode(f) {
                    Ok((Msg::Command(k), n)) => Some((k.command, n, k.arg)),
                    _ => None,
                })
                .collect();
            let u = CommandCode::UnlockCeilings as u8;
            let unlocks: Vec<_> = commands.iter().filter(|k| k.0 == u).collect();
            if unlock {
                assert_eq!(unlocks, [&(u, 4, 0xAB), &(u, 5, 0xCD)]);
                // Before any write.
                assert!(matches!(
                    decode(out.frames().next().unwrap()),
                    Ok((Msg::Command(_), 4))
                ));
            } else {
                assert!(unlocks.is_empty());
            }
        }
    }

    #[test]
    fn a_commit_refused_for_the_ceiling_lock_names_the_parameter() {
        let ids = [4, 5, 6];
        let mut cfgs = configs(ids);
        cfgs[2].ceiling_jerk = 123.0;
        let opts = SessionOptions::default();
        for unlock in [false, true] {
            let mut c = Configuration::new(cfgs);
            let mut out = Outbox::default();
            let nodes0 = Nodes::new(ids);
            c.start(0, &nodes0, unlock, &mut out);
            let mut nodes = Nodes::new(ids);
            for (k, v) in nodes.0.iter_mut().enumerate() {
                let locked = k == 2;
                v.last_answer = Some(CommandAnswer {
                    command: CommandCode::ConfigCommit as u8,
                    token: c.commits[k].token,
                    result: if locked {
                        FaultCode::CeilingsLocked as u8
                    } else {
                        0
                    },
                    value: if locked { 57 } else { cfgs[k].crc() },
                });
            }
            let e = c.committed(0, &nodes, &opts, &mut out).unwrap_err();
            let msg = e.to_string();
            assert!(e.is_refusal(), "{msg}");
            assert!(
                msg.contains("node 6") && msg.contains("`ceiling_jerk` (to 123)"),
                "{msg}"
            );
            assert_eq!(msg.contains("maintenance window"), unlock, "{msg}");
        }
    }
}
