//! Which plant the virtual machine drives: the rigid one (`plant.rs`,
//! every existing figure) or the flexible one (`flex.rs`, vibration).

use nalgebra::Vector3;
use triquint_shared::Robot;
use triquint_shared::kinematics::KinematicsError;

use crate::flex::{FlexError, FlexParams, FlexPlant};
use crate::plant::{Plant, PlantConfig};

/// The plant's kind, as the command lines name it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, clap::ValueEnum)]
pub enum PlantKind {
    /// The rigid Lagrangian machine.
    #[default]
    Rigid,
    /// Screw and coupling compliance per axis, the platform on its struts,
    /// a current-loop lag and an accelerometer on the platform.
    Flexible,
}

/// The plant of a virtual machine.
#[derive(Clone, Debug)]
// One per machine, never in a collection: the size difference costs nothing.
#[allow(clippy::large_enum_variant)]
pub enum PlantModel {
    Rigid(Plant),
    Flexible(FlexPlant),
}

impl PlantModel {
    /// A plant of `kind` at joint position `q0` (the flexible one's
    /// parameters `flex`), brakes on.
    pub fn new(
        kind: PlantKind,
        nominal: &Robot,
        cfg: PlantConfig,
        flex: &FlexParams,
        q0: Vector3<f64>,
    ) -> Result<Self, FlexError> {
        Ok(match kind {
            PlantKind::Rigid => Self::Rigid(Plant::new(nominal, cfg, q0)),
            PlantKind::Flexible => Self::Flexible(FlexPlant::new(nominal, cfg, flex.clone(), q0)?),
        })
    }

    /// The joint positions the encoders read (m): the rigid joints, or the
    /// flexible machine's rotors.
    pub fn q(&self) -> Vector3<f64> {
        match self {
            Self::Rigid(p) => p.q,
            Self::Flexible(p) => p.motor_q(),
        }
    }

    /// Sets the motor torque of axis `i` (N·m).
    pub fn set_torque(&mut self, i: usize, tau: f64) {
        match self {
            Self::Rigid(p) => p.tau[i] = tau,
            Self::Flexible(p) => p.tau[i] = tau,
        }
    }

    /// Brakes on: nothing moves.
    pub fn set_braked(&mut self, on: bool) {
        match self {
            Self::Rigid(p) => p.braked = on,
            Self::Flexible(p) => p.braked = on,
        }
    }

    /// Integrates `dt` seconds.
    pub fn advance(&mut self, dt: f64) -> Result<(), KinematicsError> {
        match self {
            Self::Rigid(p) => p.advance(dt),
            Self::Flexible(p) => p.advance(dt),
        }
    }

    /// The flexible machine, if this is one.
    pub fn flexible(&self) -> Option<&FlexPlant> {
        match self {
            Self::Rigid(_) => None,
            Self::Flexible(p) => Some(p),
        }
    }
}
