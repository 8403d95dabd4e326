//! The upload session on drives whose node ids are not 1, 2, 3 in order
//! (4, 5, 6 and 2, 1, 3), through the `CanPort` seam: scripted drives
//! take the configuration, and one of them ends up with another CRC than
//! the plan's; the read-back must name that drive, compare its values with
//! its own plan configuration, and never panic. A drive whose sync report
//! stops at its commit is the one a Sync timeout names.

use std::collections::VecDeque;

use triquint_link::{CanPort, PortError, Received, Session, SessionOptions, UploadError};
use triquint_shared::plan::Plan;
use triquint_shared::protocol::{
    CommandAck, CommandCode, DriveConfig, Frame, Heartbeat, HeartbeatExt, Msg, PARAM_COUNT,
    PROTOCOL_VERSION, State, config_value_frame, decode, flags,
};

/// One scripted drive: what it was written, and the CRC it reports.
struct Drive {
    id: u8,
    written: [f32; PARAM_COUNT],
    crc: u32,
}

/// Three drives on a fake bus; the clock moves 1 ms a poll. `bad` reports
/// `bad_crc` after its commit, whatever it was written.
struct Bus {
    now: u64,
    drives: Vec<Drive>,
    rx: VecDeque<Received>,
    bad: u8,
    bad_crc: u32,
    /// A drive whose extended heartbeats (its sync status) stop once a
    /// configuration is committed.
    mute: u8,
    committed: bool,
}

impl Bus {
    fn push(&mut self, frame: Frame) {
        self.rx.push_back(Received {
            frame,
            t_us: self.now,
            own: false,
        });
    }
}

impl CanPort for Bus {
    fn now_us(&mut self) -> u64 {
        self.now += 1_000;
        // Every drive's heartbeats, every 10 ms.
        if self.now % 10_000 == 0 {
            let beats: Vec<(u8, u32)> = self.drives.iter().map(|d| (d.id, d.crc)).collect();
            for (id, crc) in beats {
                let h = Heartbeat {
                    state: State::Idle as u8,
                    protocol_version: PROTOCOL_VERSION,
                    config_crc: crc,
                    ..Heartbeat::default()
                };
                self.push(h.to_frame(id));
                if self.committed && id == self.mute {
                    continue;
                }
                let e = HeartbeatExt {
                    flags: flags::SYNCED | flags::HOMED,
                    ..HeartbeatExt::default()
                };
                self.push(e.to_frame(id));
            }
        }
        self.now
    }

    fn send(&mut self, frame: &Frame) -> Result<bool, PortError> {
        let Ok((msg, node)) = decode(frame) else {
            return Ok(true);
        };
        // Its own syncs come back, as SocketCAN's loopback gives them: the
        // session dates each sync by its echo.
        if matches!(msg, Msg::TimeSync(_)) {
            self.rx.push_back(Received {
                frame: *frame,
                t_us: self.now,
                own: true,
            });
        }
        let (bad, bad_crc) = (self.bad, self.bad_crc);
        let mut committed = self.committed;
        let mut out = Vec::new();
        for d in self.drives.iter_mut().filter(|d| node == 0 || node == d.id) {
            match msg {
                Msg::ConfigWrite { index, value } => d.written[index as usize] = value,
                Msg::Command(c) if c.command == CommandCode::ConfigCommit as u8 => {
                    committed = true;
                    d.crc = if d.id == bad { bad_crc } else { c.arg };
                    let a = CommandAck {
                        command: c.command,
                        token: c.token,
                        result: 0,
                        state: State::Idle as u8,
                        value: c.arg,
                    };
                    out.push(a.to_frame(d.id));
                }
                Msg::Command(c) if c.command == CommandCode::ReadConfig as u8 => {
                    for (k, v) in d.written.iter().enumerate() {
                        out.push(config_value_frame(d.id, k as u8, *v));
                    }
                }
                Msg::Command(c) => {
                    let a = CommandAck {
                        command: c.command,
                        token: c.token,
                        result: 0,
                        state: State::Idle as u8,
                        value: 0,
                    };
                    out.push(a.to_frame(d.id));
                }
                _ => {}
            }
        }
        self.committed = committed;
        for f in out {
            self.push(f);
        }
        Ok(true)
    }

    fn recv(&mut self) -> Result<Option<Received>, PortError> {
        Ok(self.rx.pop_front())
    }
}

/// Configurations of axes 1–3 on `ids`, each a little different.
fn configs(ids: [u8; 3]) -> [DriveConfig; 3] {
    let mut k = 0.0;
    ids.map(|id| {
        k += 1.0;
        let mut c = DriveConfig::from_values(&[0.25; PARAM_COUNT]);
        c.node_id = f32::from(id);
        c.axis = k - 1.0;
        c
    })
}

/// Drives `ids` on a bus where `bad` keeps another CRC and `mute` stops
/// reporting its sync at the commit.
fn bus(ids: [u8; 3], bad: u8, mute: u8) -> Bus {
    Bus {
        now: 0,
        drives: ids
            .iter()
            .map(|&id| Drive {
                id,
                written: [0.0; PARAM_COUNT],
                crc: 0,
            })
            .collect(),
        rx: VecDeque::new(),
        bad,
        bad_crc: 0x0BAD_C0DE,
        mute,
        committed: false,
    }
}

/// Polls `s` on `bus` until it fails: the error.
fn error_of(mut s: Session, mut bus: Bus, what: &str) -> UploadError {
    for _ in 0..20_000 {
        match s.poll(&mut bus) {
            Ok(None) => {}
            Ok(Some(_)) => panic!("{what}: no error"),
            Err(e) => return e,
        }
    }
    panic!("{what}: no verdict");
}

/// Configures drives `ids` where `bad` keeps another CRC: the error.
fn configure(ids: [u8; 3], bad: u8) -> UploadError {
    let s = Session::configure(configs(ids), SessionOptions::default());
    error_of(
        s,
        bus(ids, bad, 0),
        &format!("ids {ids:?}, node {bad} differs"),
    )
}

/// Node ids out of order, each with the drive a test singles out and its
/// index.
fn cases() -> impl Iterator<Item = ([u8; 3], u8, usize)> {
    [
        ([4, 5, 6], 5),
        ([4, 5, 6], 6),
        ([2, 1, 3], 2),
        ([2, 1, 3], 1),
    ]
    .into_iter()
    .map(|(ids, id)| (ids, id, ids.iter().position(|&x| x == id).unwrap()))
}

#[test]
fn a_differing_crc_is_read_back_from_the_right_node() {
    for (ids, bad, i) in cases() {
        match configure(ids, bad) {
            // Its values are its plan's: it did not commit them.
            UploadError::ConfigCrc {
                node,
                node_crc,
                plan_crc,
            } => {
                assert_eq!(node, triquint_link::Drive::of(ids, i), "ids {ids:?}");
                assert_eq!(node_crc, 0x0BAD_C0DE);
                assert_eq!(plan_crc, configs(ids)[i].crc());
            }
            e => panic!("ids {ids:?}, node {bad}: {e}"),
        }
    }
}

/// The plan the HIL suite runs.
fn plan() -> Plan {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../testdata/hil/paper-case1.json"
    );
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// A drive that reported itself synced before its commit and nothing of
/// its sync since cannot be synced to this session's time base: the Sync
/// phase's timeout names it, not the first drive.
#[test]
fn a_sync_timeout_names_the_drive_whose_report_predates_the_session() {
    for (ids, mute, i) in cases() {
        let s = Session::new(&plan(), configs(ids), SessionOptions::default()).unwrap();
        match error_of(
            s,
            bus(ids, 0, mute),
            &format!("ids {ids:?}, node {mute} mute"),
        ) {
            UploadError::Timeout { node, what } => {
                assert_eq!(what, "synchronising its clock", "ids {ids:?}");
                assert_eq!(node, triquint_link::Drive::of(ids, i), "ids {ids:?}");
            }
            e => panic!("ids {ids:?}, node {mute}: {e}"),
        }
    }
}
