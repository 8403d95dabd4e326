//! Why an operation on the machine was not carried out, with what the person
//! at the machine needs to know: the commands map it onto the exit-status
//! table (`crate::exit`), the web control shows its message.

use triquint_link::configs::PlanConfigError;
use triquint_link::{Feed, PortError, SocketCanError, UploadError};
use triquint_planner::PlanError;
use triquint_shared::kinematics::KinematicsError;
use triquint_shared::params::OutsideTravel;
use triquint_shared::protocol::{CommandAck, FaultCode, State};

use crate::ops::bus::Bus;
use crate::ops::shown::{Drive, nodes_arg, percent, state_name};

pub type OpResult<T = ()> = Result<T, OpError>;

/// Why an operation on the machine was not carried out.
#[derive(Debug, thiserror::Error)]
pub enum OpError {
    /// The interface would not open.
    #[error(transparent)]
    Open(#[from] SocketCanError),
    /// Sending or receiving failed.
    #[error(transparent)]
    Port(#[from] PortError),
    /// The interface took no frame for longer than a command may wait.
    #[error("the transmit queue stayed full")]
    QueueFull,
    /// A drive sent no heartbeat while the host listened.
    #[error("{drive} sent no heartbeat within {within_s} s")]
    NoHeartbeat { drive: Drive, within_s: f64 },
    /// A drive did not answer a feed command (resends included).
    #[error("{iface}: {drive} did not answer the command within {within_ms} ms")]
    NoAnswer {
        iface: String,
        drive: Drive,
        within_ms: u128,
    },
    /// A drive refused a feed command; `ack` is its answer.
    #[error("{}", feed_refusal(iface, *ids, *drive, *feed, ack))]
    FeedRefused {
        iface: String,
        ids: [u8; 3],
        drive: Drive,
        feed: Feed,
        ack: CommandAck,
    },
    /// A drive's position is unknown: it is not homed.
    #[error(
        "{iface}: {drive} is not homed (its position is unknown): run `triquint home --iface {iface}{}` first",
        nodes_arg(*ids)
    )]
    NotHomed {
        iface: String,
        ids: [u8; 3],
        drive: Drive,
    },
    /// A drive sent no position.
    #[error("{iface}: {drive}: no position (Telemetry) within {within_s} s")]
    NoPosition {
        iface: String,
        drive: Drive,
        within_s: f64,
    },
    /// The joints the drives report have no pose.
    #[error("the drives report joints {q:?} m, which have no valid pose: {source}")]
    NoPose {
        q: [f64; 3],
        #[source]
        source: KinematicsError,
    },
    /// A move's target is out of the robot's reach.
    #[error(transparent)]
    Unreachable(KinematicsError),
    /// A move's target is outside the sliders' travel.
    #[error(
        "the target ({:.3}, {:.3}, {:.3}) mm is outside the travel: {source}",
        target_mm[0],
        target_mm[1],
        target_mm[2]
    )]
    OutsideTravel {
        target_mm: [f64; 3],
        #[source]
        source: OutsideTravel,
    },
    /// A move could not be planned.
    #[error(transparent)]
    Plan(#[from] PlanError),
    /// The drives' configurations for a plan could not be made.
    #[error(transparent)]
    Configs(#[from] PlanConfigError),
    /// Configuring the drives without motion: no answer, or the port failed.
    #[error("{iface}: configuring the drives: {source}")]
    Configure {
        iface: String,
        #[source]
        source: UploadError,
    },
    /// An upload (or configuration) ended early; refusals say what to run.
    #[error("{}", upload_message(source, iface, *ids, *timeout_s))]
    Upload {
        iface: String,
        ids: [u8; 3],
        timeout_s: f64,
        #[source]
        source: UploadError,
    },
}

impl OpError {
    /// An upload's error on `bus`.
    pub fn upload(source: UploadError, bus: &Bus) -> Self {
        Self::Upload {
            iface: bus.iface.clone(),
            ids: bus.ids,
            timeout_s: bus.timeout_s,
            source,
        }
    }
}

fn upload_message(e: &UploadError, iface: &str, ids: [u8; 3], timeout_s: f64) -> String {
    let n = nodes_arg(ids);
    match e {
        e if e.is_config() => e.to_string(),
        e @ (UploadError::Segment { .. } | UploadError::Unstreamable { .. }) => e.to_string(),
        e @ UploadError::Faulted { .. } => format!(
            "{iface}: {e}: see why with `triquint status --iface {iface}{n}`, clear it with `triquint clear --iface {iface}{n}` (or upload with --clear)"
        ),
        e @ UploadError::NotHomed { .. } => {
            format!("{iface}: {e}: run `triquint home --iface {iface}{n}` first")
        }
        e @ UploadError::ArmTooFar { start_mm, .. } => format!(
            "{iface}: {e}; run `triquint move-to {} {} {} --iface {iface}{n}` first",
            mm(start_mm[0]),
            mm(start_mm[1]),
            mm(start_mm[2])
        ),
        e @ UploadError::Timeout { .. } => format!("{iface}: {e} (silent for {timeout_s} s)"),
        e @ UploadError::CeilingsLocked { .. } => format!(
            "{iface}: {e}: a drive takes raised ceilings or wider travel only in maintenance, with the machine at rest: `triquint configure --machine MACHINE.toml --iface {iface}{n} --unlock-ceilings`"
        ),
        e => format!("{iface}: {e}"),
    }
}

fn feed_refusal(iface: &str, ids: [u8; 3], drive: Drive, f: Feed, a: &CommandAck) -> String {
    let n = nodes_arg(ids);
    match (f, FaultCode::from_u8(a.result)) {
        (Feed::Override(pm), Some(FaultCode::OverrideAboveCap)) => format!(
            "{iface}: {drive} refused an override of {} %: the cap of the configured plan is {} % (`triquint override {} --iface {iface}{n}` at most)",
            percent(pm as u32),
            percent(a.value),
            percent(a.value)
        ),
        (_, Some(FaultCode::WrongState)) if a.state == State::Fault as u8 => format!(
            "{iface}: {drive} is in Fault: nothing to {}; see why with `triquint status --iface {iface}{n}`, clear it with `triquint clear --iface {iface}{n}`",
            verb(f)
        ),
        (_, code) => format!(
            "{iface}: {drive} refused ({}) in state {}",
            code.map_or("unknown code", FaultCode::name),
            state_name(a.state)
        ),
    }
}

/// What `f` does, for messages.
fn verb(f: Feed) -> &'static str {
    match f {
        Feed::Hold => "hold",
        Feed::Resume => "resume",
        Feed::Stop | Feed::QuickStop => "stop",
        Feed::Override(_) => "override",
    }
}

/// A millimetre figure as a command argument: 3 decimals, no trailing zeros.
fn mm(x: f64) -> String {
    let s = format!("{x:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".to_string()
    } else {
        s.to_string()
    }
}
