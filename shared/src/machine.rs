//! The machine: one description of a real robot that every command reads
//! (`--machine FILE.toml`, docs/machine.md). Its robot (paper Table 1),
//! homing, per-axis drive train (encoder, direction, torque constant,
//! current limit, switch, travel), machine-wide tuning, and the ceilings no
//! plan may exceed. The default is the paper's machine as the virtual
//! hardware models it, so every example runs unchanged.

use serde::{Deserialize, Serialize};

use crate::params::{Robot, Short, Travel};
use crate::protocol::config::{DEFAULT_BANDWIDTH_HZ, DriveSettings, HomingSettings};

/// What the supported boards' firmware fixes, which a machine file for
/// them must match.
pub mod boards {
    /// B-G431B-ESC1: counts per motor revolution (quadrature edges of a
    /// 1024-line encoder).
    pub const B_G431B_ESC1_COUNTS_PER_REV: u32 = 4096;
    /// B-G431B-ESC1: the firmware's |Iq| clamp (A); the board is rated 40 A peak.
    pub const B_G431B_ESC1_MAX_CURRENT: f32 = 15.0;
}

/// One axis's drive train (`[axis.N]`).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    /// Node id (1–15) of the axis's drive.
    pub node_id: u8,
    /// Encoder counts per motor revolution.
    pub counts_per_rev: f64,
    /// +1 if positive motor torque (and a rising encoder count) lifts the slider.
    pub direction: f64,
    /// Motor torque constant Kt (N·m/A).
    pub torque_constant: f64,
    /// Phase current limit (A); the axis's torque ceiling is Kt × this.
    /// None: the machine's `[ceilings] torque` alone bounds it.
    pub current_limit: Option<f64>,
    /// Joint position of the homing switch edge (m).
    pub switch_height: f64,
    /// Lowest and highest joint position a motion may reach (m).
    pub travel_min: f64,
    pub travel_max: f64,
    /// A holding brake applied whenever the power stage is off.
    pub brake: bool,
}

/// What no plan may exceed on this machine, per joint (SI).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Ceilings {
    pub velocity: f64,
    pub acceleration: f64,
    pub jerk: f64,
    pub torque: f64,
}

impl Ceilings {
    /// The four ceilings by name, in the order of [`Limits::named`](crate::Limits::named).
    pub fn named(&self) -> [(&'static str, f64); 4] {
        [
            ("velocity", self.velocity),
            ("acceleration", self.acceleration),
            ("jerk", self.jerk),
            ("torque", self.torque),
        ]
    }
}

/// The largest ceiling: the top of the range every limit is held to.
pub const CEILING_MAX: f64 = 1e6;

impl Default for Ceilings {
    /// None: the default machine is the virtual one, which nothing can
    /// break, so its ceilings are the top of the limits' range. A real
    /// machine's file states its own.
    fn default() -> Self {
        Self {
            velocity: CEILING_MAX,
            acceleration: CEILING_MAX,
            jerk: CEILING_MAX,
            torque: CEILING_MAX,
        }
    }
}

/// Machine-wide tuning of the drives (`[drive]`).
#[derive(Clone, Debug, PartialEq)]
pub struct Tuning {
    /// Closed-loop bandwidth (Hz) the PID gains are placed at.
    pub bandwidth: f64,
    /// Identified slider friction for the feedforward: Coulomb (N), viscous (N·s/m).
    pub friction_coulomb: f64,
    pub friction_viscous: f64,
    /// Following error that stops the machine (m).
    pub following_error_max: f64,
    /// How far outside the travel the drives' soft limits sit (m): room
    /// for a following error at the travel's end, never reaching a switch.
    pub soft_limit_margin: f64,
    /// Control tick rate (Hz).
    pub control_rate: f64,
    /// Largest feed override σ the drives allow (1 = 100 %), below what
    /// the plan's limits allow: every stop ramp is sized for a stop from
    /// it, so a lower one shortens them and the look-ahead they need.
    pub max_override: f64,
}

impl Default for Tuning {
    fn default() -> Self {
        Self {
            bandwidth: DEFAULT_BANDWIDTH_HZ,
            // An identification 20 % short of the virtual machine's 6 N and 30 N·s/m.
            friction_coulomb: 4.8,
            friction_viscous: 24.0,
            following_error_max: 1.0e-3,
            soft_limit_margin: 1.0e-3,
            control_rate: 1000.0,
            max_override: crate::protocol::config::OVERRIDE_CAP_MAX,
        }
    }
}

/// The machine's compliance, as the frequencies and damping ratios of its
/// modes at the simulator's reference pose (docs/vibration.md): what the
/// flexible plant of the simulator is built from, and what `triquint
/// resonance` reports. The defaults are assumptions, not measurements.
#[derive(Clone, Debug, PartialEq)]
pub struct Vibration {
    /// One slider on its screw and coupling, motor held, platform rigid (Hz).
    pub screw_hz: f64,
    /// Damping ratio of that mode.
    pub screw_damping: f64,
    /// Lowest mode of the platform and payload on the struts, sliders held (Hz).
    pub platform_hz: f64,
    /// Damping ratio of that mode.
    pub platform_damping: f64,
    /// Bandwidth of the drives' current loop (Hz).
    pub current_loop_hz: f64,
}

impl Default for Vibration {
    fn default() -> Self {
        Self {
            screw_hz: 50.0,
            screw_damping: 0.05,
            platform_hz: 30.0,
            platform_damping: 0.03,
            current_loop_hz: 1000.0,
        }
    }
}

/// A whole machine. Build it with [`Machine::default`] (the paper's
/// machine) or from a machine file; [`Machine::validate`] holds it to the
/// rules docs/machine.md states.
#[derive(Clone, Debug, PartialEq)]
pub struct Machine {
    pub robot: Robot,
    pub homing: HomingSettings,
    pub drive: Tuning,
    pub axes: [Axis; 3],
    pub ceilings: Ceilings,
    pub vibration: Vibration,
}

impl Default for Machine {
    fn default() -> Self {
        let travel = Travel::default();
        let homing = HomingSettings::default();
        let axis = |a: usize| Axis {
            node_id: a as u8 + 1,
            // A 17-bit encoder on the motor.
            counts_per_rev: 131_072.0,
            direction: 1.0,
            torque_constant: 0.08,
            current_limit: None,
            switch_height: homing.switch_height[a],
            travel_min: travel.min[a],
            travel_max: travel.max[a],
            brake: false,
        };
        let axes = core::array::from_fn(axis);
        Self {
            robot: Robot::default(),
            homing,
            drive: Tuning::default(),
            axes,
            ceilings: Ceilings::default(),
            vibration: Vibration::default(),
        }
    }
}

/// A machine value outside what the machine file accepts: the key (as the
/// file spells it, `axis.2.travel_max`), its value and the accepted range.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[error("`{key}` = {}: {rule}", Short(*value))]
pub struct MachineError {
    pub key: &'static str,
    /// The axis (1–3) for an `[axis.N]` key.
    pub axis: Option<usize>,
    pub value: f64,
    pub rule: &'static str,
}

impl Default for DriveSettings {
    /// The default machine's drive settings.
    fn default() -> Self {
        Machine::default().drive_settings()
    }
}

impl Machine {
    /// The sliders' travel.
    pub fn travel(&self) -> Travel {
        Travel {
            min: self.axes.each_ref().map(|a| a.travel_min),
            max: self.axes.each_ref().map(|a| a.travel_max),
        }
    }

    /// The ceilings with the torque one lowered to the weakest axis's
    /// Kt × current limit: what a plan's limits are held to.
    pub fn effective_ceilings(&self) -> Ceilings {
        let torque = self
            .axes
            .iter()
            .filter_map(|a| a.current_limit.map(|i| a.torque_constant * i))
            .fold(self.ceilings.torque, f64::min);
        Ceilings {
            torque,
            ..self.ceilings.clone()
        }
    }

    /// Encoder counts per metre of slider travel of axis `a`: counts per
    /// revolution over the lead, signed by the axis's direction.
    pub fn counts_per_metre(&self, a: usize) -> f64 {
        self.axes[a].direction * self.axes[a].counts_per_rev / self.robot.lead
    }

    /// The homing settings with the axes' switch heights.
    pub fn homing_settings(&self) -> HomingSettings {
        HomingSettings {
            switch_height: self.axes.each_ref().map(|a| a.switch_height),
            ..self.homing.clone()
        }
    }

    /// What the drives are configured with (everything but the plan's
    /// limits and stop ramps).
    pub fn drive_settings(&self) -> DriveSettings {
        let m = self.drive.soft_limit_margin;
        DriveSettings {
            bandwidth_hz: self.drive.bandwidth,
            direction: self.axes.each_ref().map(|a| a.direction),
            counts_per_metre: core::array::from_fn(|a| self.counts_per_metre(a)),
            following_error_max: self.drive.following_error_max,
            arm_tolerance: 0.2e-3,
            underrun_margin: 0.05,
            sync_timeout: 0.25,
            control_rate: self.drive.control_rate,
            telemetry_rate: 50.0,
            heartbeat_period: 0.1,
            feedforward: true,
            velocity_filter: 300.0,
            friction_coulomb: self.drive.friction_coulomb,
            friction_viscous: self.drive.friction_viscous,
            torque_constant: self.axes.each_ref().map(|a| a.torque_constant),
            soft_limits: self
                .axes
                .each_ref()
                .map(|a| [a.travel_min - m, a.travel_max + m]),
            node_ids: self.axes.each_ref().map(|a| a.node_id),
            brake: self.axes.each_ref().map(|a| a.brake),
            homing: self.homing_settings(),
            ceilings: self.effective_ceilings(),
            max_override: self.drive.max_override,
        }
    }

    /// Every value within its accepted range, and the rules between them:
    /// distinct node ids; per axis travel min < max, and the travel (with
    /// the soft-limit margin) short of the switch by the back-off on the
    /// switch's side.
    pub fn validate(&self) -> Result<(), MachineError> {
        let err = |key, axis, value, rule| {
            Err(MachineError {
                key,
                axis,
                value,
                rule,
            })
        };
        let within = |key, axis: Option<usize>, v: f64, lo: f64, hi: f64, rule| {
            if v.is_finite() && (lo..=hi).contains(&v) {
                Ok(())
            } else {
                err(key, axis, v, rule)
            }
        };
        let h = &self.homing;
        within(
            "homing.velocity",
            None,
            h.velocity,
            1e-6,
            1.0,
            "must be in 1e-6..1 m/s",
        )?;
        within(
            "homing.acceleration",
            None,
            h.acceleration,
            1e-6,
            100.0,
            "must be in 1e-6..100 m/s²",
        )?;
        within(
            "homing.jerk",
            None,
            h.jerk,
            1e-6,
            1e4,
            "must be in 1e-6..1e4 m/s³",
        )?;
        if h.direction != 1.0 && h.direction != -1.0 {
            return err(
                "homing.direction",
                None,
                h.direction,
                "must be 1 (switches above the travel) or -1 (below)",
            );
        }
        within(
            "homing.backoff",
            None,
            h.backoff,
            0.0,
            0.1,
            "must be in 0..0.1 m",
        )?;
        within(
            "homing.max_travel",
            None,
            h.max_travel,
            1e-3,
            10.0,
            "must be in 0.001..10 m",
        )?;
        within(
            "homing.timeout",
            None,
            h.timeout,
            0.1,
            600.0,
            "must be in 0.1..600 s",
        )?;
        within(
            "homing.following_error_max",
            None,
            h.following_error_max,
            1e-6,
            0.1,
            "must be in 1e-6..0.1 m",
        )?;
        within(
            "homing.max_skew",
            None,
            h.max_skew,
            1e-4,
            10.0,
            "must be in 1e-4..10 m",
        )?;
        let d = &self.drive;
        within(
            "drive.bandwidth",
            None,
            d.bandwidth,
            0.1,
            200.0,
            "must be in 0.1..200 Hz",
        )?;
        within(
            "drive.control_rate",
            None,
            d.control_rate,
            1000.0,
            10_000.0,
            "must be in 1000..10000 Hz",
        )?;
        if d.bandwidth * 10.0 > d.control_rate {
            return err(
                "drive.bandwidth",
                None,
                d.bandwidth,
                "must be at most a tenth of drive.control_rate",
            );
        }
        within(
            "drive.friction_coulomb",
            None,
            d.friction_coulomb,
            0.0,
            1e4,
            "must be in 0..1e4 N",
        )?;
        within(
            "drive.friction_viscous",
            None,
            d.friction_viscous,
            0.0,
            1e5,
            "must be in 0..1e5 N·s/m",
        )?;
        within(
            "drive.following_error_max",
            None,
            d.following_error_max,
            1e-6,
            0.1,
            "must be in 1e-6..0.1 m",
        )?;
        within(
            "drive.soft_limit_margin",
            None,
            d.soft_limit_margin,
            0.0,
            0.1,
            "must be in 0..0.1 m",
        )?;
        within(
            "drive.max_override",
            None,
            d.max_override,
            1.0,
            crate::protocol::config::OVERRIDE_CAP_MAX,
            "must be in 1..32 (σ, 1 = 100 %)",
        )?;
        let c = &self.ceilings;
        within(
            "ceilings.velocity",
            None,
            c.velocity,
            1e-6,
            CEILING_MAX,
            "must be in 1e-6..1e6 m/s",
        )?;
        within(
            "ceilings.acceleration",
            None,
            c.acceleration,
            1e-6,
            CEILING_MAX,
            "must be in 1e-6..1e6 m/s²",
        )?;
        within(
            "ceilings.jerk",
            None,
            c.jerk,
            1e-6,
            CEILING_MAX,
            "must be in 1e-6..1e6 m/s³",
        )?;
        within(
            "ceilings.torque",
            None,
            c.torque,
            1e-6,
            CEILING_MAX,
            "must be in 1e-6..1e6 N·m",
        )?;
        let v = &self.vibration;
        for (key, value) in [
            ("vibration.screw_hz", v.screw_hz),
            ("vibration.platform_hz", v.platform_hz),
        ] {
            within(key, None, value, 0.1, 1e4, "must be in 0.1..1e4 Hz")?;
        }
        for (key, value) in [
            ("vibration.screw_damping", v.screw_damping),
            ("vibration.platform_damping", v.platform_damping),
        ] {
            within(key, None, value, 0.0, 0.99, "must be in 0..0.99")?;
        }
        within(
            "vibration.current_loop_hz",
            None,
            v.current_loop_hz,
            1.0,
            1e6,
            "must be in 1..1e6 Hz",
        )?;
        for (i, a) in self.axes.iter().enumerate() {
            let n = Some(i + 1);
            within(
                "node_id",
                n,
                f64::from(a.node_id),
                1.0,
                15.0,
                "must be 1 to 15",
            )?;
            if self.axes[..i].iter().any(|b| b.node_id == a.node_id) {
                return err(
                    "node_id",
                    n,
                    f64::from(a.node_id),
                    "must differ from the other axes'",
                );
            }
            within(
                "counts_per_rev",
                n,
                a.counts_per_rev,
                1.0,
                16_777_216.0,
                "must be a whole number 1..2^24",
            )?;
            if libm::trunc(a.counts_per_rev) != a.counts_per_rev {
                return err(
                    "counts_per_rev",
                    n,
                    a.counts_per_rev,
                    "must be a whole number 1..2^24",
                );
            }
            if a.direction != 1.0 && a.direction != -1.0 {
                return err("direction", n, a.direction, "must be 1 or -1");
            }
            within(
                "torque_constant",
                n,
                a.torque_constant,
                1e-4,
                10.0,
                "must be in 1e-4..10 N·m/A",
            )?;
            if let Some(i_max) = a.current_limit {
                within(
                    "current_limit",
                    n,
                    i_max,
                    0.01,
                    500.0,
                    "must be in 0.01..500 A",
                )?;
            }
            within(
                "travel_min",
                n,
                a.travel_min,
                -10.0,
                10.0,
                "must be in -10..10 m",
            )?;
            within(
                "travel_max",
                n,
                a.travel_max,
                -10.0,
                10.0,
                "must be in -10..10 m",
            )?;
            if a.travel_min >= a.travel_max {
                return err("travel_max", n, a.travel_max, "must be above travel_min");
            }
            within(
                "switch_height",
                n,
                a.switch_height,
                -10.0,
                10.0,
                "must be in -10..10 m",
            )?;
            // The travel and the soft limit beyond it stay clear of the
            // switch: the back-off's rest is the travel's end at most.
            let slack = 1e-9;
            let (edge, clear) = if h.direction > 0.0 {
                (a.travel_max, a.switch_height - h.backoff - a.travel_max)
            } else {
                (a.travel_min, a.travel_min - (a.switch_height + h.backoff))
            };
            if clear < -slack {
                return err(
                    if h.direction > 0.0 {
                        "travel_max"
                    } else {
                        "travel_min"
                    },
                    n,
                    edge,
                    "must leave the homing back-off before the switch (switch_height − homing.backoff above it, or + below)",
                );
            }
            if d.soft_limit_margin >= (a.switch_height - edge) * h.direction {
                return err(
                    "drive.soft_limit_margin",
                    None,
                    d.soft_limit_margin,
                    "must end the soft limit before the switch",
                );
            }
        }
        self.robot.validate().map_err(|e| match e {
            crate::params::ParamError::Invalid { name, rule, value } => MachineError {
                key: name,
                axis: None,
                value,
                rule: match rule {
                    "in 0..1e6" => "must be in 0..1e6",
                    _ => "must be in 1e-6..1e6",
                },
            },
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::string::ToString;

    #[test]
    fn the_default_machine_is_valid_and_is_todays_drive_settings() {
        let m = Machine::default();
        m.validate().unwrap();
        let s = m.drive_settings();
        assert_eq!(s.counts_per_metre, [131_072.0 / 0.010; 3]);
        assert_eq!(s.torque_constant, [0.08; 3]);
        assert_eq!(s.node_ids, [1, 2, 3]);
        assert_eq!(m.travel(), Travel::default());
        // The soft limits sit the margin outside the travel, short of the switch.
        assert_eq!(s.soft_limits[0], [0.049, 0.416]);
        assert!(s.soft_limits[0][1] < s.homing.switch_height[0]);
    }

    #[test]
    fn the_encoder_scale_follows_the_axis_not_a_constant() {
        let mut m = Machine::default();
        m.axes[1].counts_per_rev = f64::from(boards::B_G431B_ESC1_COUNTS_PER_REV);
        m.axes[1].direction = -1.0;
        m.robot.lead = 0.005;
        assert_eq!(m.counts_per_metre(1), -4096.0 / 0.005);
        assert_eq!(m.drive_settings().direction[1], -1.0);
    }

    #[test]
    fn bad_values_name_their_key_and_range() {
        let mut m = Machine::default();
        m.axes[2].travel_max = 0.419;
        let e = m.validate().unwrap_err();
        assert_eq!((e.key, e.axis), ("travel_max", Some(3)));
        let mut m = Machine::default();
        m.axes[0].node_id = 2;
        assert_eq!(m.validate().unwrap_err().key, "node_id");
        let mut m = Machine::default();
        m.axes[0].counts_per_rev = 4096.5;
        assert_eq!(m.validate().unwrap_err().key, "counts_per_rev");
        let mut m = Machine::default();
        m.ceilings.jerk = f64::NAN;
        assert!(
            m.validate()
                .unwrap_err()
                .to_string()
                .contains("ceilings.jerk")
        );
        let mut m = Machine::default();
        m.robot.lead = 0.0;
        assert_eq!(m.validate().unwrap_err().key, "lead");
        // Switches below: the travel's bottom clears them.
        let mut m = Machine::default();
        m.homing.direction = -1.0;
        for a in &mut m.axes {
            a.switch_height = 0.046;
        }
        assert_eq!(m.validate().unwrap_err().key, "travel_min");
        for a in &mut m.axes {
            a.switch_height = 0.040;
        }
        m.validate().unwrap();
    }

    #[test]
    fn the_torque_ceiling_is_the_weakest_axis() {
        let mut m = Machine::default();
        m.axes[1].current_limit = Some(5.0);
        m.axes[1].torque_constant = 0.05;
        assert_eq!(m.effective_ceilings().torque, 0.25);
        assert_eq!(Machine::default().effective_ceilings(), Ceilings::default());
    }
}
