//! The machine as the page shows it: the `status` model of the drives
//! ([`Listener`]) plus what only a monitor keeps: heartbeat ages, staleness,
//! the traces, the platform's trail, the planned path from the segments
//! seen on the bus, bus statistics. Fed one frame at a time by the frame
//! source; read by the server under one mutex.

use std::collections::VecDeque;

use nalgebra::Vector3;
use serde_json::{Value as Json, json};
use triquint_link::{Listener, Received};
use triquint_shared::kinematics::Pose;
use triquint_shared::protocol::{Msg, SegmentEvent, SegmentRx, WireSegment, decode, flags};
use triquint_shared::{Model as Kinematics, Robot};

use super::stats::BusStats;
use super::traces::{KEEP_US, Traces};

/// A node is stale after this long without a heartbeat (five periods).
pub const STALE_US: u64 = 500_000;
/// Trail points at most this often (bus time).
const TRAIL_STEP_US: u64 = 20_000;
/// Points per planned segment.
const PATH_POINTS: usize = 8;
/// At most this many planned points are kept.
const MAX_PATH: usize = 20_000;

/// Everything the monitor knows.
pub struct Model {
    pub listener: Listener,
    kinematics: Kinematics<f64>,
    robot: Robot,
    /// Where the frames come from, for the page ("vcan0", "replay of x.log").
    pub source: String,
    pub replay: bool,
    pub traces: Traces,
    /// Platform positions (mm) with their bus time.
    pub trail: VecDeque<(u64, [f64; 3])>,
    /// The planned platform path (mm) from the segments seen, and a counter
    /// that changes with it.
    pub planned: Vec<[f64; 3]>,
    pub planned_version: u64,
    pub segments_seen: u64,
    pub stats: BusStats,
    parts: SegmentRx,
    /// Bus time (µs) of the latest frame.
    pub now_us: u64,
    /// Latest torque command (N·m) and following error (m) per axis.
    ext: [Option<(f32, f32)>; 3],
    /// Frames taken in.
    pub frames: u64,
}

impl Model {
    pub fn new(ids: [u8; 3], robot: Robot, source: String, replay: bool) -> Self {
        Self {
            listener: Listener::new(ids),
            kinematics: robot.model::<f64>(),
            robot,
            source,
            replay,
            traces: Traces::default(),
            trail: VecDeque::new(),
            planned: Vec::new(),
            planned_version: 0,
            segments_seen: 0,
            stats: BusStats::default(),
            parts: SegmentRx::default(),
            now_us: 0,
            ext: [None; 3],
            frames: 0,
        }
    }

    /// Moves the clock on (bus time) without a frame.
    pub fn tick(&mut self, now_us: u64) {
        self.now_us = self.now_us.max(now_us);
    }

    fn platform(&self, q_m: [f64; 3]) -> Option<[f64; 3]> {
        Pose::from_joints(&self.kinematics, Vector3::from(q_m))
            .ok()
            .map(|p| [p.r.x * 1e3, p.r.y * 1e3, p.r.z * 1e3])
    }

    fn segment(&mut self, w: &WireSegment) {
        self.segments_seen += 1;
        if w.seq == 0 {
            self.planned.clear();
        }
        let b = w.normalised_f64();
        for k in 0..=PATH_POINTS {
            if k == 0 && !self.planned.is_empty() {
                continue;
            }
            let tau = k as f64 / PATH_POINTS as f64;
            let q = b.map(|c| c.iter().rev().fold(0.0, |acc, x| acc * tau + x));
            if let Some(p) = self.platform(q)
                && self.planned.len() < MAX_PATH
            {
                self.planned.push(p);
            }
        }
        self.planned_version += 1;
    }

    /// Takes in one frame heard at bus time `rx.t_us`.
    pub fn take(&mut self, rx: &Received) {
        self.frames += 1;
        self.tick(rx.t_us);
        let t = rx.t_us;
        let decoded = decode(&rx.frame).ok();
        self.stats.take(
            t,
            &rx.frame,
            decoded.as_ref().map(|(m, _)| m.kind().def().name),
        );
        self.listener.take(rx);
        let Some((msg, node)) = decoded else {
            return;
        };
        match msg {
            Msg::SegmentPart | Msg::SegmentPartFd | Msg::SegmentCompact | Msg::SegmentCompactFd => {
                if let Some(SegmentEvent::Complete { segment, .. }) =
                    self.parts.push(msg.kind(), rx.frame.payload())
                {
                    self.segment(&segment);
                }
            }
            Msg::Telemetry(tm) => {
                if let Some(i) = self.listener.nodes.index(node) {
                    self.traces.position(i, t, tm.position);
                    self.trail_point(t);
                }
            }
            Msg::TelemetryExt(e) => {
                if let Some(i) = self.listener.nodes.index(node) {
                    self.traces.ext(i, t, e.following_error, e.torque);
                    self.ext[i] = Some((e.torque, e.following_error));
                }
            }
            _ => {}
        }
    }

    fn trail_point(&mut self, t: u64) {
        if self
            .trail
            .back()
            .is_some_and(|&(s, _)| s + TRAIL_STEP_US > t)
        {
            return;
        }
        let n = &self.listener.nodes.0;
        let (Some(a), Some(b), Some(c)) = (n[0].position, n[1].position, n[2].position) else {
            return;
        };
        if let Some(p) = self.platform([a, b, c].map(f64::from)) {
            self.trail.push_back((t, p));
        }
        while self.trail.front().is_some_and(|&(s, _)| s + KEEP_US < t) {
            self.trail.pop_front();
        }
    }

    /// The state in `triquint status --json`'s schema, each node with what
    /// the monitor adds (held, override, heartbeat age, stale, latest
    /// torque and following error), plus the bus, the latest trace samples
    /// and the platform.
    pub fn state_json(&self) -> Json {
        let status = self.listener.status(&self.robot);
        let mut v = serde_json::to_value(&status).unwrap_or_else(|_| json!({}));
        if let Some(nodes) = v.get_mut("nodes").and_then(Json::as_array_mut) {
            for (i, n) in nodes.iter_mut().enumerate() {
                let view = &self.listener.nodes.0[i];
                let age = view
                    .heartbeat_at
                    .map(|t| self.now_us.saturating_sub(t) as f64 * 1e-6);
                let ext = self.ext[i];
                if let Some(o) = n.as_object_mut() {
                    o.insert("held".into(), json!(view.flags & flags::HELD != 0));
                    o.insert("override".into(), json!(view.flags & flags::OVERRIDE != 0));
                    o.insert("heartbeat_age_s".into(), json!(age));
                    o.insert(
                        "stale".into(),
                        json!(age.is_none_or(|a| a > STALE_US as f64 * 1e-6)),
                    );
                    o.insert("torque_nm".into(), json!(ext.map(|e| e.0)));
                    o.insert(
                        "following_error_um".into(),
                        json!(ext.map(|e| f64::from(e.1) * 1e6)),
                    );
                    o.insert(
                        "position_raw_mm".into(),
                        json!(view.position.map(|q| f64::from(q) * 1e3)),
                    );
                }
            }
        }
        if let Some(o) = v.as_object_mut() {
            o.insert("time_s".into(), json!(self.now_us as f64 * 1e-6));
            o.insert("source".into(), json!(self.source));
            o.insert("replay".into(), json!(self.replay));
            o.insert("frames".into(), json!(self.frames));
            o.insert("bus".into(), json!(self.stats.report(self.now_us)));
            o.insert("segments_seen".into(), json!(self.segments_seen));
            o.insert("planned_version".into(), json!(self.planned_version));
            o.insert("trail_mm".into(), json!(self.trail.back().map(|&(_, p)| p)));
            let latest = self.traces.latest();
            o.insert(
                "latest".into(),
                json!({
                    "position_mm": latest[0],
                    "following_error_um": latest[1],
                    "torque_nm": latest[2],
                }),
            );
        }
        v
    }

    /// Trail points newer than `t_us`: `[[t_s, x, y, z], …]` (mm).
    pub fn trail_since(&self, t_us: Option<u64>) -> Vec<[f64; 4]> {
        self.trail
            .iter()
            .filter(|&&(t, _)| t_us.is_none_or(|c| t > c))
            .map(|&(t, p)| [t as f64 * 1e-6, p[0], p[1], p[2]])
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use triquint_shared::protocol::{Heartbeat, HeartbeatExt, State, Telemetry, TelemetryExt};

    fn rx(frame: triquint_shared::protocol::Frame, t_us: u64) -> Received {
        Received {
            frame,
            t_us,
            own: false,
        }
    }

    #[test]
    fn heartbeats_telemetry_and_staleness() {
        let robot = Robot::default();
        let q = Pose::from_cartesian(&robot.model::<f64>(), Vector3::new(0.0, 0.0, 0.6))
            .unwrap()
            .q;
        let mut m = Model::new([1, 2, 3], robot, "test".into(), true);
        for id in 1..=3u8 {
            m.take(&rx(
                Heartbeat {
                    state: State::Running as u8,
                    protocol_version: 2,
                    ..Heartbeat::default()
                }
                .to_frame(id),
                1000,
            ));
            m.take(&rx(
                HeartbeatExt {
                    flags: flags::SYNCED | flags::HOMED | flags::HELD,
                    ..HeartbeatExt::default()
                }
                .to_frame(id),
                1000,
            ));
            m.take(&rx(
                Telemetry {
                    position: q[usize::from(id - 1)] as f32,
                    velocity: 0.0,
                }
                .to_frame(id),
                2000,
            ));
            m.take(&rx(
                TelemetryExt {
                    torque: 1.5,
                    following_error: 2e-6,
                }
                .to_frame(id),
                2000,
            ));
        }
        let s = m.state_json();
        assert_eq!(s["nodes"][0]["state"], "Running");
        assert_eq!(s["nodes"][2]["held"], true);
        assert_eq!(s["nodes"][1]["stale"], false);
        assert!((s["nodes"][1]["following_error_um"].as_f64().unwrap() - 2.0).abs() < 1e-3);
        let p = s["platform_mm"].as_array().unwrap();
        assert!((p[2].as_f64().unwrap() - 600.0).abs() < 1e-2, "{p:?}");
        assert_eq!(m.trail.len(), 1);
        assert_eq!(m.stats.total, 12);
        m.tick(1000 + STALE_US + 1);
        assert_eq!(m.state_json()["nodes"][0]["stale"], true);
    }
}
