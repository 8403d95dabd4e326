//! A drive as messages name it: the axis it drives and its CAN node id.

/// `axis 2 (node 5)`: the axis (1, 2 or 3, the machine file's `[axis.N]`)
/// and the drive's node id, the words of every message about a drive.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Drive {
    pub axis: usize,
    pub node: u8,
}

impl Drive {
    /// The drive of axis `i + 1` among the node ids `ids` of axes 1, 2, 3.
    pub fn of(ids: [u8; 3], i: usize) -> Self {
        Drive {
            axis: i + 1,
            node: ids[i],
        }
    }

    /// The drive whose node id is `node`, when it is one of `ids`.
    pub fn with_node(ids: [u8; 3], node: u8) -> Option<Self> {
        ids.iter()
            .position(|id| *id == node)
            .map(|i| Drive::of(ids, i))
    }
}

impl std::fmt::Display for Drive {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "axis {} (node {})", self.axis, self.node)
    }
}
