//! Figures and names as the operations' messages show them.

use triquint_shared::protocol::State;

/// `--nodes` as the command line had it, for the commands a message suggests.
pub fn nodes_arg(ids: [u8; 3]) -> String {
    if ids == [1, 2, 3] {
        String::new()
    } else {
        format!(" --nodes {},{},{}", ids[0], ids[1], ids[2])
    }
}

pub use triquint_link::Drive;

/// `axis k (node n)` for a node among `ids`, `node n` for another.
pub fn drive_name(ids: [u8; 3], node: u8) -> String {
    Drive::with_node(ids, node).map_or_else(|| format!("node {node}"), |d| d.to_string())
}

/// Name of a state in an acknowledgement.
pub fn state_name(s: u8) -> &'static str {
    State::from_u8(s).map_or("unknown", State::name)
}

/// Per mille as a percentage for people: 117.7 %, 50 %.
pub fn percent(pm: u32) -> String {
    let s = format!("{:.1}", pm as f64 / 10.0);
    s.trim_end_matches(".0").to_string()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentages_print_short() {
        assert_eq!(percent(1177), "117.7");
        assert_eq!(percent(500), "50");
    }

    #[test]
    fn a_drive_is_named_by_its_axis_and_its_node() {
        assert_eq!(Drive::of([4, 5, 6], 1).to_string(), "axis 2 (node 5)");
        assert_eq!(drive_name([4, 5, 6], 6), "axis 3 (node 6)");
        assert_eq!(drive_name([4, 5, 6], 9), "node 9");
    }

    #[test]
    fn the_default_nodes_need_no_option() {
        assert_eq!(nodes_arg([1, 2, 3]), "");
        assert_eq!(nodes_arg([4, 5, 6]), " --nodes 4,5,6");
    }
}
