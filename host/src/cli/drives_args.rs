//! Which drives a command speaks to (`hold`, `resume`, `override`, `stop`,
//! `estop`): the interface and the node ids of axes 1, 2, 3, from
//! `--nodes` or the machine file, as `upload` and `status` take them.

use clap::Args;

use crate::cli::bus_args::node_ids;
use crate::exit::CliResult;
use crate::machine_arg::MachineArg;

#[derive(Args, Debug, Clone)]
pub struct DrivesArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE")]
    pub iface: String,
    /// Node ids of the drives of axes 1, 2, 3 (1 to 15) [default: the
    /// machine file's `axis.N.node_id`].
    #[arg(long = "nodes", value_name = "A,B,C")]
    pub nodes: Option<String>,
    #[command(flatten)]
    pub machine: MachineArg,
}

impl DrivesArgs {
    /// The node ids: `--nodes` when given (the machine file is then not
    /// read), else the machine file's; bad input for either refused.
    pub fn ids(&self) -> CliResult<[u8; 3]> {
        match &self.nodes {
            Some(n) => Ok(triquint_cli_common::parse::parse_axis_nodes("--nodes", n)?),
            None => node_ids(None, &self.machine.load()?),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::exit::Status;

    fn drives(nodes: Option<&str>, machine: Option<std::path::PathBuf>) -> DrivesArgs {
        DrivesArgs {
            iface: "vcan0".into(),
            nodes: nodes.map(Into::into),
            machine: MachineArg { file: machine },
        }
    }

    #[test]
    fn the_ids_come_from_nodes_else_the_machine_file() {
        let dir = std::env::temp_dir().join(format!("triquint-drives-args-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("m.toml");
        let paper = std::fs::read_to_string(
            std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("../examples/machines/paper.toml"),
        )
        .unwrap();
        let mut text = String::new();
        let mut next = [4u8, 5, 6].into_iter();
        for line in paper.lines() {
            if line.trim_start().starts_with("node_id") {
                text += &format!("node_id = {}\n", next.next().unwrap());
            } else {
                text += line;
                text += "\n";
            }
        }
        assert!(next.next().is_none(), "paper.toml names three node ids");
        std::fs::write(&path, text).unwrap();
        assert_eq!(drives(None, Some(path.clone())).ids().unwrap(), [4, 5, 6]);
        assert_eq!(drives(None, None).ids().unwrap(), [1, 2, 3]);
        let missing = dir.join("no-such.toml");
        assert_eq!(
            drives(Some("7,8,9"), Some(missing.clone())).ids().unwrap(),
            [7, 8, 9]
        );
        let e = drives(None, Some(missing)).ids().unwrap_err();
        assert_eq!(e.status, Status::BadInput, "{}", e.message);
        let e = drives(Some("1,2"), Some(path)).ids().unwrap_err();
        assert_eq!(e.status, Status::BadInput, "{}", e.message);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
