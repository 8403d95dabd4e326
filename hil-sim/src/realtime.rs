//! The virtual machine in real time on a SocketCAN interface: each drive
//! (the real firmware core) on its own socket and its own offset, drifting
//! clock, one plant, all paced to wall time. A listening socket sees every
//! frame on the bus for the run's accounting: bus load (frame bit times at
//! 1 Mbit/s, 5 Mbit/s FD data phase, over wall time), the plan (reassembled
//! from the segment frames) and the common start, for the tracking error.
//!
//! On the flexible plant a run closes a settle window after the plan's end
//! (the machine rings on), with the residual vibration the in-process
//! machine reports (`vibration.rs`), over the same window from the same
//! accelerometer.
//!
//! A tick that starts more than one period late is a missed deadline: the
//! loop counts it and goes on from the current time, never slipping silently.

use std::collections::VecDeque;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, SystemTime};

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_firmware::node::service;
use triquint_shared::machine::Machine;
use triquint_shared::plan::{Segment, eval};
use triquint_shared::protocol::segment::{FLAG_FIRST, FLAG_LAST};
use triquint_shared::protocol::{
    CommandCode, FaultCode, Frame, Msg, SegmentEvent, SegmentRx, State, decode, frame_time_ns,
};

use crate::flex::{FlexError, FlexParams};
use crate::metrics::{Tracking, segment_from_wire, tracking_segments};
use crate::node_port::NodePort;
use crate::plant::PlantConfig;
use crate::plant_model::{PlantKind, PlantModel};
use crate::report::{JsonFault, RunReport};
use crate::sim::{FaultEvent, LocalClock, Sample, SimError, SimNode, SimSwitch, SwitchMode};
use crate::vibration::SETTLE_WINDOW_S;
use triquint_link::socketcan::{SocketCanError, SocketCanPort};

/// What runs, where.
#[derive(Clone, Debug)]
pub struct RealtimeConfig {
    pub iface: String,
    /// Node ids of the drives to run, axis 1 first (1–15); fewer than
    /// three leave the last axes without a drive (braked).
    pub nodes: Vec<u8>,
    /// Power on unhomed, each encoder with an unknown offset from this seed.
    pub unhomed: Option<u64>,
    /// The machine simulated: its robot, switches (heights and homing
    /// direction), encoder scales and motor directions.
    pub machine: Machine,
    /// How each axis's switch behaves.
    pub switches: [SwitchMode; 3],
    pub fd: bool,
    pub rate_hz: f64,
    pub plant: PlantConfig,
    /// Rigid or flexible, and the flexible plant's parameters.
    pub plant_kind: PlantKind,
    pub flex: FlexParams,
    /// Joint positions at power-on (m).
    pub q0: Vector3<f64>,
    pub clock_seed: u64,
    pub max_drift_ppm: f64,
    pub nominal_bps: u64,
    pub data_bps: u64,
}

impl RealtimeConfig {
    pub fn new(iface: &str, machine: Machine, q0: Vector3<f64>) -> Self {
        let flex = FlexParams::for_machine(&machine);
        Self {
            iface: iface.to_string(),
            nodes: vec![1, 2, 3],
            unhomed: None,
            machine,
            switches: [SwitchMode::Working; 3],
            fd: false,
            rate_hz: 1000.0,
            plant: PlantConfig::default(),
            plant_kind: PlantKind::Rigid,
            flex,
            q0,
            clock_seed: 7,
            max_drift_ppm: 200.0,
            nominal_bps: 1_000_000,
            data_bps: 5_000_000,
        }
    }
}

/// Why the real-time machine stopped before it was asked to.
#[derive(Debug, thiserror::Error)]
pub enum RealtimeError {
    #[error(transparent)]
    Bus(#[from] SocketCanError),
    #[error(transparent)]
    Machine(#[from] SimError),
    #[error(transparent)]
    Flex(#[from] FlexError),
}

/// Everything the machine measured.
#[derive(Clone, Debug, Default)]
pub struct RealtimeReport {
    pub runs: Vec<RunReport>,
    pub ticks: u64,
    pub missed_deadlines: u64,
    /// Ticks not run at all (further behind than the catch-up limit).
    pub skipped_ticks: u64,
    pub max_late_us: f64,
    pub wall_time_s: f64,
    /// Every protocol frame seen, and the bus busy fraction over the whole time.
    pub frames: u64,
    pub bus_load: f64,
    /// Frames on the bus that are not protocol frames.
    pub foreign_frames: u64,
    /// The plant's joint positions when the simulator stopped (m), what
    /// the drives' telemetry reports at rest (the web monitor's vcan test).
    pub final_joint_position_m: [f64; 3],
}

/// The run being watched.
#[derive(Default)]
struct Watch {
    since_ns: Option<u64>,
    busy_ns: u64,
    segment_busy_ns: u64,
    frames: u64,
    segment_frames: u64,
    rx: SegmentRx,
    segments: Vec<Segment>,
    start_arg: Option<u32>,
    start_host_ns: Option<i64>,
    running: bool,
    /// The plan's last segment went over the bus.
    saw_last: bool,
    samples: Vec<Sample>,
}

fn is_host_frame(msg: &Msg, node: u8) -> bool {
    match msg {
        Msg::TimeSync(_)
        | Msg::Command(_)
        | Msg::ConfigWrite { .. }
        | Msg::SegmentPart
        | Msg::SegmentPartFd
        | Msg::SegmentCompact
        | Msg::SegmentCompactFd => true,
        Msg::Emergency(_) => node == 0,
        _ => false,
    }
}

impl Watch {
    fn on_frame(&mut self, f: &Frame, t_ns: u64, cfg: &RealtimeConfig) {
        let Ok((msg, node)) = decode(f) else {
            return;
        };
        if self.since_ns.is_none() && is_host_frame(&msg, node) {
            *self = Watch {
                since_ns: Some(t_ns),
                ..Watch::default()
            };
        }
        if self.since_ns.is_none() {
            return;
        }
        let d = frame_time_ns(f, cfg.nominal_bps, cfg.data_bps);
        self.busy_ns += d;
        self.frames += 1;
        match msg {
            Msg::SegmentPart | Msg::SegmentPartFd | Msg::SegmentCompact | Msg::SegmentCompactFd => {
                self.segment_busy_ns += d;
                self.segment_frames += 1;
                if let Some(SegmentEvent::Complete { segment: w, .. }) =
                    self.rx.push(msg.kind(), f.payload())
                {
                    if w.flags & FLAG_FIRST != 0 {
                        self.segments.clear();
                    }
                    self.saw_last |= w.flags & FLAG_LAST != 0;
                    // Retransmissions arrive again: keep the first copy.
                    if w.seq as usize == self.segments.len() {
                        let t0 = self.segments.last().map_or(0.0, |s| s.t0_s + s.duration_s);
                        self.segments.push(segment_from_wire(&w, t0));
                    }
                }
            }
            Msg::Command(c) if c.command == CommandCode::Start as u8 => {
                self.start_arg = Some(c.arg);
            }
            _ => {}
        }
    }
}

/// A run that has closed, waiting (on the flexible plant) for its settle
/// window to pass before it is reported.
struct Closed {
    run: RunReport,
    /// The plan's end in plant time (s) and the joints' end position (m).
    settle: Option<(f64, Vector3<f64>)>,
}

impl Closed {
    /// Plant time (s) from which it can be reported.
    fn ready_at(&self) -> f64 {
        self.settle
            .map_or(0.0, |(end_s, _)| end_s + SETTLE_WINDOW_S)
    }

    /// The run, with the residual vibration over the window so far (all of
    /// it unless the machine was stopped first).
    fn report(mut self, plant: &PlantModel) -> Result<RunReport, SimError> {
        if let (Some((end_s, q)), Some(f)) = (self.settle, plant.flexible()) {
            let window = SETTLE_WINDOW_S.min(f.time_s() - end_s);
            if window > 0.0 {
                self.run.vibration = f
                    .residual(end_s, window, q)
                    .map_err(|source| SimError::Plant { t_s: end_s, source })?;
            }
        }
        Ok(self.run)
    }
}

/// Host time (ns) of a wrapping 32-bit µs host time, unwrapped near `est_ns`.
fn unwrap_host_us(arg: u32, est_ns: i64) -> i64 {
    let est_us = est_ns.div_euclid(1000);
    (est_us + arg.wrapping_sub(est_us as u32) as i32 as i64) * 1000
}

/// The least lateness logged (µs).
const LOGGED_LATE_US: f64 = 100_000.0;

/// Ticks later than this are not caught up but skipped (and counted).
const MAX_CATCH_UP_NS: u64 = 5_000_000_000;

/// Opens the machine's socket on `cfg.iface`.
pub fn open(cfg: &RealtimeConfig) -> Result<SocketCanPort, SocketCanError> {
    // One socket for the three drives, receiving its own frames too: they
    // reach the other drives (as on a bus) and the run's accounting, with one
    // read pass per tick (system calls are dear in an emulated guest).
    SocketCanPort::open(&cfg.iface, cfg.fd, true, SystemTime::now())
}

/// Runs the machine on the socket of [`open`] until `stop` is set (or it
/// fails); `report` holds what was measured either way.
pub fn run(
    mut port: SocketCanPort,
    cfg: &RealtimeConfig,
    stop: &AtomicBool,
    report: &mut RealtimeReport,
) -> Result<(), RealtimeError> {
    let mut rng = ChaCha8Rng::seed_from_u64(cfg.clock_seed);
    let mut offsets = cfg.unhomed.map(ChaCha8Rng::seed_from_u64);
    let mut nodes: Vec<SimNode> = cfg
        .nodes
        .iter()
        .enumerate()
        .map(|(axis, &id)| {
            let clock = LocalClock {
                offset_ns: rng.random_range(0..10_000_000_000i64),
                drift: rng.random_range(-1.0..1.0) * cfg.max_drift_ppm * 1e-6,
            };
            // An encoder's count at power-on says nothing of the position:
            // up to ±10 m of counts.
            let offset = offsets
                .as_mut()
                .map(|r| r.random_range(-130_000_000..130_000_000i64));
            let mut n = SimNode::on_axis(id, axis, clock, offset);
            n.switch = Some(SimSwitch::new(
                cfg.machine.axes[axis.min(2)].switch_height,
                cfg.machine.homing.direction,
                cfg.switches[axis.min(2)],
            ));
            n
        })
        .collect();
    let tick_ns = (1e9 / cfg.rate_hz).round().max(1000.0) as u64;
    // One RK4 step per tick (a quarter of the in-process machine's steps):
    // stable and accurate for this plant at 1 kHz, and affordable in real time.
    let mut plant_cfg = cfg.plant.clone();
    plant_cfg.max_step_s = plant_cfg.max_step_s.max(tick_ns as f64 * 1e-9);
    let mut plant = PlantModel::new(
        cfg.plant_kind,
        &cfg.machine.robot,
        plant_cfg,
        &cfg.flex,
        cfg.q0,
    )?;
    let mut watch = Watch::default();
    let start_ns = port.now_ns();
    let mut plant_ns = start_ns;
    let mut next = start_ns + tick_ns;
    let mut all_busy_ns = 0u64;
    let mut rx = Vec::new();
    let mut closed: VecDeque<Closed> = VecDeque::new();
    let mut logged_late_us = LOGGED_LATE_US;
    let result = 'run: loop {
        if stop.load(Ordering::Relaxed) {
            break 'run Ok(());
        }
        let now = port.now_ns();
        if now < next {
            std::thread::sleep(Duration::from_nanos(next - now));
            continue;
        }
        // Late ticks run back to back at their own times (the controller and
        // the plant stay a consistent discrete-time system); each one that
        // starts a whole period late is a missed deadline.
        let late = now - next;
        let late_us = late as f64 * 1e-3;
        // Lateness past 0.1 s is logged when it happens, each time it
        // doubles, to be set beside the other processes' logs (the suite
        // reruns a failed test whose simulator was that late); a line a
        // tick would itself make the loop later.
        if late_us > logged_late_us {
            eprintln!(
                "triquint-sim: tick {:.3} s after start ran {:.0} ms late",
                (next - start_ns) as f64 * 1e-9,
                late_us * 1e-3
            );
            logged_late_us = 2.0 * late_us;
        }
        report.max_late_us = report.max_late_us.max(late_us);
        if late >= tick_ns {
            report.missed_deadlines += 1;
        }
        if late > MAX_CATCH_UP_NS {
            // Too far behind (the host stalled us): skip, with the plant
            // frozen over the gap rather than integrated under one held torque.
            let skip = late / tick_ns;
            report.missed_deadlines += skip;
            report.skipped_ticks += skip;
            next += skip * tick_ns;
            plant_ns = next;
        }
        let t = next;
        next += tick_ns;
        report.ticks += 1;

        rx.clear();
        loop {
            let r = match port.recv() {
                Ok(Some(r)) => r,
                Ok(None) => break,
                Err(e) => break 'run Err(e.into()),
            };
            all_busy_ns += frame_time_ns(&r.frame, cfg.nominal_bps, cfg.data_bps);
            report.frames += 1;
            let was_idle = watch.since_ns.is_none();
            watch.on_frame(&r.frame, r.t_ns, cfg);
            if was_idle && watch.since_ns.is_some() {
                for n in &mut nodes {
                    n.peak_torque = 0.0;
                    n.started_ns = None;
                    n.faults.clear();
                    n.max_stop_jerk = 0.0;
                    n.executed.clear();
                    n.states.clear();
                }
            }
            rx.push(r);
        }
        if let Err(source) = plant.advance(t.saturating_sub(plant_ns) as f64 * 1e-9) {
            break 'run Err(SimError::Plant {
                t_s: (t - start_ns) as f64 * 1e-9,
                source,
            }
            .into());
        }
        plant_ns = t;
        for n in nodes.iter_mut() {
            let axis = n.axis;
            let local = n.clock.local_us(t);
            let mut p = NodePort {
                port: &mut port,
                rx: &rx,
                next: 0,
                clock: n.clock,
                tick_ns: t,
                error: None,
            };
            service(&mut n.node, &mut p);
            let cpm = cfg.machine.counts_per_metre(axis);
            let tau = n.control_tick(local, plant.q()[axis], cpm, t);
            plant.set_torque(axis, cfg.machine.axes[axis].direction * tau);
            n.note_fault(t);
            service(&mut n.node, &mut p);
            if let Some(e) = p.error {
                break 'run Err(e.into());
            }
        }
        plant.set_braked(nodes.len() < 3 || !nodes.iter().all(SimNode::enabled));
        closed.extend(observe(&mut watch, &mut nodes, &plant, t));
        let now_s = plant.flexible().map_or(0.0, |f| f.time_s());
        while closed.front().is_some_and(|c| c.ready_at() <= now_s) {
            if let Some(c) = closed.pop_front() {
                match c.report(&plant) {
                    Ok(r) => report.runs.push(r),
                    Err(e) => break 'run Err(e.into()),
                }
            }
        }
        // Between runs the accelerometer's record is not needed: kept, it
        // would grow for as long as the machine runs.
        if let (PlantModel::Flexible(f), None, true) =
            (&mut plant, watch.since_ns, closed.is_empty())
        {
            f.accel.clear();
        }
    };
    let end = port.now_ns();
    report.wall_time_s = (end - start_ns) as f64 * 1e-9;
    report.bus_load = all_busy_ns as f64 / (end - start_ns).max(1) as f64;
    report.foreign_frames = port.foreign;
    let q = plant.q();
    report.final_joint_position_m = [q[0], q[1], q[2]];
    // Runs still in their settle window are reported with what it holds.
    for c in closed {
        report.runs.push(c.report(&plant)?);
    }
    // A run cut short by the stop is reported as it stands (not completed).
    if watch.since_ns.is_some() && watch.running {
        let r = finish(&watch, &nodes, end, false);
        report.runs.push(r);
    }
    result
}

/// Samples the machine during a run and closes the run when every drive is at rest.
fn observe(
    watch: &mut Watch,
    nodes: &mut [SimNode],
    plant: &PlantModel,
    now: u64,
) -> Option<Closed> {
    watch.since_ns?;
    let first = nodes.first()?;
    let local = first.clock.local_us(now);
    let host_ns = first.node.host_ns(local);
    if let (Some(arg), Some(h), None) = (watch.start_arg, host_ns, watch.start_host_ns) {
        watch.start_host_ns = Some(unwrap_host_us(arg, h));
    }
    let states: Vec<State> = nodes.iter().map(|n| n.node.state()).collect();
    if states
        .iter()
        .any(|s| matches!(s, State::Running | State::Stopping))
    {
        watch.running = true;
    }
    if watch.running
        && let Some(h) = host_ns
    {
        let q = plant.q();
        watch
            .samples
            .push(Sample::of(h.max(0) as u64, [q[0], q[1], q[2]], nodes));
    }
    let at_rest = states
        .iter()
        .all(|s| matches!(s, State::Idle | State::Fault));
    let refused = nodes.iter().any(|n| !n.faults.is_empty()) && at_rest;
    if (watch.running && at_rest) || refused {
        let completed = states.iter().all(|s| *s == State::Idle) && nodes.len() == 3;
        let run = finish(watch, nodes, now, completed);
        // The plan's end in plant time: the drives stopped at most a tick
        // after it, by their own clocks.
        let settle = match (plant.flexible(), watch.start_host_ns, host_ns) {
            (Some(f), Some(start), Some(h)) if watch.running => {
                eval::at(&watch.segments, run.plan_time_s).map(|end| {
                    let since_end_s = (h - start) as f64 * 1e-9 - run.plan_time_s;
                    (f.time_s() - since_end_s.max(0.0), Vector3::from(end.q))
                })
            }
            _ => None,
        };
        *watch = Watch::default();
        return Some(Closed { run, settle });
    }
    None
}

fn finish(watch: &Watch, nodes: &[SimNode], now: u64, completed: bool) -> RunReport {
    let since = watch.since_ns.unwrap_or(now);
    let window = now.saturating_sub(since).max(1) as f64;
    let plan_time_s = eval::duration(&watch.segments);
    let tracking = match watch.start_host_ns {
        Some(s) if !watch.segments.is_empty() => tracking_segments(
            &watch.segments,
            plan_time_s,
            s.max(0) as u64,
            &watch.samples,
        ),
        _ => Tracking::default(),
    };
    let started: Vec<u64> = nodes.iter().filter_map(|n| n.started_ns).collect();
    let t0 = started.iter().min().copied().unwrap_or(since);
    let skew = started.iter().max().map_or(0, |m| m - t0);
    let mut peak = [0.0; 3];
    for n in nodes {
        peak[n.axis] = n.peak_torque as f64;
    }
    let mut faults: Vec<FaultEvent> = nodes
        .iter()
        .flat_map(|n| n.faults.iter())
        .copied()
        .collect();
    faults.sort_by_key(|f| f.t_ns);
    let no_fault = faults.iter().all(|f| f.code == FaultCode::None);
    let (stop_s, stopped_within_buffer) = stop_figures(watch, nodes);
    RunReport {
        completed: completed && no_fault && started.len() == nodes.len(),
        faults: faults
            .iter()
            .map(|f| JsonFault::new(f, (f.t_ns as f64 - t0 as f64) * 1e-9))
            .collect(),
        rms_error_m: tracking.rms_error_m,
        max_error_m: tracking.max_error_m,
        tracking_samples: tracking.samples,
        peak_torque_nm: peak,
        bus_load: watch.busy_ns as f64 / window,
        segment_bus_load: watch.segment_busy_ns as f64 / window,
        frames: watch.frames,
        segment_frames: watch.segment_frames,
        segments: watch.segments.len(),
        plan_time_s,
        duration_s: window * 1e-9,
        start_skew_us: skew as f64 * 1e-3,
        executed: RunReport::executed_by_node(
            nodes
                .iter()
                .flat_map(|n| n.executed.iter().map(|e| (n.node.node_id(), e.1, e.2))),
        ),
        stop_s,
        stopped_within_buffer,
        stop_ramp_s: nodes
            .iter()
            .filter_map(|n| n.node.config())
            .map(|c| c.stop_time as f64)
            .fold(0.0, f64::max),
        override_cap: RunReport::override_cap_of(nodes.iter().filter_map(|n| n.node.config())),
        max_stop_jerk: [0, 1, 2].map(|a| {
            nodes
                .iter()
                .find(|n| n.axis == a)
                .map_or(0.0, |n| n.max_stop_jerk as f64)
        }),
        fault_run: None,
        vibration: None,
    }
}

/// Time from the first fault to the last running axis at rest, and whether
/// every faulted axis stayed inside its buffered plan time.
fn stop_figures(watch: &Watch, nodes: &[SimNode]) -> (Option<f64>, bool) {
    let n_seg = watch.segments.len();
    let within = nodes.iter().all(|n| {
        let had_last = watch.saw_last && n.executed.iter().any(|e| e.1 as usize + 1 == n_seg);
        n.node.state() != State::Fault || n.node.plan_ns() <= n.node.buffered_end_ns() || had_last
    });
    let Some(first) = nodes.iter().flat_map(|n| &n.faults).map(|f| f.t_ns).min() else {
        return (None, within);
    };
    let mut rest = first;
    for n in nodes.iter().filter(|n| n.started_ns.is_some()) {
        match n
            .states
            .iter()
            .find(|(t, s)| *t >= first && *s == State::Fault)
        {
            Some((t, _)) => rest = rest.max(*t),
            // Still moving (or finished without stopping): no stop time.
            None if n.node.state() != State::Idle => return (None, within),
            None => {}
        }
    }
    (Some((rest - first) as f64 * 1e-9), within)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn start_time_unwraps_around_the_estimate() {
        // Estimate just after a 32-bit µs wrap, start just before it.
        let est = (1i64 << 32) * 1000 + 5_000_000;
        let arg = u32::MAX - 1000;
        assert_eq!(unwrap_host_us(arg, est), ((1i64 << 32) - 1001) * 1000);
        assert_eq!(unwrap_host_us(123_456, 100_000_000), 123_456_000);
    }

    #[test]
    fn watch_rebuilds_the_plan_from_segment_frames() {
        use triquint_shared::protocol::WireSegment;
        use triquint_shared::protocol::segment::FLAG_LAST;
        let plan = crate::testplan::paper_case1().unwrap();
        let cfg = RealtimeConfig::new("vcan0", Machine::default(), Vector3::zeros());
        let n = plan.segments.len();
        for fd in [false, true] {
            let mut w = Watch::default();
            let mut frames = 0;
            for round in 0..2 {
                // The second round repeats every segment (retransmissions).
                let _ = round;
                let mut chain = triquint_shared::protocol::compact::Chain::default();
                let wire: Vec<WireSegment> = plan
                    .segments
                    .iter()
                    .enumerate()
                    .map(|(i, s)| {
                        let flags = if i == 0 { FLAG_FIRST } else { 0 }
                            | if i + 1 == n { FLAG_LAST } else { 0 };
                        WireSegment::from_quintic(i as u16, &s.quintic(), flags).unwrap()
                    })
                    .collect();
                for (i, ws) in wire.iter().enumerate() {
                    for f in chain.next(ws, wire.get(i + 1)).frames(fd) {
                        w.on_frame(&f, 1000, &cfg);
                        frames += 1;
                    }
                }
            }
            // The repeated first segment restarts the plan; the rest follow.
            assert_eq!(w.segments.len(), n);
            let end = w.segments.last().map(|s| s.t0_s + s.duration_s).unwrap();
            assert!((end - plan.total_time_s).abs() < 1e-9);
            assert_eq!(w.segment_frames, frames);
            // Compact after the first segment.
            assert!(frames < 2 * n as u64 * if fd { 2 } else { 20 });
        }
    }

    /// A closed run on the flexible plant waits out its settle window and
    /// then carries the residual over it; cut short, over what it holds;
    /// on the rigid plant, none.
    #[test]
    fn a_run_on_the_flexible_plant_reports_its_settle_window() {
        use triquint_shared::kinematics::Pose;
        let machine = Machine::default();
        let model = machine.robot.model::<f64>();
        let q = Pose::from_cartesian(&model, Vector3::new(0.0, 0.0, 0.6))
            .unwrap()
            .q;
        let flex = FlexParams::for_machine(&machine);
        let mut plant = PlantModel::new(
            PlantKind::Flexible,
            &machine.robot,
            PlantConfig::default(),
            &flex,
            q,
        )
        .unwrap();
        let closed = |end_s: f64| Closed {
            run: RunReport::default(),
            settle: Some((end_s, q)),
        };
        assert_eq!(closed(0.1).ready_at(), 0.1 + SETTLE_WINDOW_S);
        plant.advance(0.1 + SETTLE_WINDOW_S).unwrap();
        let v = closed(0.1).report(&plant).unwrap().vibration.unwrap();
        assert_eq!(v.window_s, SETTLE_WINDOW_S);
        let full = v.samples;
        assert!(
            full as f64 >= SETTLE_WINDOW_S * flex.accelerometer_hz,
            "{full}"
        );
        // Stopped 0.2 s into the window: the report says so.
        let v = closed(0.4).report(&plant).unwrap().vibration.unwrap();
        assert!((v.window_s - 0.2).abs() < 1e-9, "{v:?}");
        assert!(v.samples < full / 2, "{v:?}");
        // Nothing of the window yet: no figure.
        assert!(closed(0.7).report(&plant).unwrap().vibration.is_none());
        let rigid = PlantModel::new(
            PlantKind::Rigid,
            &machine.robot,
            PlantConfig::default(),
            &flex,
            q,
        )
        .unwrap();
        assert!(closed(0.0).report(&rigid).unwrap().vibration.is_none());
    }
}
