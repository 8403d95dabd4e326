//! Drive configuration: the parameters a node needs to compute the
//! feedforward, close its loop and check segments. Declared once here; each is
//! written with a ConfigWrite frame (byte 0 = parameter index, a DBC
//! multiplexor; bytes 1–4 = f32 value) and activated by ConfigCommit with the
//! CRC-32 of the whole set, which every heartbeat then reports.

use super::crc::Crc32;
use super::wire::{Addr, FieldDef, MessageDef, WireType, spec_text};
use crate::machine::Ceilings;
use crate::params::RobotParams;
use crate::{Limits, Robot};

/// One configuration parameter.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamDef {
    pub index: u8,
    pub name: &'static str,
    pub unit: &'static str,
    pub doc: &'static str,
}

macro_rules! config_params {
    ($( $(#[doc = $doc:literal])* $idx:literal $name:ident [$unit:literal] ),* $(,)?) => {
        /// A node's complete configuration, in SI units, as the f32 values on the wire.
        #[derive(Clone, Copy, Debug, PartialEq, Default)]
        pub struct DriveConfig { $( $(#[doc = $doc])* pub $name: f32, )* }

        /// Every parameter, in index order.
        pub const PARAMS: &[ParamDef] = &[ $( ParamDef {
            index: $idx, name: stringify!($name), unit: $unit, doc: spec_text!($($doc),*)
        } ),* ];

        impl DriveConfig {
            /// Values in index order.
            pub fn to_values(&self) -> [f32; PARAM_COUNT] {
                [ $( self.$name ),* ]
            }
            /// From values in index order.
            pub fn from_values(v: &[f32; PARAM_COUNT]) -> Self {
                let mut c = Self::default();
                $( c.$name = v[$idx]; )*
                c
            }
        }
    };
}

config_params! {
    /// Which row of the inverse dynamics this node drives (0, 1, 2 = node − 1).
    0 axis [""],
    /// s: platform circumradius.
    1 platform_radius ["m"],
    /// S: base circumradius.
    2 base_radius ["m"],
    /// l: strut length.
    3 strut_length ["m"],
    /// d: slider offset toward the centre.
    4 slider_offset ["m"],
    /// m_p: platform mass.
    5 platform_mass ["kg"],
    /// Payload on the platform.
    6 payload_mass ["kg"],
    /// m_i: strut mass.
    7 strut_mass ["kg"],
    /// m_qi: slider mass.
    8 slider_mass ["kg"],
    /// I_M: motor rotor inertia.
    9 motor_inertia ["kg.m2"],
    /// I_C: coupling inertia.
    10 coupling_inertia ["kg.m2"],
    /// I_L: leadscrew inertia.
    11 leadscrew_inertia ["kg.m2"],
    /// p: leadscrew lead.
    12 lead ["m"],
    /// g: gravity.
    13 gravity ["m/s2"],
    /// Joint velocity limit (segments are checked against it).
    14 max_velocity ["m/s"],
    /// Joint acceleration limit.
    15 max_acceleration ["m/s2"],
    /// Joint jerk limit.
    16 max_jerk ["m/s3"],
    /// Motor torque limit; the command is clamped to it.
    17 max_torque ["N.m"],
    /// Proportional gain (torque per metre of position error).
    18 kp ["N.m/m"],
    /// Integral gain.
    19 ki ["N.m/(m.s)"],
    /// Derivative gain (torque per m/s of velocity error).
    20 kd ["N.m.s/m"],
    /// Clamp of the integral term.
    21 integral_limit ["N.m"],
    /// +1 if positive motor torque lifts the slider, −1 if it lowers it.
    22 direction [""],
    /// Encoder counts per metre of slider travel (signed: the encoder's direction).
    23 counts_per_metre ["1/m"],
    /// Following-error bound that stops the machine.
    24 following_error_max ["m"],
    /// Arm is refused further than this from the plan start.
    25 arm_tolerance ["m"],
    /// Stop ramp length T_s of the time-scaling's transitions (stop, feed hold/resume, override); a stop from σ takes T_s·max(√σ, σ).
    26 stop_time ["s"],
    /// Stop ramp length of a quick stop.
    27 quick_stop_time ["s"],
    /// Extra buffered time required beyond the stop's path length before underrun.
    28 underrun_margin ["s"],
    /// Time without a sync after which the node stops (LostSync).
    29 sync_timeout ["s"],
    /// Control tick rate (1000–10000).
    30 control_rate ["Hz"],
    /// Telemetry rate (0 = off).
    31 telemetry_rate ["Hz"],
    /// Heartbeat period.
    32 heartbeat_period ["s"],
    /// 1 = inverse-dynamics feedforward on, 0 = feedback only.
    33 feedforward [""],
    /// Cut-off of the first-order velocity filter.
    34 velocity_filter ["Hz"],
    /// Identified Coulomb friction of the slider (feedforward; 0 = none).
    35 friction_coulomb ["N"],
    /// Identified viscous friction of the slider (feedforward).
    36 friction_viscous ["N.s/m"],
    /// Node id (1–15) the drive answers to; a board keeps it in flash and uses it from its next start.
    37 node_id [""],
    /// Motor torque constant Kt: the current loop's q-axis reference is torque / Kt.
    38 torque_constant ["N.m/A"],
    /// Soft limit of this axis's joint position, low end: segments beyond it are rejected, a measured position beyond it stops the machine.
    39 soft_limit_min ["m"],
    /// Soft limit of this axis's joint position, high end.
    40 soft_limit_max ["m"],
    /// Homing: cruise speed toward the switch (and of the back-off).
    41 homing_velocity ["m/s"],
    /// Homing: acceleration limit.
    42 homing_acceleration ["m/s2"],
    /// Homing: jerk limit.
    43 homing_jerk ["m/s3"],
    /// Homing: +1 seeks the switch upward (increasing joint position), −1 downward.
    44 homing_direction [""],
    /// Homing: joint position of the switch edge; the axis zero is set from it.
    45 switch_height ["m"],
    /// Homing: distance moved back off the switch after its edge.
    46 homing_backoff ["m"],
    /// Homing: longest travel toward the switch (HomeSwitchNeverTriggered beyond).
    47 homing_max_travel ["m"],
    /// Homing: longest time from Home to homed (HomingTimeout beyond).
    48 homing_timeout ["s"],
    /// Homing: following-error bound while the pose is unknown (FollowingError beyond).
    49 homing_following_error_max ["m"],
    /// Node id of the drive of axis 1 (peer supervision listens to these three only).
    50 axis_node_1 [""],
    /// Node id of the drive of axis 2.
    51 axis_node_2 [""],
    /// Node id of the drive of axis 3.
    52 axis_node_3 [""],
    /// Largest feed override σ (1 = 100 %) at which the plan, and a hold begun there, stay within the limits; Override above it is refused.
    53 override_cap [""],
    /// 1 = the axis has a holding brake, applied whenever the power stage is off; 0 = none (a fault reaction then removes torque only where the fault reaction table allows it).
    54 brake [""],
    /// The machine's velocity ceiling for every joint (its `[ceilings]`, not the plan's): the drive refuses a segment, an override cap or a stop ramp that would exceed it, and a `max_velocity` above it.
    55 ceiling_velocity ["m/s"],
    /// The machine's acceleration ceiling for every joint.
    56 ceiling_acceleration ["m/s2"],
    /// The machine's jerk ceiling for every joint; a stop ramp is held to a multiple of it (docs/protocol.md, "Ceilings").
    57 ceiling_jerk ["m/s3"],
    /// The machine's torque ceiling (the lowest of `[ceilings] torque` and Kt × current limit): `max_torque`, the command's clamp, may not exceed it.
    58 ceiling_torque ["N.m"],
}

/// Number of configuration parameters.
pub const PARAM_COUNT: usize = 59;

/// ConfigWrite: host → node n, one parameter per frame.
pub const CONFIG_WRITE: MessageDef = MessageDef {
    name: "ConfigWrite",
    addr: Addr::ToNode(0x040),
    len: 5,
    sender: "host",
    period: "on upload",
    doc: spec_text!(" One configuration parameter (byte 0 = index, a multiplexor)."),
    mux: Some("index"),
    fd: false,
    fields: &CONFIG_FIELDS,
};

/// ConfigValue: node n → host, the answer to ReadConfig, one parameter per frame.
pub const CONFIG_VALUE: MessageDef = MessageDef {
    name: "ConfigValue",
    addr: Addr::FromNode(0x1C0),
    len: 5,
    sender: "node",
    period: "on ReadConfig",
    doc: spec_text!(" One parameter of the written configuration (byte 0 = index, a multiplexor)."),
    mux: Some("index"),
    fd: false,
    fields: &CONFIG_FIELDS,
};

const CONFIG_FIELDS: [FieldDef; 2] = [
    FieldDef {
        name: "index",
        offset: 0,
        ty: WireType::U8,
        scale: 1.0,
        unit: "",
        doc: spec_text!(" Parameter index (multiplexor)."),
        values: None,
    },
    FieldDef {
        name: "value",
        offset: 1,
        ty: WireType::F32,
        scale: 1.0,
        unit: "",
        doc: spec_text!(" Value in the parameter's unit."),
        values: None,
    },
];

/// Payload of a ConfigWrite/ConfigValue frame.
pub fn encode_param(index: u8, value: f32) -> [u8; 5] {
    let v = value.to_le_bytes();
    [index, v[0], v[1], v[2], v[3]]
}

/// Decodes a ConfigWrite/ConfigValue payload.
pub fn decode_param(data: &[u8]) -> Option<(u8, f32)> {
    if data.len() < 5 {
        return None;
    }
    Some((
        data[0],
        f32::from_le_bytes([data[1], data[2], data[3], data[4]]),
    ))
}

/// CRC-32 of a configuration: over (index u8, value f32 LE) for every parameter in index order.
pub fn config_crc(values: &[f32; PARAM_COUNT]) -> u32 {
    let mut c = Crc32::new();
    for (i, v) in values.iter().enumerate() {
        c.update(&encode_param(i as u8, *v));
    }
    c.finish()
}

/// A configuration value that a drive cannot run with.
#[derive(Clone, Copy, Debug, PartialEq, thiserror::Error)]
#[error("configuration parameter `{name}` = {value} is invalid ({rule})")]
pub struct ConfigError {
    pub name: &'static str,
    pub value: f32,
    pub rule: &'static str,
}

/// Smoothstep S(u) = 10u³ − 15u⁴ + 6u⁵ bounds used by the stop time-scaling.
pub const SMOOTHSTEP_MAX_D1: f64 = 1.875;
/// The largest feed-override cap a drive accepts (σ; `override_cap` range 1–32).
pub const OVERRIDE_CAP_MAX: f64 = 32.0;
/// max |S''(u)| = 10/√3.
pub const SMOOTHSTEP_MAX_D2: f64 = 5.773_502_691_896_258;

/// Settings of a drive that are not in the plan (machine and tuning).
#[derive(Clone, Debug, PartialEq)]
pub struct DriveSettings {
    /// Closed-loop bandwidth (Hz) the PID gains are placed at (triple pole).
    pub bandwidth_hz: f64,
    pub direction: [f64; 3],
    pub counts_per_metre: [f64; 3],
    pub following_error_max: f64,
    pub arm_tolerance: f64,
    pub underrun_margin: f64,
    pub sync_timeout: f64,
    pub control_rate: f64,
    pub telemetry_rate: f64,
    pub heartbeat_period: f64,
    pub feedforward: bool,
    pub velocity_filter: f64,
    /// Identified friction (feedforward): Coulomb (N) and viscous (N·s/m).
    pub friction_coulomb: f64,
    pub friction_viscous: f64,
    /// Motor torque constant Kt of each axis (N·m/A).
    pub torque_constant: [f64; 3],
    /// Soft limits [low, high] of each axis's joint position (m): the
    /// guideway travel the drives enforce.
    pub soft_limits: [[f64; 2]; 3],
    /// Node id of the drive of each axis (1–15, distinct).
    pub node_ids: [u8; 3],
    /// Which axes have a holding brake (the fault reactions, firmware `reaction`).
    pub brake: [bool; 3],
    pub homing: HomingSettings,
    /// The machine's ceilings (torque already lowered to the weakest
    /// axis's Kt × current limit): the drives hold them whatever a plan says.
    pub ceilings: Ceilings,
    /// Largest feed override σ (the machine file's `drive.max_override`):
    /// the override cap is the plan's, never above it.
    pub max_override: f64,
}

/// How the drives home (the robot file's `[homing]` table).
#[derive(Clone, Debug, PartialEq)]
pub struct HomingSettings {
    pub velocity: f64,
    pub acceleration: f64,
    pub jerk: f64,
    /// +1: the switches are above the sliders' travel, −1: below.
    pub direction: f64,
    /// Joint position of each axis's switch edge (m).
    pub switch_height: [f64; 3],
    pub backoff: f64,
    pub max_travel: f64,
    pub timeout: f64,
    pub following_error_max: f64,
    /// Host side (`triquint home`): once one axis is at its switch, how
    /// much further another may travel without reaching its own before
    /// the host stops every drive (m): bounds the platform's sideways push.
    pub max_skew: f64,
}

impl Default for HomingSettings {
    fn default() -> Self {
        // Switches 10 mm above the highest slider position of the paper's
        // workspace (0.08–0.41 m): from any pose at most 0.34 m at
        // 25 mm/s, about 14 s; the travel bound a little beyond that.
        Self {
            velocity: 0.025,
            acceleration: 0.25,
            jerk: 2.5,
            direction: 1.0,
            switch_height: [0.42; 3],
            backoff: 0.005,
            max_travel: 0.4,
            timeout: 30.0,
            following_error_max: 2.0e-3,
            max_skew: 0.36,
        }
    }
}

/// The loop bandwidth every plan runs with (Hz). Not tuned per plan.
pub const DEFAULT_BANDWIDTH_HZ: f64 = 10.0;

/// Inertia of one axis seen at the motor (kg m²): rotor plus the slider, half
/// a strut and a third of the platform reflected through the screw.
pub fn axis_inertia(robot: &Robot) -> f64 {
    let k = robot.lead / (2.0 * core::f64::consts::PI);
    let m = robot.slider_mass
        + 0.5 * robot.strut_mass
        + (robot.platform_mass + robot.payload_mass) / 3.0;
    robot.rotor_inertia() + m * k * k
}

impl DriveConfig {
    /// The configuration of node `axis + 1` for a plan's robot and limits,
    /// stop times from the plan's maxima, and gains from the settings' bandwidth:
    /// a triple closed-loop pole at ω (Kp = 3Jω², Ki = Jω³, Kd = 3Jω, in N·m per metre).
    pub fn new(
        robot: &Robot,
        limits: &Limits,
        axis: usize,
        s: &DriveSettings,
        stop_time_s: f64,
        quick_stop_time_s: f64,
    ) -> Self {
        let a = axis.min(2);
        let w = 2.0 * core::f64::consts::PI * s.bandwidth_hz;
        let ratio = 2.0 * core::f64::consts::PI / robot.lead;
        let j = axis_inertia(robot) * ratio;
        let f = |x: f64| x as f32;
        let c = &s.ceilings;
        Self {
            axis: a as f32,
            platform_radius: f(robot.platform_radius),
            base_radius: f(robot.base_radius),
            strut_length: f(robot.strut_length),
            slider_offset: f(robot.slider_offset),
            platform_mass: f(robot.platform_mass),
            payload_mass: f(robot.payload_mass),
            strut_mass: f(robot.strut_mass),
            slider_mass: f(robot.slider_mass),
            motor_inertia: f(robot.motor_inertia),
            coupling_inertia: f(robot.coupling_inertia),
            leadscrew_inertia: f(robot.leadscrew_inertia),
            lead: f(robot.lead),
            gravity: f(robot.gravity),
            // The run's limits, never above the machine's ceilings.
            max_velocity: f(limits.velocity.min(c.velocity)),
            max_acceleration: f(limits.acceleration.min(c.acceleration)),
            max_jerk: f(limits.jerk.min(c.jerk)),
            max_torque: f(limits.torque.min(c.torque)),
            kp: f(3.0 * j * w * w),
            ki: f(j * w * w * w),
            kd: f(3.0 * j * w),
            integral_limit: f(0.5 * limits.torque),
            direction: f(s.direction[a]),
            counts_per_metre: f(s.counts_per_metre[a]),
            following_error_max: f(s.following_error_max),
            arm_tolerance: f(s.arm_tolerance),
            stop_time: f(stop_time_s),
            quick_stop_time: f(quick_stop_time_s),
            underrun_margin: f(s.underrun_margin),
            sync_timeout: f(s.sync_timeout),
            control_rate: f(s.control_rate),
            telemetry_rate: f(s.telemetry_rate),
            heartbeat_period: f(s.heartbeat_period),
            feedforward: if s.feedforward { 1.0 } else { 0.0 },
            velocity_filter: f(s.velocity_filter),
            friction_coulomb: f(s.friction_coulomb),
            friction_viscous: f(s.friction_viscous),
            node_id: s.node_ids[a] as f32,
            torque_constant: f(s.torque_constant[a]),
            soft_limit_min: f(s.soft_limits[a][0]),
            soft_limit_max: f(s.soft_limits[a][1]),
            homing_velocity: f(s.homing.velocity),
            homing_acceleration: f(s.homing.acceleration),
            homing_jerk: f(s.homing.jerk),
            homing_direction: f(s.homing.direction),
            switch_height: f(s.homing.switch_height[a]),
            homing_backoff: f(s.homing.backoff),
            homing_max_travel: f(s.homing.max_travel),
            homing_timeout: f(s.homing.timeout),
            homing_following_error_max: f(s.homing.following_error_max),
            axis_node_1: s.node_ids[0] as f32,
            axis_node_2: s.node_ids[1] as f32,
            axis_node_3: s.node_ids[2] as f32,
            override_cap: 1.0,
            brake: if s.brake[a] { 1.0 } else { 0.0 },
            ceiling_velocity: f(c.velocity),
            ceiling_acceleration: f(c.acceleration),
            ceiling_jerk: f(c.jerk),
            ceiling_torque: f(c.torque),
        }
    }

    /// Node ids of the drives of axes 1–3.
    pub fn axis_nodes(&self) -> [f32; 3] {
        [self.axis_node_1, self.axis_node_2, self.axis_node_3]
    }

    pub fn crc(&self) -> u32 {
        config_crc(&self.to_values())
    }

    /// The robot these parameters describe, in the wire's f32 (a drive
    /// builds its model from it with no double-precision code).
    pub fn robot(&self) -> RobotParams<f32> {
        RobotParams {
            platform_radius: self.platform_radius,
            base_radius: self.base_radius,
            strut_length: self.strut_length,
            slider_offset: self.slider_offset,
            platform_mass: self.platform_mass,
            payload_mass: self.payload_mass,
            strut_mass: self.strut_mass,
            slider_mass: self.slider_mass,
            motor_inertia: self.motor_inertia,
            coupling_inertia: self.coupling_inertia,
            leadscrew_inertia: self.leadscrew_inertia,
            lead: self.lead,
            gravity: self.gravity,
        }
    }

    /// Checks that a drive can run with these values (no panics, no NaN).
    pub fn validate(&self) -> Result<(), ConfigError> {
        let values = self.to_values();
        for (p, v) in PARAMS.iter().zip(values.iter()) {
            if !v.is_finite() {
                return Err(ConfigError {
                    name: p.name,
                    value: *v,
                    rule: "finite",
                });
            }
        }
        if !(1.0..=OVERRIDE_CAP_MAX as f32).contains(&self.override_cap) {
            return Err(ConfigError {
                name: "override_cap",
                value: self.override_cap,
                rule: "1 to 32",
            });
        }
        let positive: [(&'static str, f32); 24] = [
            ("ceiling_velocity", self.ceiling_velocity),
            ("ceiling_acceleration", self.ceiling_acceleration),
            ("ceiling_jerk", self.ceiling_jerk),
            ("ceiling_torque", self.ceiling_torque),
            ("homing_velocity", self.homing_velocity),
            ("homing_acceleration", self.homing_acceleration),
            ("homing_jerk", self.homing_jerk),
            ("homing_max_travel", self.homing_max_travel),
            ("homing_timeout", self.homing_timeout),
            (
                "homing_following_error_max",
                self.homing_following_error_max,
            ),
            ("torque_constant", self.torque_constant),
            ("max_velocity", self.max_velocity),
            ("max_acceleration", self.max_acceleration),
            ("max_jerk", self.max_jerk),
            ("max_torque", self.max_torque),
            ("following_error_max", self.following_error_max),
            ("arm_tolerance", self.arm_tolerance),
            ("stop_time", self.stop_time),
            ("quick_stop_time", self.quick_stop_time),
            ("sync_timeout", self.sync_timeout),
            ("heartbeat_period", self.heartbeat_period),
            ("velocity_filter", self.velocity_filter),
            ("kp", self.kp),
            ("kd", self.kd),
        ];
        for (name, value) in positive {
            if value <= 0.0 {
                return Err(ConfigError {
                    name,
                    value,
                    rule: "> 0",
                });
            }
        }
        let id_ok =
            |x: f32| (1.0..=super::wire::MAX_NODE_ID as f32).contains(&x) && (x as u8) as f32 == x;
        let nodes = self.axis_nodes();
        let own = nodes[(self.axis as usize).min(2)];
        let rules: [(&'static str, f32, bool, &'static str); 23] = [
            (
                "max_velocity",
                self.max_velocity,
                self.max_velocity <= self.ceiling_velocity,
                "<= ceiling_velocity",
            ),
            (
                "max_acceleration",
                self.max_acceleration,
                self.max_acceleration <= self.ceiling_acceleration,
                "<= ceiling_acceleration",
            ),
            (
                "max_jerk",
                self.max_jerk,
                self.max_jerk <= self.ceiling_jerk,
                "<= ceiling_jerk",
            ),
            (
                "max_torque",
                self.max_torque,
                self.max_torque <= self.ceiling_torque,
                "<= ceiling_torque",
            ),
            (
                "brake",
                self.brake,
                self.brake == 0.0 || self.brake == 1.0,
                "0 or 1",
            ),
            ("node_id", self.node_id, id_ok(self.node_id), "1 to 15"),
            (
                "axis_node_1",
                self.axis_node_1,
                id_ok(self.axis_node_1),
                "1 to 15",
            ),
            (
                "axis_node_2",
                self.axis_node_2,
                id_ok(self.axis_node_2),
                "1 to 15",
            ),
            (
                "axis_node_3",
                self.axis_node_3,
                id_ok(self.axis_node_3),
                "1 to 15",
            ),
            (
                "axis_node_2",
                self.axis_node_2,
                nodes[0] != nodes[1] && nodes[1] != nodes[2] && nodes[0] != nodes[2],
                "three distinct node ids",
            ),
            (
                "soft_limit_max",
                self.soft_limit_max,
                self.soft_limit_max > self.soft_limit_min,
                "> soft_limit_min",
            ),
            (
                "friction_coulomb",
                self.friction_coulomb,
                self.friction_coulomb >= 0.0,
                ">= 0",
            ),
            (
                "friction_viscous",
                self.friction_viscous,
                self.friction_viscous >= 0.0,
                ">= 0",
            ),
            (
                "axis",
                self.axis,
                self.axis == 0.0 || self.axis == 1.0 || self.axis == 2.0,
                "0, 1 or 2",
            ),
            (
                "direction",
                self.direction,
                self.direction == 1.0 || self.direction == -1.0,
                "+1 or -1",
            ),
            (
                "counts_per_metre",
                self.counts_per_metre,
                self.counts_per_metre != 0.0,
                "non-zero",
            ),
            (
                "control_rate",
                self.control_rate,
                (1000.0..=10000.0).contains(&self.control_rate),
                "1000 to 10000",
            ),
            (
                "telemetry_rate",
                self.telemetry_rate,
                self.telemetry_rate >= 0.0 && self.telemetry_rate <= self.control_rate,
                "0 to control_rate",
            ),
            (
                "feedforward",
                self.feedforward,
                self.feedforward == 0.0 || self.feedforward == 1.0,
                "0 or 1",
            ),
            ("ki", self.ki, self.ki >= 0.0, ">= 0"),
            (
                "homing_direction",
                self.homing_direction,
                self.homing_direction == 1.0 || self.homing_direction == -1.0,
                "+1 or -1",
            ),
            (
                "homing_backoff",
                self.homing_backoff,
                self.homing_backoff >= 0.0,
                ">= 0",
            ),
            (
                "underrun_margin",
                self.underrun_margin,
                self.underrun_margin >= 0.0,
                ">= 0",
            ),
        ];
        for (name, value, ok, rule) in rules {
            if !ok {
                return Err(ConfigError { name, value, rule });
            }
        }
        if own != self.node_id {
            return Err(ConfigError {
                name: "node_id",
                value: self.node_id,
                rule: "the axis_node_k of this drive's axis",
            });
        }
        self.robot().validate().map_err(|e| match e {
            crate::params::ParamError::Invalid { name, rule, value } => {
                ConfigError { name, value, rule }
            }
        })
    }

    /// The first parameter that differs from `other`: (name, ours, theirs).
    pub fn first_difference(&self, other: &Self) -> Option<(&'static str, f32, f32)> {
        let (a, b) = (self.to_values(), other.to_values());
        PARAMS
            .iter()
            .zip(a.iter().zip(b.iter()))
            .find(|(_, (x, y))| x.to_bits() != y.to_bits())
            .map(|(p, (x, y))| (p.name, *x, *y))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_is_dense_and_ordered() {
        assert_eq!(PARAMS.len(), PARAM_COUNT);
        for (i, p) in PARAMS.iter().enumerate() {
            assert_eq!(p.index as usize, i, "{}", p.name);
        }
    }

    #[test]
    fn paper_config_is_valid_and_round_trips() {
        let c = DriveConfig::new(
            &Robot::default(),
            &Limits::default(),
            1,
            &DriveSettings::default(),
            0.8,
            0.3,
        );
        c.validate().unwrap();
        let back = DriveConfig::from_values(&c.to_values());
        assert_eq!(back, c);
        assert_eq!(back.crc(), c.crc());
        let mut d = c;
        d.kp *= 1.01;
        assert_ne!(d.crc(), c.crc());
        assert_eq!(c.first_difference(&d).map(|x| x.0), Some("kp"));
        d.direction = 0.5;
        assert_eq!(d.validate().unwrap_err().name, "direction");
    }

    #[test]
    fn node_id_kt_and_soft_limits_are_carried_and_checked() {
        let s = DriveSettings {
            torque_constant: [0.05, 0.06, 0.07],
            soft_limits: [[0.0, 0.5], [0.1, 0.6], [0.2, 0.7]],
            ..DriveSettings::default()
        };
        let c = DriveConfig::new(&Robot::default(), &Limits::default(), 2, &s, 0.8, 0.3);
        assert_eq!(
            (
                c.node_id,
                c.torque_constant,
                c.soft_limit_min,
                c.soft_limit_max
            ),
            (3.0, 0.07, 0.2, 0.7)
        );
        c.validate().unwrap();
        for (bad, name) in [
            (DriveConfig { node_id: 16.0, ..c }, "node_id"),
            (DriveConfig { node_id: 4.0, ..c }, "node_id"),
            (
                DriveConfig {
                    axis_node_1: 3.0,
                    ..c
                },
                "axis_node_2",
            ),
            (DriveConfig { node_id: 0.0, ..c }, "node_id"),
            (
                DriveConfig {
                    max_velocity: 2.0 * c.ceiling_velocity,
                    ..c
                },
                "max_velocity",
            ),
            (
                DriveConfig {
                    max_torque: 2.0 * c.ceiling_torque,
                    ..c
                },
                "max_torque",
            ),
            (
                DriveConfig {
                    torque_constant: 0.0,
                    ..c
                },
                "torque_constant",
            ),
            (
                DriveConfig {
                    soft_limit_max: 0.2,
                    ..c
                },
                "soft_limit_max",
            ),
            (
                DriveConfig {
                    soft_limit_min: f32::NAN,
                    ..c
                },
                "soft_limit_min",
            ),
        ] {
            assert_eq!(bad.validate().unwrap_err().name, name);
        }
    }
}
