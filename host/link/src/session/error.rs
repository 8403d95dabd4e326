//! Why an upload cannot go on.

use triquint_shared::protocol::segment::SegmentError;
use triquint_shared::protocol::{CommandCode, FaultCode, Reject};

use crate::{Drive, PortError};

/// Why an upload cannot go on.
#[derive(Debug, thiserror::Error)]
pub enum UploadError {
    #[error(transparent)]
    Port(#[from] PortError),
    #[error("segment {seq}: {source}")]
    Segment {
        seq: usize,
        #[source]
        source: SegmentError,
    },
    #[error("{node}: no answer while {what}")]
    Timeout { node: Drive, what: &'static str },
    #[error(
        "{node}: configuration differs from the plan's: `{param}` is {node_value} on the node, {plan_value} in the plan"
    )]
    ConfigMismatch {
        node: Drive,
        param: &'static str,
        node_value: f32,
        plan_value: f32,
    },
    #[error("{}", config_crc(*node, *node_crc, *plan_crc))]
    ConfigCrc {
        node: Drive,
        node_crc: u32,
        plan_crc: u32,
    },
    #[error("{node} speaks protocol version {got}, this host version {want}: update {}", if got < want { "the drive's firmware (or triquint-sim)" } else { "the host (triquint)" })]
    Version { node: Drive, got: u8, want: u8 },
    #[error("{node} is in Fault ({}); nothing was sent", code_name(*code, "unknown"))]
    Faulted {
        node: Drive,
        /// `None`: a code this host does not know.
        code: Option<FaultCode>,
    },
    #[error("{node} refused: NotHomed (its position is unknown until it is homed); nothing moved")]
    NotHomed { node: Drive },
    #[error(
        "{node} refused Arm: ArmTooFar: the platform is not at the plan's start ({}); nothing moved",
        too_far(distances_mm)
    )]
    ArmTooFar {
        node: Drive,
        /// Measured minus start joint position of each axis (mm; `None`: no position heard).
        distances_mm: [Option<f64>; 3],
        /// The plan's start (mm).
        start_mm: [f64; 3],
    },
    #[error("{node} rejected segment {seq}: {}", reject_name(*reason))]
    Rejected {
        node: Drive,
        seq: u16,
        /// `None`: a reason this host does not know.
        reason: Option<Reject>,
    },
    #[error("segment {seq}: not acknowledged by {node} after {tries} transmissions")]
    Retransmits { node: Drive, seq: usize, tries: u32 },
    #[error(
        "segments {first}–{last} last {} ms, less than the {} ms that queues of {capacity} segments need (look-ahead and refill, docs/protocol.md, Streamability): the drives would underrun; nothing moved",
        *run_us as f64 / 1e3,
        *need_us as f64 / 1e3
    )]
    Unstreamable {
        capacity: usize,
        first: usize,
        last: usize,
        run_us: u64,
        need_us: u64,
    },
    #[error(
        "{node} refused the configuration: CeilingsLocked: it widens `{}` (to {plan_value}) beyond what the drive holds{}; nothing moved",
        param.unwrap_or("a ceiling or the travel"),
        if *unlocked { ", even in the maintenance window (it closed, or the unlock was refused)" } else { "" }
    )]
    CeilingsLocked {
        node: Drive,
        /// The parameter the drive named (`None`: an index this host does not know).
        param: Option<&'static str>,
        plan_value: f32,
        /// The session had asked for the maintenance window.
        unlocked: bool,
    },
    #[error("{node} refused {}: {}", command.name(), code_name(*code, "unknown code"))]
    Refused {
        node: Drive,
        command: CommandCode,
        /// `None`: a code this host does not know.
        code: Option<FaultCode>,
    },
}

/// A fault code's protocol name, or `unknown` for a byte this host does
/// not know.
fn code_name(code: Option<FaultCode>, unknown: &'static str) -> &'static str {
    code.map_or(unknown, FaultCode::name)
}

/// A rejection reason's protocol name.
fn reject_name(reason: Option<Reject>) -> &'static str {
    reason.map_or("unknown reason", Reject::name)
}

/// The ConfigCrc message: the same CRC on both sides means the node has
/// the values and still refused them (one missing, or out of its range).
fn config_crc(node: Drive, node_crc: u32, plan_crc: u32) -> String {
    if node_crc == plan_crc {
        format!(
            "{node} refused the plan's configuration (CRC 0x{plan_crc:08X} on both sides): a value is missing or out of range on the node"
        )
    } else {
        format!(
            "{node}: configuration CRC 0x{node_crc:08X} differs from the plan's 0x{plan_crc:08X}"
        )
    }
}

/// "axis 1 12.345 mm, axis 2 …" for the ArmTooFar message.
fn too_far(d: &[Option<f64>; 3]) -> String {
    d.iter()
        .enumerate()
        .map(|(i, x)| match x {
            Some(x) => format!("axis {} {:+.3} mm", i + 1, x),
            None => format!("axis {} position unknown", i + 1),
        })
        .collect::<Vec<_>>()
        .join(", ")
}

impl UploadError {
    /// Is this a refusal: nothing moved, the machine is not ready for this
    /// (not homed, faulted, not at the plan's start, an Arm refused)?
    pub fn is_refusal(&self) -> bool {
        matches!(
            self,
            UploadError::Faulted { .. }
                | UploadError::NotHomed { .. }
                | UploadError::ArmTooFar { .. }
                | UploadError::Refused { .. }
                | UploadError::CeilingsLocked { .. }
        )
    }

    /// Is this a drive rejecting the plan's own contents (bad input, exit
    /// 2): a segment invalid, not continuous with the one before, or
    /// outside the axis's soft limits; or a plan the drives' queues cannot
    /// stream? Other rejections are the bus's or the machine's.
    pub fn is_bad_plan(&self) -> bool {
        matches!(
            self,
            UploadError::Rejected {
                reason: Some(Reject::Invalid | Reject::Discontinuous | Reject::OutsideSoftLimits),
                ..
            } | UploadError::Unstreamable { .. }
        )
    }

    /// Is this the plan's or the machine's configuration (bad input, exit 2)?
    pub fn is_config(&self) -> bool {
        matches!(
            self,
            UploadError::ConfigMismatch { .. } | UploadError::ConfigCrc { .. }
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_crc_message_never_contradicts_itself() {
        let same = UploadError::ConfigCrc {
            node: Drive { axis: 2, node: 5 },
            node_crc: 0xF23B_5964,
            plan_crc: 0xF23B_5964,
        }
        .to_string();
        assert!(!same.contains("differs"), "{same}");
        assert!(
            same.contains("axis 2 (node 5) refused") && same.contains("0xF23B5964"),
            "{same}"
        );
        let other = UploadError::ConfigCrc {
            node: Drive { axis: 2, node: 5 },
            node_crc: 1,
            plan_crc: 0xF23B_5964,
        }
        .to_string();
        assert!(
            other.contains("0x00000001 differs from the plan's 0xF23B5964"),
            "{other}"
        );
    }

    #[test]
    fn a_rejected_plan_is_bad_input_a_lost_part_is_not() {
        let rejected = |r: Reject| UploadError::Rejected {
            node: Drive { axis: 1, node: 4 },
            seq: 4,
            reason: Some(r),
        };
        for r in [
            Reject::Invalid,
            Reject::Discontinuous,
            Reject::OutsideSoftLimits,
        ] {
            assert!(rejected(r).is_bad_plan(), "{r:?}");
        }
        for r in [Reject::WrongState, Reject::NotHomed] {
            assert!(!rejected(r).is_bad_plan(), "{r:?}");
        }
        let timeout = UploadError::Timeout {
            node: Drive { axis: 1, node: 4 },
            what: "streaming",
        };
        assert!(!timeout.is_bad_plan());
    }

    /// The messages print the protocol's names of the typed codes, and a
    /// byte the host does not know as unknown.
    #[test]
    fn typed_codes_print_their_protocol_names() {
        let faulted = UploadError::Faulted {
            node: Drive { axis: 1, node: 4 },
            code: Some(FaultCode::FollowingError),
        };
        assert_eq!(
            faulted.to_string(),
            "axis 1 (node 4) is in Fault (FollowingError); nothing was sent"
        );
        let unknown = UploadError::Faulted {
            node: Drive { axis: 1, node: 4 },
            code: FaultCode::from_u8(250),
        };
        assert_eq!(
            unknown.to_string(),
            "axis 1 (node 4) is in Fault (unknown); nothing was sent"
        );
        let refused = UploadError::Refused {
            node: Drive { axis: 3, node: 6 },
            command: CommandCode::ConfigCommit,
            code: Some(FaultCode::WrongState),
        };
        assert_eq!(
            refused.to_string(),
            "axis 3 (node 6) refused ConfigCommit: WrongState"
        );
        let rejected = UploadError::Rejected {
            node: Drive { axis: 2, node: 5 },
            seq: 7,
            reason: None,
        };
        assert_eq!(
            rejected.to_string(),
            "axis 2 (node 5) rejected segment 7: unknown reason"
        );
    }
}
