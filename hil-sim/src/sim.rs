//! The virtual machine: three firmware nodes with their own drifting clocks,
//! the bus, and the plant, advanced together in true time.

use nalgebra::Vector3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use triquint_firmware::{Encoder, LimitSwitch, MotorOutput, NoSwitch, Node, RxFrame};
use triquint_shared::Robot;
use triquint_shared::kinematics::KinematicsError;
use triquint_shared::protocol::config::HomingSettings;
use triquint_shared::protocol::{FaultCode, Frame, State};

use crate::bus::{Bus, BusConfig, Delivery};
use crate::faults::{BABBLER, FaultInjector, FaultWindow};
use crate::flex::{FlexError, FlexParams};
use crate::plant::PlantConfig;
use crate::plant_model::{PlantKind, PlantModel};

/// Everything configurable about the virtual hardware.
#[derive(Clone, Debug)]
pub struct SimConfig {
    pub fd: bool,
    /// Control tick rate of the nodes (Hz); must match the drives' configuration.
    pub rate_hz: f64,
    pub plant: PlantConfig,
    pub bus: BusConfig,
    /// Seed of the clock offsets and drifts.
    pub clock_seed: u64,
    /// Clock drift bound (ppm): each node draws a drift in ±this.
    pub max_drift_ppm: f64,
    /// Encoder counts per metre of each axis, signed (the drives are
    /// configured with the same values).
    pub counts_per_metre: [f64; 3],
    /// The sign of each motor's torque on its slider (+1 lifts): the
    /// machine's wiring, which the drives' `direction` must match.
    pub motor_direction: [f64; 3],
    /// Which axes have a holding brake (the drives are configured with the
    /// same). A drive whose power stage is off holds the machine still
    /// where its axis has a brake, and before it was first enabled (the
    /// machine at rest from power-on); otherwise its axis is free under
    /// gravity.
    pub brake: [bool; 3],
    /// An external torque on one axis's motor (a push, a collision):
    /// (axis, from, until true time in ns, N·m lifting).
    pub push: Option<(usize, u64, u64, f64)>,
    /// Communication service interval of the nodes (µs of local time).
    pub comm_interval_us: u64,
    /// Record a sample every this many control ticks of node 1 (0 = every tick).
    pub record_every: u32,
    /// Frames a node's controller holds for transmission (mailboxes).
    pub tx_mailboxes: usize,
}

impl Default for SimConfig {
    fn default() -> Self {
        Self {
            fd: false,
            rate_hz: 1000.0,
            plant: PlantConfig::default(),
            bus: BusConfig::default(),
            clock_seed: 7,
            max_drift_ppm: 200.0,
            counts_per_metre: [131_072.0 / 0.010; 3],
            motor_direction: [1.0; 3],
            brake: [false; 3],
            push: None,
            comm_interval_us: 50,
            record_every: 1,
            tx_mailboxes: 3,
        }
    }
}

/// A node's local clock: local = offset + (1 + drift)·true.
#[derive(Clone, Copy, Debug)]
pub struct LocalClock {
    pub offset_ns: i64,
    pub drift: f64,
}

impl LocalClock {
    pub fn local_ns(&self, t_ns: u64) -> i64 {
        self.offset_ns + (t_ns as f64 * (1.0 + self.drift)).round() as i64
    }
    pub fn local_us(&self, t_ns: u64) -> u64 {
        (self.local_ns(t_ns).max(0) / 1000) as u64
    }
    /// True time (ns) at which the local clock reads `local_us`.
    pub fn true_ns(&self, local_us: u64) -> u64 {
        let l = local_us as f64 * 1000.0 - self.offset_ns as f64;
        (l / (1.0 + self.drift)).ceil().max(0.0) as u64
    }
}

/// One recorded instant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    pub t_ns: u64,
    pub q: [f64; 3],
    pub torque: [f32; 3],
    pub reference: [f32; 3],
    pub state: [State; 3],
}

/// A fault as seen on the node (first tick in the faulted state or stop).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FaultEvent {
    pub node: u8,
    pub code: FaultCode,
    pub t_ns: u64,
}

/// How a guideway's limit switch behaves.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SwitchMode {
    /// Active at and beyond its height (in the homing direction).
    #[default]
    Working,
    /// Always active (a shorted or stuck switch).
    Stuck,
    /// Never active (a broken wire).
    Dead,
}

/// A guideway's limit switch at `height` (m, true joint position), active
/// at and beyond it in `direction`; its edge latches the encoder count of
/// the exact crossing, as a hardware capture input does.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SimSwitch {
    pub height: f64,
    pub direction: f64,
    pub mode: SwitchMode,
    active: bool,
    edge: Option<i64>,
}

impl SimSwitch {
    pub fn new(height: f64, direction: f64, mode: SwitchMode) -> Self {
        Self {
            height,
            direction,
            mode,
            active: false,
            edge: None,
        }
    }

    fn is_on(&self, q: f64) -> bool {
        match self.mode {
            SwitchMode::Working => (q - self.height) * self.direction >= 0.0,
            SwitchMode::Stuck => true,
            SwitchMode::Dead => false,
        }
    }

    /// The axis at `q` (m): an edge since the last update latches `edge_counts`,
    /// the count at the switch height.
    fn update(&mut self, q: f64, edge_counts: i64) {
        let on = self.is_on(q);
        if on && !self.active && self.mode == SwitchMode::Working {
            self.edge = Some(edge_counts);
        }
        self.active = on;
    }
}

impl LimitSwitch for SimSwitch {
    fn active(&mut self) -> bool {
        self.active
    }
    fn take_edge(&mut self) -> Option<i64> {
        self.edge.take()
    }
}

/// One simulated drive.
#[derive(Clone)]
pub struct SimNode {
    pub node: Node,
    /// The axis (0–2) it drives.
    pub axis: usize,
    /// Encoder count at joint position 0 (0: homed at power-on).
    pub enc_offset: i64,
    /// Its guideway's limit switch (none: no switch).
    pub switch: Option<SimSwitch>,
    pub clock: LocalClock,
    next_tick_us: u64,
    next_comm_us: u64,
    pending_torque: f64,
    enabled: bool,
    /// The power stage has been on since power-on (or the last reset).
    ever_enabled: bool,
    motor: SimMotor,
    last_fault: FaultCode,
    /// True time of the first Running tick.
    pub started_ns: Option<u64>,
    pub faults: Vec<FaultEvent>,
    pub peak_torque: f32,
    /// Largest |joint jerk| of the reference while Stopping (m/s³).
    pub max_stop_jerk: f32,
    /// Segments the node took its reference from, in order: (true time of
    /// the first tick, sequence number, CRC-32 of the body it received).
    pub executed: Vec<(u64, u16, u32)>,
    /// State changes seen at control ticks: (true time, new state).
    pub states: Vec<(u64, State)>,
    /// True time an Emergency frame of another station first reached this node.
    pub emergency_rx_ns: Option<u64>,
}

struct SimEncoder(i64);
impl Encoder for SimEncoder {
    fn read_counts(&mut self) -> i64 {
        self.0
    }
}

#[derive(Clone, Default)]
struct SimMotor {
    torque: f32,
    enabled: bool,
}
impl MotorOutput for SimMotor {
    fn set_torque(&mut self, t: f32) {
        self.torque = t;
    }
    fn enable(&mut self, on: bool) {
        self.enabled = on;
    }
}

impl SimNode {
    /// Drive `id` (1–3) of axis `id − 1` with its own clock, unconfigured,
    /// power stage off, homed, no switch.
    pub fn new(id: u8, clock: LocalClock) -> Self {
        Self::on_axis(id, id.saturating_sub(1).min(2) as usize, clock, None)
    }

    /// Drive `id` of `axis`; `unhomed`: powered on with this encoder
    /// offset (counts), unhomed.
    pub fn on_axis(id: u8, axis: usize, clock: LocalClock, unhomed: Option<i64>) -> Self {
        Self {
            node: match unhomed {
                Some(_) => Node::new_unhomed(id),
                None => Node::new(id),
            },
            axis: axis.min(2),
            enc_offset: unhomed.unwrap_or(0),
            switch: None,
            clock,
            next_tick_us: 0,
            next_comm_us: 0,
            pending_torque: 0.0,
            enabled: false,
            ever_enabled: false,
            motor: SimMotor::default(),
            last_fault: FaultCode::None,
            started_ns: None,
            faults: Vec::new(),
            peak_torque: 0.0,
            max_stop_jerk: 0.0,
            executed: Vec::new(),
            states: Vec::new(),
            emergency_rx_ns: None,
        }
    }

    /// Is the power stage on (brake released)?
    pub fn enabled(&self) -> bool {
        self.enabled
    }

    /// One control tick at local time `local_us` with the axis at `q` (m),
    /// at true time `t_ns`. Returns the motor torque acting from now on: the
    /// previous tick's command (one-tick actuation delay), 0 when disabled.
    pub fn control_tick(&mut self, local_us: u64, q: f64, counts_per_metre: f64, t_ns: u64) -> f64 {
        let counts = (q * counts_per_metre).floor() as i64 + self.enc_offset;
        let mut motor = std::mem::take(&mut self.motor);
        match self.switch.as_mut() {
            Some(sw) => {
                let edge = (sw.height * counts_per_metre).floor() as i64 + self.enc_offset;
                sw.update(q, edge);
                self.node
                    .tick_with_switch(local_us, &mut SimEncoder(counts), &mut motor, sw);
            }
            None => self.node.tick_with_switch(
                local_us,
                &mut SimEncoder(counts),
                &mut motor,
                &mut NoSwitch,
            ),
        }
        let acting = if self.enabled {
            self.pending_torque
        } else {
            0.0
        };
        self.pending_torque = motor.torque as f64;
        self.enabled = motor.enabled;
        self.ever_enabled |= motor.enabled;
        self.peak_torque = self.peak_torque.max(motor.torque.abs());
        self.motor = motor;
        if self.node.state() == State::Stopping {
            self.max_stop_jerk = self
                .max_stop_jerk
                .max(self.node.stats.reference.qddd.amax());
        }
        if self.started_ns.is_none() && self.node.state() == State::Running {
            self.started_ns = Some(t_ns);
        }
        let st = self.node.state();
        if self.states.last().is_none_or(|x| x.1 != st) {
            self.states.push((t_ns, st));
        }
        if let Some((seq, crc)) = self.node.executing()
            && self
                .executed
                .last()
                .is_none_or(|x| (x.1, x.2) != (seq, crc))
        {
            self.executed.push((t_ns, seq, crc));
        }
        acting
    }

    /// Records a change of the fault code at true time `t_ns`.
    pub fn note_fault(&mut self, t_ns: u64) {
        let f = self.node.fault();
        if f != self.last_fault {
            if f != FaultCode::None {
                self.faults.push(FaultEvent {
                    node: self.node.node_id(),
                    code: f,
                    t_ns,
                });
            }
            self.last_fault = f;
        }
    }
}

impl Sample {
    /// The machine at true time `t_ns`: joint positions `q` and every drive's state.
    pub fn of(t_ns: u64, q: [f64; 3], nodes: &[SimNode]) -> Self {
        let k = |i: usize| nodes.get(i).map(|n| &n.node);
        Sample {
            t_ns,
            q,
            torque: [0, 1, 2].map(|i| k(i).map_or(0.0, |n| n.stats.torque)),
            // Each node's reference of its own axis.
            reference: [0, 1, 2].map(|i| k(i).map_or(0.0, |n| n.stats.reference.q[i])),
            state: [0, 1, 2].map(|i| k(i).map_or(State::Idle, |n| n.state())),
        }
    }
}

/// An error of the virtual machine itself.
#[derive(Debug, thiserror::Error)]
pub enum SimError {
    #[error("the plant left the workspace at t = {t_s:.4} s: {source}")]
    Plant {
        t_s: f64,
        #[source]
        source: KinematicsError,
    },
}

/// The virtual machine (a clone runs on from the same instant).
#[derive(Clone)]
pub struct Sim {
    pub cfg: SimConfig,
    pub bus: Bus,
    pub plant: PlantModel,
    pub nodes: Vec<SimNode>,
    t_ns: u64,
    plant_t_ns: u64,
    tick_us: u64,
    tick_count: u64,
    pub samples: Vec<Sample>,
    /// Fault injection between the bus and the stations (see [`Sim::with_faults`]).
    pub faults: Option<FaultInjector>,
}

impl Sim {
    /// A machine whose bus passes every frame through a seeded fault layer;
    /// the bus gets a fifth station for a babbling node.
    pub fn with_faults(
        robot: &Robot,
        q0: Vector3<f64>,
        cfg: SimConfig,
        windows: Vec<FaultWindow>,
        seed: u64,
    ) -> Self {
        let mut sim = Self::new(robot, q0, cfg);
        sim.bus = Bus::new(sim.cfg.bus.clone(), BABBLER + 1);
        sim.faults = Some(FaultInjector::new(windows, seed, BABBLER + 1));
        sim
    }

    /// A machine on the flexible plant (`flex`), otherwise as [`Sim::new`].
    pub fn flexible(
        robot: &Robot,
        q0: Vector3<f64>,
        cfg: SimConfig,
        flex: &FlexParams,
    ) -> Result<Self, FlexError> {
        let plant = PlantModel::new(PlantKind::Flexible, robot, cfg.plant.clone(), flex, q0)?;
        let mut sim = Self::new(robot, q0, cfg);
        sim.plant = plant;
        Ok(sim)
    }

    /// Every guideway gets its limit switch (`homing`'s heights and
    /// direction, `modes`), and every drive powers on again unhomed with a
    /// seeded encoder offset (±10 m of counts): homing is needed, for real.
    pub fn power_on_unhomed(&mut self, seed: u64, homing: &HomingSettings, modes: [SwitchMode; 3]) {
        let mut rng = ChaCha8Rng::seed_from_u64(seed);
        for (i, n) in self.nodes.iter_mut().enumerate() {
            let id = n.node.node_id();
            n.node = Node::new_unhomed(id);
            n.enc_offset = rng.random_range(-130_000_000..130_000_000i64);
            n.switch = Some(SimSwitch::new(
                homing.switch_height[i],
                homing.direction,
                modes[i],
            ));
        }
    }

    /// Power-cycles node `i` (0–2): it restarts Idle, unconfigured, motor off,
    /// with its clock running on.
    pub fn reset_node(&mut self, i: usize) {
        let n = &mut self.nodes[i];
        n.node = Node::new(i as u8 + 1);
        n.pending_torque = 0.0;
        n.enabled = false;
        n.ever_enabled = false;
        n.motor = SimMotor::default();
    }

    /// Next delivery from the bus to `station`, through the fault layer.
    fn next_delivery(&mut self, station: usize) -> Option<Delivery> {
        let Some(inj) = self.faults.as_mut() else {
            return self.bus.receive(station);
        };
        while let Some(d) = self.bus.receive(station) {
            inj.deliver(station, d, self.t_ns);
        }
        inj.ready(station, self.t_ns)
    }

    /// A machine at joint position `q0`, nodes unconfigured, brakes on.
    pub fn new(robot: &Robot, q0: Vector3<f64>, cfg: SimConfig) -> Self {
        let mut rng = ChaCha8Rng::seed_from_u64(cfg.clock_seed);
        let tick_us = (1e6 / cfg.rate_hz).round().max(1.0) as u64;
        let nodes = (1..=3u8)
            .map(|id| {
                SimNode::new(
                    id,
                    LocalClock {
                        offset_ns: rng.random_range(0..10_000_000_000i64),
                        drift: rng.random_range(-1.0..1.0) * cfg.max_drift_ppm * 1e-6,
                    },
                )
            })
            .collect::<Vec<_>>();
        let mut sim = Self {
            bus: Bus::new(cfg.bus.clone(), 4),
            plant: PlantModel::Rigid(crate::plant::Plant::new(robot, cfg.plant.clone(), q0)),
            nodes,
            t_ns: 0,
            plant_t_ns: 0,
            tick_us,
            tick_count: 0,
            samples: Vec::new(),
            faults: None,
            cfg,
        };
        for n in &mut sim.nodes {
            let l = n.clock.local_us(0);
            n.next_tick_us = (l / tick_us + 1) * tick_us;
            n.next_comm_us = l + 1;
        }
        sim
    }

    /// True time (ns); the host's clock.
    pub fn now_ns(&self) -> u64 {
        self.t_ns
    }

    /// The host queues a frame now.
    pub fn host_send(&mut self, frame: Frame) {
        self.bus.advance(self.t_ns);
        self.bus.send(0, frame, self.t_ns);
    }

    /// Frames the host has queued that are not on the bus yet.
    pub fn host_pending(&self) -> usize {
        self.bus.pending(0)
    }

    /// Next frame delivered to the host (including its own, as transmit confirmations).
    pub fn host_receive(&mut self) -> Option<Delivery> {
        self.next_delivery(0)
    }

    /// Records a change of node `i`'s fault code at the current time.
    fn note_fault(&mut self, i: usize) {
        let t_ns = self.t_ns;
        self.nodes[i].note_fault(t_ns);
    }

    fn service(&mut self, i: usize) {
        self.service_frames(i);
        self.note_fault(i);
    }

    fn service_frames(&mut self, i: usize) {
        let station = i + 1;
        while let Some(d) = self.next_delivery(station) {
            let n = &mut self.nodes[i];
            if (0x010..=0x01F).contains(&d.frame.id) && d.from != station {
                n.emergency_rx_ns.get_or_insert(d.t_ns);
            }
            let rx = RxFrame {
                frame: d.frame,
                timestamp_us: n.clock.local_us(d.t_ns),
            };
            n.node.on_frame(&rx);
        }
        let bus_off = self
            .faults
            .as_ref()
            .is_some_and(|f| f.bus_off(station, self.t_ns));
        let n = &mut self.nodes[i];
        // The controller's error counters, as the fault layer's confinement keeps them.
        if let Some(f) = self.faults.as_mut() {
            n.node
                .set_error_counters(f.error_counters(station, self.t_ns).registers());
        }
        while !bus_off && self.bus.pending(station) < self.cfg.tx_mailboxes {
            let Some(f) = n.node.pop_tx() else { break };
            self.bus.send(station, f, self.t_ns);
        }
    }

    fn control_tick(&mut self, i: usize, local_us: u64) {
        let cpm = self.cfg.counts_per_metre[i];
        let t_ns = self.t_ns;
        let tau = self.nodes[i].control_tick(local_us, self.plant.q()[i], cpm, t_ns);
        let push = match self.cfg.push {
            Some((axis, from, until, t)) if axis == i && (from..until).contains(&t_ns) => t,
            _ => 0.0,
        };
        self.plant
            .set_torque(i, self.cfg.motor_direction[i] * tau + push);
        let brake = self.cfg.brake;
        let held = self
            .nodes
            .iter()
            .any(|n| !n.enabled && (brake[n.axis] || !n.ever_enabled));
        self.plant.set_braked(held);
        if i == 0 {
            self.tick_count += 1;
            let every = self.cfg.record_every.max(1) as u64;
            if self.tick_count % every == 0 {
                let q = self.plant.q();
                self.samples
                    .push(Sample::of(t_ns, [q[0], q[1], q[2]], &self.nodes));
            }
        }
    }

    /// Runs the machine up to true time `until_ns`.
    pub fn run_until(&mut self, until_ns: u64) -> Result<(), SimError> {
        loop {
            // Next event: a node's control tick or communication service.
            let mut next: Option<(u64, usize, bool)> = None;
            for (i, n) in self.nodes.iter().enumerate() {
                let t_tick = n.clock.true_ns(n.next_tick_us);
                let t_comm = n.clock.true_ns(n.next_comm_us);
                for (t, is_tick) in [(t_tick, true), (t_comm, false)] {
                    if next.is_none_or(|x| t < x.0) {
                        next = Some((t, i, is_tick));
                    }
                }
            }
            let Some((t, i, is_tick)) = next else {
                return Ok(());
            };
            let t_stop = t.min(until_ns).max(self.t_ns);
            self.t_ns = t_stop;
            if let Some(f) = self.faults.as_mut() {
                f.feed_babbler(&mut self.bus, self.t_ns);
            }
            self.bus.advance(self.t_ns);
            if t > until_ns {
                return Ok(());
            }
            if is_tick {
                // The plant only matters at control ticks: integrate lazily.
                let dt = self.t_ns.saturating_sub(self.plant_t_ns) as f64 * 1e-9;
                self.plant.advance(dt).map_err(|source| SimError::Plant {
                    t_s: self.t_ns as f64 * 1e-9,
                    source,
                })?;
                self.plant_t_ns = self.t_ns;
                let local = self.nodes[i].next_tick_us;
                self.service(i);
                self.control_tick(i, local);
                self.note_fault(i);
                self.service(i);
                self.nodes[i].next_tick_us += self.tick_us;
            } else {
                self.service(i);
                self.nodes[i].next_comm_us += self.cfg.comm_interval_us;
            }
        }
    }

    /// Every fault event of every node, in time order.
    pub fn faults(&self) -> Vec<FaultEvent> {
        let mut v: Vec<FaultEvent> = self.nodes.iter().flat_map(|n| n.faults.clone()).collect();
        v.sort_by_key(|f| f.t_ns);
        v
    }
}
