//! Why an upload cannot go on.

use triquint_shared::protocol::segment::SegmentError;

use crate::PortError;

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
    #[error("node {node}: no answer while {what}")]
    Timeout { node: u8, what: &'static str },
    #[error(
        "node {node}: configuration differs from the plan's: `{param}` is {node_value} on the node, {plan_value} in the plan"
    )]
    ConfigMismatch {
        node: u8,
        param: &'static str,
        node_value: f32,
        plan_value: f32,
    },
    #[error(
        "node {node}: configuration CRC 0x{node_crc:08X} differs from the plan's 0x{plan_crc:08X}"
    )]
    ConfigCrc {
        node: u8,
        node_crc: u32,
        plan_crc: u32,
    },
    #[error("node {node}: protocol version {got}, expected {want}")]
    Version { node: u8, got: u8, want: u8 },
    #[error("node {node} rejected segment {seq}: {reason}")]
    Rejected {
        node: u8,
        seq: u16,
        reason: &'static str,
    },
    #[error("segment {seq}: not acknowledged by node {node} after {tries} transmissions")]
    Retransmits { node: u8, seq: usize, tries: u32 },
    #[error("node {node} refused {command}: {code}")]
    Refused {
        node: u8,
        command: &'static str,
        code: &'static str,
    },
}

impl UploadError {
    /// Is this the plan's or the machine's configuration (bad input, exit 2)?
    pub fn is_config(&self) -> bool {
        matches!(
            self,
            UploadError::ConfigMismatch { .. } | UploadError::ConfigCrc { .. }
        )
    }
    /// Is this a motion fault (exit 5)?
    pub fn is_motion_fault(&self) -> bool {
        matches!(self, UploadError::Refused { .. })
    }
}
