//! What state each drive is in, decoded from what it sends on its own
//! (heartbeats, telemetry): the model behind `triquint status` (and a later
//! web monitor, which reuses this serialised schema). Read-only: nothing
//! here sends a frame.

use nalgebra::Vector3;
use serde::Serialize;
use triquint_shared::Robot;
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::{FaultCode, Msg, PROTOCOL_VERSION, State, decode, flags};

use crate::Received;
use crate::session::nodes::{AXES, NodeView, Nodes};

/// The machine as its drives report it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MachineStatus {
    /// The host's protocol version.
    pub host_protocol_version: u8,
    /// One entry per axis, axis 1 first.
    pub nodes: Vec<NodeStatus>,
    /// Platform position by forward kinematics (mm); null unless every
    /// axis is homed and reported its position.
    pub platform_mm: Option<[f64; 3]>,
    /// Every node sent heartbeats.
    pub all_heard: bool,
}

/// One drive.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NodeStatus {
    pub id: u8,
    /// Axis 1–3.
    pub axis: u8,
    /// It sent a heartbeat while we listened.
    pub heard: bool,
    /// State name (null: silent).
    pub state: Option<&'static str>,
    pub fault: FaultStatus,
    pub homed: bool,
    /// "homed", "homing", "not homed" or "failed" (a homing fault).
    pub homing: &'static str,
    /// Joint position (mm); null unless homed and reported.
    pub joint_position_mm: Option<f64>,
    pub queue_depth: u8,
    pub synced: bool,
    pub configured: bool,
    pub switch_active: bool,
    /// Feed hold: held at rest, slowing to it, or kept for the next plan.
    pub held: bool,
    /// A feed override other than 100 % is set.
    #[serde(rename = "override")]
    pub override_active: bool,
    pub bus_errors: BusErrors,
    /// Protocol version it reports (null: silent).
    pub protocol_version: Option<u8>,
}

/// A fault code with its name and what to do about it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FaultStatus {
    pub code: u8,
    pub name: &'static str,
    pub hint: &'static str,
}

/// The CAN controller's error counters and the segments it rejected.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct BusErrors {
    pub tx: u8,
    pub rx: u8,
    pub rejects: u16,
}

/// What to do about a fault, one line.
pub fn hint(code: FaultCode) -> &'static str {
    use FaultCode::*;
    match code {
        None => "",
        Underrun => "the host did not stream fast enough; clear and upload again",
        LostSync => "time sync lost (host stopped or bus trouble); clear and upload again",
        FollowingError => {
            "the axis could not follow (load, gains, obstruction); check the machine, then clear"
        }
        PeerEmergency => "another drive stopped; see its fault, then clear",
        HostEmergency => "emergency stop from the host; clear when safe",
        ArmTooFar => "the platform is not at the plan's start; run triquint move-to to its start",
        NotSynced => "no time sync yet; upload again",
        NoConfig => "not configured; upload or home configures it",
        ConfigMismatch => "configuration refused; check the robot file and upload again",
        StartInPast => "the Start came late (bus or host load); clear and upload again",
        EmptyQueue => "the plan's first segment is missing; upload again",
        WrongState => "command not allowed in this state; see the state",
        Kinematics => "the pose left the workspace; check the plan, then clear",
        BadCommand => "unknown command; host and drive versions differ?",
        QuickStop => "quick stop (not an error); clear",
        PeerLost => "a drive fell silent or was reset; check it, then clear",
        SoftLimit => "the axis left its soft limits; check the machine, then clear",
        NotHomed => "position unknown: run triquint home",
        HomingTimeout => "homing took too long; check the switch and the axis, clear, home again",
        HomeSwitchActive => {
            "the limit switch is already active: move the axis off it, clear, home again"
        }
        HomeSwitchNeverTriggered => {
            "no switch edge within the maximum travel: check the switch wiring, clear, home again"
        }
        OverrideAboveCap => {
            "override above the plan's cap (see the cap printed); give a smaller percentage"
        }
        WrongDirection => {
            "the axis moved against its torque at enable: check the axis's direction (motor and encoder wiring) in the machine file, then clear"
        }
        WrongScale => {
            "the axis moved too much or too little for its torque at enable: check counts_per_rev, lead and the masses in the machine file, then clear"
        }
        CeilingsLocked => {
            "the configuration raises a ceiling or widens the travel the drive holds: only in maintenance, triquint configure --unlock-ceilings"
        }
    }
}

fn fault_status(raw: u8) -> FaultStatus {
    match FaultCode::from_u8(raw) {
        Some(c) => FaultStatus {
            code: raw,
            name: c.name(),
            hint: hint(c),
        },
        None => FaultStatus {
            code: raw,
            name: "unknown",
            hint: "a code this host does not know: update the host",
        },
    }
}

fn homing_name(v: &NodeView) -> &'static str {
    let homing_fault = matches!(
        FaultCode::from_u8(v.fault),
        Some(
            FaultCode::HomingTimeout
                | FaultCode::HomeSwitchActive
                | FaultCode::HomeSwitchNeverTriggered
        )
    );
    if v.homed {
        "homed"
    } else if v.state == Some(State::Homing) {
        "homing"
    } else if homing_fault {
        "failed"
    } else {
        "not homed"
    }
}

/// Everything heard from the drives of one robot.
#[derive(Clone, Debug, PartialEq)]
pub struct Listener {
    pub nodes: Nodes,
}

impl Listener {
    /// The drives of axes 1–3 on node ids `ids`.
    pub fn new(ids: [u8; AXES]) -> Self {
        Self {
            nodes: Nodes::new(ids),
        }
    }

    /// Takes in one frame (others' and unrelated frames are ignored).
    pub fn take(&mut self, rx: &Received) {
        if rx.own {
            return;
        }
        let Ok((msg, node)) = decode(&rx.frame) else {
            return;
        };
        let Some(i) = self.nodes.index(node) else {
            return;
        };
        let v = &mut self.nodes.0[i];
        match msg {
            Msg::Heartbeat(h) => v.heartbeat(&h, rx.t_us),
            Msg::HeartbeatExt(h) => v.heartbeat_ext(&h, rx.t_us),
            Msg::Telemetry(t) => v.position = Some(t.position),
            Msg::CommandAck(a) => v.last_answer = Some(a.into()),
            _ => {}
        }
    }

    /// Every node sent a heartbeat and its extension.
    pub fn all_heard(&self) -> bool {
        self.nodes
            .all(|v| v.heartbeat_at.is_some() && v.sync_seen_at.is_some())
    }

    /// The status, with the platform position from `robot`'s kinematics.
    pub fn status(&self, robot: &Robot) -> MachineStatus {
        let nodes: Vec<NodeStatus> = self
            .nodes
            .0
            .iter()
            .enumerate()
            .map(|(i, v)| {
                let heard = v.heartbeat_at.is_some();
                NodeStatus {
                    id: v.id,
                    axis: i as u8 + 1,
                    heard,
                    state: v.state.map(State::name),
                    fault: fault_status(v.fault),
                    homed: v.homed,
                    homing: homing_name(v),
                    joint_position_mm: v
                        .position
                        .filter(|_| v.homed && heard)
                        .map(|q| f64::from(q) * 1e3),
                    queue_depth: v.depth,
                    synced: v.sync_ok,
                    configured: v.flags & flags::CONFIGURED != 0,
                    switch_active: v.flags & flags::SWITCH != 0,
                    held: v.flags & flags::HELD != 0,
                    override_active: v.flags & flags::OVERRIDE != 0,
                    bus_errors: BusErrors {
                        tx: v.tx_errors,
                        rx: v.rx_errors,
                        rejects: v.rejects,
                    },
                    protocol_version: heard.then_some(v.version),
                }
            })
            .collect();
        let q: Vec<f64> = nodes
            .iter()
            .filter_map(|n| n.joint_position_mm.map(|x| x * 1e-3))
            .collect();
        let platform_mm = match q.as_slice() {
            [a, b, c] => Pose::from_joints(&robot.model::<f64>(), Vector3::new(*a, *b, *c))
                .ok()
                .map(|p| [p.r.x * 1e3, p.r.y * 1e3, p.r.z * 1e3]),
            _ => None,
        };
        MachineStatus {
            host_protocol_version: PROTOCOL_VERSION,
            all_heard: self.all_heard(),
            nodes,
            platform_mm,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use triquint_shared::protocol::{Heartbeat, HeartbeatExt, Telemetry};

    fn rx(frame: triquint_shared::protocol::Frame) -> Received {
        Received {
            frame,
            t_us: 1,
            own: false,
        }
    }

    #[test]
    fn status_decodes_heartbeats_of_the_configured_ids_only() {
        let mut l = Listener::new([4, 5, 6]);
        let robot = Robot::default();
        let q = Pose::from_cartesian(&robot.model::<f64>(), Vector3::new(0.0, 0.0, 0.6))
            .unwrap()
            .q;
        for (i, id) in [4u8, 5, 6].into_iter().enumerate() {
            l.take(&rx(Heartbeat {
                state: State::Idle as u8,
                fault: if id == 6 {
                    FaultCode::HomeSwitchNeverTriggered as u8
                } else {
                    0
                },
                queue_depth: 0,
                protocol_version: PROTOCOL_VERSION,
                config_crc: 1,
            }
            .to_frame(id)));
            let homed = if id == 6 { 0 } else { flags::HOMED };
            l.take(&rx(HeartbeatExt {
                flags: flags::SYNCED | homed | flags::CONFIGURED,
                ..HeartbeatExt::default()
            }
            .to_frame(id)));
            l.take(&rx(Telemetry {
                position: q[i] as f32,
                velocity: 0.0,
            }
            .to_frame(id)));
        }
        // A heartbeat of another device (node 1) is not ours.
        l.take(&rx(Heartbeat::default().to_frame(1)));
        let s = l.status(&robot);
        assert!(s.all_heard);
        assert_eq!(s.nodes.iter().map(|n| n.id).collect::<Vec<_>>(), [4, 5, 6]);
        assert_eq!(s.nodes[2].homing, "failed");
        assert_eq!(s.nodes[2].fault.name, "HomeSwitchNeverTriggered");
        assert!(!s.nodes[2].fault.hint.is_empty());
        assert_eq!(s.nodes[2].joint_position_mm, None);
        assert!(s.nodes[0].joint_position_mm.is_some());
        // Not all three known: no platform position.
        assert_eq!(s.platform_mm, None);
        // All three homed: the platform by forward kinematics.
        l.take(&rx(HeartbeatExt {
            flags: flags::SYNCED | flags::HOMED,
            ..HeartbeatExt::default()
        }
        .to_frame(6)));
        let p = l.status(&robot).platform_mm.unwrap();
        assert!(
            p[0].abs() < 1e-3 && p[1].abs() < 1e-3 && (p[2] - 600.0).abs() < 1e-3,
            "{p:?}"
        );
    }
}
