//! Commands: the state machine's transitions the host asks for (Arm,
//! Start, Stop, feed hold, configuration commit, ...), each answered by a
//! CommandAck, repeats within the repeat window answered again.

use triquint_shared::protocol::contract::{MAINTENANCE_WINDOW_US, REPEAT_WINDOW_US};
use triquint_shared::protocol::{
    Command, CommandAck, CommandCode, FaultCode, State, config_value_frame,
};

use super::{Drive, OUTBOX, StopReason};
use crate::derived_config::DerivedConfig;
use crate::inbox::{CommandData, LockCheck, Prepared};
use crate::scaling::q16_from_permille;
#[cfg(doc)]
use crate::sync::SyncEstimator;

/// A ReadConfig answer goes out while fewer frames than this wait, so the
/// rest of the outbox stays free for acknowledgements, emergencies and the
/// periodic frames.
const READOUT_BELOW: usize = OUTBOX / 2;

impl<const Q: usize> Drive<Q> {
    pub(super) fn command_ack(&mut self, c: &Command, result: FaultCode, value: u32) {
        let a = CommandAck {
            command: c.command,
            token: c.token,
            result: result as u8,
            state: self.state as u8,
            value,
        };
        self.last_command = Some((*c, a, self.command_rx_us));
        let f = a.to_frame(self.node_id);
        self.send(f);
    }

    // Not inlined into the tick: commands are rare, and the tick's own code
    // must fit the 10 KB of CCM SRAM on the ESC1 board.
    #[inline(never)]
    pub(super) fn on_command(&mut self, c: &Command, local_us: u64, data: &CommandData) {
        self.command_rx_us = local_us;
        if let Some((last, ack, at)) = self.last_command
            && last == *c
            && local_us.saturating_sub(at) < REPEAT_WINDOW_US
        {
            let f = ack.to_frame(self.node_id);
            self.send(f);
            return;
        }
        let code = c.command();
        // The maintenance window lasts until anything but its own commit.
        if !matches!(
            code,
            Ok(CommandCode::UnlockCeilings | CommandCode::ConfigCommit | CommandCode::ReadConfig)
        ) {
            self.maintenance.close();
        }
        let Ok(code) = code else {
            self.command_ack(c, FaultCode::BadCommand, 0);
            return;
        };
        let r = match code {
            CommandCode::Arm => {
                // With the override the plan starts at: set before the upload
                // (another process), the host learns it here.
                let r = self.arm(local_us);
                let pm = self.override_permille();
                self.command_ack(c, r, pm);
                return;
            }
            CommandCode::Start => self.start(c.arg, local_us),
            CommandCode::Stop | CommandCode::QuickStop => {
                let quick = code == CommandCode::QuickStop;
                match (self.state, self.active) {
                    (State::Running, _) => {
                        let t = self.applies_at(c, local_us, data);
                        let r = data.retarget();
                        self.begin_stop_dated(StopReason::Commanded, quick, t, r, carried_ramp(c));
                        FaultCode::None
                    }
                    (State::Stopping, Some(a)) => {
                        // A quick stop during a stop: the shorter ramp, from here.
                        if quick {
                            let t = self.applies_at(c, local_us, data);
                            let r = data.retarget();
                            let quick_ns = self.ramps_ns(&a).1;
                            self.scaling.retarget_ready(t, 0, quick_ns, r);
                        }
                        FaultCode::None
                    }
                    (State::Homing, _) => {
                        self.abort_homing();
                        FaultCode::None
                    }
                    (State::Armed, _) => {
                        self.state = State::Loaded;
                        self.start_ns = None;
                        FaultCode::None
                    }
                    _ => FaultCode::None,
                }
            }
            CommandCode::ClearFault => {
                if self.state == State::Fault {
                    self.flush();
                    self.state = State::Idle;
                    self.fault = FaultCode::None;
                    self.law.integral = 0.0;
                    // The power stage comes back on at the next tick, with
                    // a new enable check.
                    self.torque_off = false;
                    if self.open_loop.take().is_some() {
                        // From the open-loop hold back to the loop: as at
                        // a release, with a new enable check.
                        self.enabled = false;
                    }
                    FaultCode::None
                } else {
                    FaultCode::WrongState
                }
            }
            CommandCode::FeedHold => match self.state {
                State::Running => {
                    if self.stop_reason != Some(StopReason::Hold) {
                        let t = self.applies_at(c, local_us, data);
                        let r = data.retarget();
                        self.begin_stop_dated(StopReason::Hold, false, t, r, carried_ramp(c));
                    }
                    FaultCode::None
                }
                State::Idle | State::Loaded | State::Armed => {
                    self.hold_latched = true;
                    FaultCode::None
                }
                _ => FaultCode::WrongState,
            },
            CommandCode::Resume => match (self.state, self.active) {
                (State::Running, Some(a)) => {
                    if self.stop_reason == Some(StopReason::Hold) {
                        let t = self.applies_at(c, local_us, data);
                        let (k, r) = (self.override_q16, data.retarget());
                        let stop = self.ramps_ns(&a).0;
                        self.scaling.retarget_ready(t, k, stop, r);
                        self.stop_reason = None;
                    }
                    FaultCode::None
                }
                (State::Idle | State::Loaded | State::Armed, _) => {
                    self.hold_latched = false;
                    FaultCode::None
                }
                _ => FaultCode::WrongState,
            },
            CommandCode::Override => {
                let cap = self.override_cap_permille();
                let pm = c.arg2 as u32;
                let r = if pm == 0 || pm > cap {
                    FaultCode::OverrideAboveCap
                } else {
                    self.override_q16 = q16_from_permille(pm);
                    if let (State::Running, None, Some(a)) =
                        (self.state, self.stop_reason, self.active)
                    {
                        let t = self.applies_at(c, local_us, data);
                        let (k, r) = (self.override_q16, data.retarget());
                        let stop = self.ramps_ns(&a).0;
                        self.scaling.retarget_ready(t, k, stop, r);
                    }
                    FaultCode::None
                };
                self.command_ack(c, r, cap);
                return;
            }
            CommandCode::ConfigCommit => {
                let (r, value) = match data {
                    CommandData::Commit { crc, config } => {
                        match config.as_ref().map(|p| self.lock(&p.lock, local_us)) {
                            Ok(Err((r, index))) => (r, index),
                            _ => (self.commit(config, *crc), *crc),
                        }
                    }
                    _ => (FaultCode::ConfigMismatch, 0),
                };
                self.command_ack(c, r, value);
                return;
            }
            CommandCode::UnlockCeilings => {
                let r = match (self.state, self.active) {
                    (State::Idle, Some(a)) if a.crc == c.arg => {
                        self.maintenance.open(local_us);
                        self.command_ack(c, FaultCode::None, (MAINTENANCE_WINDOW_US / 1000) as u32);
                        return;
                    }
                    (State::Idle, Some(_)) => FaultCode::ConfigMismatch,
                    (State::Idle, None) => FaultCode::NoConfig,
                    _ => FaultCode::WrongState,
                };
                self.command_ack(c, r, 0);
                return;
            }
            CommandCode::Reset => match self.state {
                State::Idle | State::Loaded | State::Armed => {
                    self.flush();
                    self.state = State::Idle;
                    FaultCode::None
                }
                _ => FaultCode::WrongState,
            },
            CommandCode::Home => self.home(local_us),
            CommandCode::ReadConfig => {
                if let CommandData::Values(values) = data {
                    self.readout = Some((*values, 0));
                }
                FaultCode::None
            }
        };
        self.command_ack(c, r, 0);
    }

    /// Sends the next values of a ReadConfig answer while fewer than
    /// [`READOUT_BELOW`] frames wait: a whole answer at once would need an
    /// outbox of [`PARAM_COUNT`] frames and more instructions than a tick has.
    #[cold]
    #[inline(never)]
    pub(super) fn config_readout(&mut self) {
        while self.outbox.len() < READOUT_BELOW {
            let Some((values, next)) = &mut self.readout else {
                return;
            };
            let Some(&v) = values.get(*next as usize) else {
                self.readout = None;
                return;
            };
            let f = config_value_frame(self.node_id, *next, v);
            *next += 1;
            self.send(f);
        }
    }

    /// Host time (ns) a feed command applies at: as the receive side
    /// dated it, else by [`SyncEstimator::apply_ns`] here.
    fn applies_at(&self, c: &Command, local_us: u64, data: &CommandData) -> i64 {
        data.applies_at()
            .unwrap_or_else(|| self.sync.apply_ns(c.arg, local_us))
    }

    /// The configuration's override cap (per mille; 1000 without one).
    pub fn override_cap_permille(&self) -> u32 {
        match self.active {
            Some(_) => (self.cfg.override_cap.clamp(1.0, 32.0) * 1000.0 + 0.5) as u32,
            None => 1000,
        }
    }

    /// The ceiling lock on a host's commit (`ceiling_lock`): one that
    /// widens a locked bound only inside the maintenance window
    /// (`CeilingsLocked` and the bound's index); one judged against
    /// another configuration than the running one (two commits crossing)
    /// is sent again (`ConfigMismatch`). A board's kept one passes.
    fn lock(&self, lock: &LockCheck, local_us: u64) -> Result<(), (FaultCode, u32)> {
        if lock.kept || self.state != State::Idle {
            return Ok(());
        }
        if lock.against != self.config_crc() {
            return Err((FaultCode::ConfigMismatch, 0));
        }
        match lock.widens {
            Some(i) if !self.maintenance.is_open(local_us) => {
                Err((FaultCode::CeilingsLocked, u32::from(i)))
            }
            _ => Ok(()),
        }
    }

    /// Runs a configuration the receive side prepared (Idle only).
    pub(super) fn commit(&mut self, config: &Result<Prepared, FaultCode>, crc: u32) -> FaultCode {
        if self.state != State::Idle {
            return FaultCode::WrongState;
        }
        let p = match config {
            Ok(p) => p,
            Err(code) => return *code,
        };
        self.cfg = p.cfg;
        self.model = p.cfg.robot().native_model();
        self.active = Some(DerivedConfig::new(&p.cfg, crc));
        self.maintenance.close();
        // The override persists, within the new configuration's cap.
        let cap = q16_from_permille(self.override_cap_permille());
        self.override_q16 = self.override_q16.min(cap);
        FaultCode::None
    }

    pub(super) fn arm(&mut self, local_us: u64) -> FaultCode {
        // A refusal, not a fault: nothing has moved, the node stays as it is.
        if !self.homed {
            return FaultCode::NotHomed;
        }
        if self.state != State::Loaded {
            return FaultCode::WrongState;
        }
        let Some(a) = self.active else {
            self.fault_now(FaultCode::NoConfig);
            return FaultCode::NoConfig;
        };
        if !self.sync.is_synced(local_us, a.sync_timeout_us) {
            self.fault_now(FaultCode::NotSynced);
            return FaultCode::NotSynced;
        }
        let Some(front) = self.queue.front().copied() else {
            self.fault_now(FaultCode::EmptyQueue);
            return FaultCode::EmptyQueue;
        };
        if !front.first {
            self.fault_now(FaultCode::EmptyQueue);
            return FaultCode::EmptyQueue;
        }
        let start = front.start_q();
        let own = start[a.axis.min(2)];
        match self.last_q {
            Some(q) if (q - own).abs() <= self.cfg.arm_tolerance => {}
            // A refusal (the node stays Loaded): the host says how far
            // each axis is and what to run.
            _ => return FaultCode::ArmTooFar,
        }
        self.hold = Some(start);
        self.hold_own = own;
        self.state = State::Armed;
        FaultCode::None
    }

    pub(super) fn start(&mut self, arg: u32, local_us: u64) -> FaultCode {
        if self.state != State::Armed {
            return FaultCode::WrongState;
        }
        let Some(now) = self.sync.host_us(local_us) else {
            self.fault_now(FaultCode::NotSynced);
            return FaultCode::NotSynced;
        };
        let d = arg.wrapping_sub(now as u32) as i32 as i64;
        if d < 0 {
            self.fault_now(FaultCode::StartInPast);
            return FaultCode::StartInPast;
        }
        self.start_ns = Some((now + d) * 1000);
        FaultCode::None
    }
}

/// The stop ramp a Stop, QuickStop or FeedHold carries (100 µs units, 0:
/// the full one); `None` when it is dated by the host but carries none
/// (another process's: `triquint stop`, `hold`, the web page), for the
/// drive to size its own for that instant.
fn carried_ramp(c: &Command) -> Option<u16> {
    if c.arg != 0 && c.arg2 == 0 {
        None
    } else {
        Some(c.arg2)
    }
}
