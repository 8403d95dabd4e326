//! The fault reactions as one table, in the manner of CiA 402's fault
//! reaction option code: per fault class, whether the axis is moving, and
//! what the machine says of its brake and load, one of stop along the path,
//! hold position, or torque off (power stage off, brake applied where there
//! is one). docs/protocol.md ("Fault reactions") gives the table and why.

use triquint_shared::protocol::FaultCode;

/// What a drive does on a fault.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reaction {
    /// Slow to rest along the buffered path (the peers do the same, so the
    /// platform stays on it), then the reaction at rest.
    StopOnPath,
    /// Hold the position where the reference is, servo on.
    Hold,
    /// Hold by the model's static torque alone, no position feedback: for
    /// an axis whose loop sign is right but whose gain is not, on a
    /// gravity-loaded axis without a brake (friction holds the model's error).
    HoldOpenLoop,
    /// Power stage off; the brake, if the axis has one, holds it.
    TorqueOff,
}

/// How far a fault leaves the axis's own loop trusted.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Class {
    /// The path, the bus or a peer failed: the axis's loop is sound.
    Path,
    /// The axis did not follow (load, collision, stall) after the enable
    /// check confirmed its direction and scale: holding is negative feedback.
    Tracking,
    /// The enable check measured the right sign and the wrong gain: the
    /// loop's gain is off by the encoder's error (it may oscillate), the
    /// torque's sign is right.
    Scale,
    /// The loop's sign is wrong or unknown (the enable check found it
    /// reversed, or the axis lost its reference before the check ended):
    /// any position loop may be positive feedback.
    Untrusted,
}

/// What the drive knows of its axis when a fault comes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Axis {
    /// The machine file declares a holding brake (configuration `brake`).
    pub brake: bool,
    /// Gravity loads the axis (configuration `gravity` ≠ 0): torque off
    /// without a brake lets it sink.
    pub gravity_loaded: bool,
    /// The enable check has passed since the power stage came on.
    pub verified: bool,
}

/// The table: per class, the reaction moving, at rest where torque off is
/// safe (a brake, or no gravity load), and at rest on a gravity-loaded
/// axis without a brake.
pub const TABLE: [(Class, Reaction, Reaction, Reaction); 4] = [
    (
        Class::Path,
        Reaction::StopOnPath,
        Reaction::TorqueOff,
        Reaction::Hold,
    ),
    (
        Class::Tracking,
        Reaction::StopOnPath,
        Reaction::TorqueOff,
        Reaction::Hold,
    ),
    (
        Class::Scale,
        Reaction::StopOnPath,
        Reaction::TorqueOff,
        Reaction::HoldOpenLoop,
    ),
    (
        Class::Untrusted,
        Reaction::TorqueOff,
        Reaction::TorqueOff,
        Reaction::TorqueOff,
    ),
];

/// The class of fault `code` on an axis (verified or not by the enable check).
pub fn class(code: FaultCode, verified: bool) -> Class {
    match code {
        FaultCode::WrongDirection => Class::Untrusted,
        FaultCode::WrongScale => Class::Scale,
        FaultCode::FollowingError | FaultCode::SoftLimit if !verified => Class::Untrusted,
        FaultCode::FollowingError => Class::Tracking,
        _ => Class::Path,
    }
}

/// The reaction to fault `code` on `axis`, moving or at rest.
pub fn reaction(code: FaultCode, moving: bool, axis: Axis) -> Reaction {
    let c = class(code, axis.verified);
    let Some(&(_, on_path, off_safe, held)) = TABLE.iter().find(|r| r.0 == c) else {
        return Reaction::TorqueOff;
    };
    if moving {
        on_path
    } else if axis.brake || !axis.gravity_loaded {
        off_safe
    } else {
        held
    }
}
