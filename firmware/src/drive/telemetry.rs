//! The periodic frames: Heartbeat and HeartbeatExt every heartbeat period,
//! Telemetry and TelemetryExt at the telemetry rate, at most one group per tick.

use triquint_shared::protocol::contract::{
    MIN_HEARTBEAT_US, UNCONFIGURED_HEARTBEAT_US, UNCONFIGURED_SYNC_TIMEOUT_US,
};
use triquint_shared::protocol::{
    Heartbeat, HeartbeatExt, PROTOCOL_VERSION, Telemetry, TelemetryExt, flags,
};

use super::Drive;
use crate::scaling::UNIT_Q16;

impl<const Q: usize> Drive<Q> {
    /// HeartbeatExt `flags`.
    fn flags(&self, now_us: u64, sync_timeout_us: u64) -> u8 {
        let bit = |on: bool, b: u8| if on { b } else { 0 };
        bit(self.sync.is_synced(now_us, sync_timeout_us), flags::SYNCED)
            | bit(self.homed, flags::HOMED)
            | bit(self.is_held(), flags::HELD)
            | bit(self.override_q16 != UNIT_Q16, flags::OVERRIDE)
            | bit(self.switch_active, flags::SWITCH)
            | bit(self.active.is_some(), flags::CONFIGURED)
    }

    pub(super) fn periodic(&mut self, now_us: u64) {
        if self.readout.is_some() {
            self.config_readout();
        }
        let (hb_us, tel_us) = match &self.active {
            Some(a) => (a.heartbeat_us.max(MIN_HEARTBEAT_US), a.telemetry_us),
            None => (UNCONFIGURED_HEARTBEAT_US, 0),
        };
        if now_us >= self.next_heartbeat_us {
            self.next_heartbeat_us = now_us + hb_us;
            let hb = Heartbeat {
                state: self.state as u8,
                fault: self.fault as u8,
                queue_depth: self.queue.len() as u8,
                protocol_version: PROTOCOL_VERSION,
                config_crc: self.config_crc(),
            };
            let f = hb.to_frame(self.node_id);
            self.send(f);
            let timeout = self
                .active
                .as_ref()
                .map(|a| a.sync_timeout_us)
                .unwrap_or(UNCONFIGURED_SYNC_TIMEOUT_US);
            let ext = HeartbeatExt {
                next_seq: self.next_seq,
                rejects: self.stats.rejects,
                tx_errors: self.errors.0,
                rx_errors: self.errors.1,
                last_reject: self.stats.last_reject,
                flags: self.flags(now_us, timeout),
            };
            let f = ext.to_frame(self.node_id);
            self.send(f);
            // At most one group of periodic frames per tick (bounds the
            // tick's worst case): telemetry due now goes out next tick.
            return;
        }
        if tel_us > 0 && now_us >= self.next_telemetry_us {
            self.next_telemetry_us = now_us + tel_us;
            let t = Telemetry {
                position: self.stats.q,
                velocity: self.stats.v,
            };
            let f = t.to_frame(self.node_id);
            self.send(f);
            let t = TelemetryExt {
                torque: self.stats.torque,
                following_error: self.stats.following_error,
            };
            let f = t.to_frame(self.node_id);
            self.send(f);
        }
    }
}
