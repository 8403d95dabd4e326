//! `triquint monitor --iface IFACE [--json]`: live bus traffic decoded with
//! the protocol declaration (message, node, every field with its unit; code
//! names; configuration parameters by name; segments reassembled), like
//! `candump` but readable. Stops on SIGINT/SIGTERM, after `--count` frames or
//! `--duration` seconds.
//!
//! With `--web [ADDR:PORT]`, serves the live web monitor instead (see
//! [`crate::web`]), from `--iface` or a `--replay`ed `candump -L` log.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant, SystemTime};

use clap::Args;
use serde_json::{Map, Value as Json, json};
use triquint_cli_common::outln;
use triquint_link::SocketCanPort;
use triquint_shared::protocol::describe::{Described, Value, describe};
use triquint_shared::protocol::{Frame, SegmentEvent, SegmentRx, decode};

use crate::exit::{CliError, CliResult};

#[derive(Args, Debug)]
pub struct MonitorArgs {
    /// SocketCAN interface (can0, vcan0).
    #[arg(long, value_name = "IFACE", required_unless_present = "replay")]
    pub iface: Option<String>,
    /// Serve the web monitor on ADDR:PORT (default 127.0.0.1:8080).
    #[arg(long, value_name = "ADDR:PORT", num_args = 0..=1,
          default_missing_value = "127.0.0.1:8080")]
    pub web: Option<std::net::SocketAddr>,
    /// With --web: replay a `candump -L` log at its recorded pace, looping.
    #[arg(
        long,
        value_name = "FILE.log",
        conflicts_with = "iface",
        requires = "web"
    )]
    pub replay: Option<std::path::PathBuf>,
    /// With --web: node ids of the drives of axes 1, 2, 3 [default: the
    /// machine file's `axis.N.node_id`].
    #[arg(long, value_name = "A,B,C", requires = "web")]
    pub nodes: Option<String>,
    /// With --web: accept POST /api/hold, /api/resume, /api/stop (from loopback).
    #[arg(long, requires = "web")]
    pub allow_control: bool,
    /// With --allow-control: from other hosts too, with the token printed at start.
    #[arg(long, requires = "allow_control")]
    pub allow_remote_control: bool,
    /// One JSON object per line.
    #[arg(long, conflicts_with = "web")]
    pub json: bool,
    /// Stop after this many frames.
    #[arg(long, value_name = "N")]
    pub count: Option<u64>,
    /// Stop after this many seconds.
    #[arg(long, value_name = "S")]
    pub duration: Option<f64>,
    #[command(flatten)]
    pub machine: crate::machine_arg::MachineArg,
}

fn json_value(v: &Value) -> Json {
    match v {
        Value::Unsigned(u) => json!(u),
        Value::Signed(i) => json!(i),
        Value::Float(x) => json!(x),
        Value::Code(c, Some(n)) => json!({ "code": c, "name": n }),
        Value::Code(c, None) => json!({ "code": c, "name": null }),
        Value::Bytes(b) => json!(b.iter().map(|x| format!("{x:02X}")).collect::<String>()),
    }
}

/// One decoded frame as a JSON object.
pub fn frame_json(t_s: f64, frame: &Frame, d: &Described) -> Json {
    let mut fields = Map::new();
    let mut units = Map::new();
    for f in &d.fields {
        fields.insert(f.name.to_string(), json_value(&f.value));
        if !f.unit.is_empty() {
            units.insert(f.name.to_string(), json!(f.unit));
        }
    }
    json!({
        "t_s": t_s,
        "id": frame.id,
        "fd": frame.fd,
        "message": d.def.name,
        "node": d.node,
        "fields": fields,
        "units": units,
    })
}

fn raw(frame: &Frame) -> String {
    let hex: String = frame.payload().iter().map(|b| format!("{b:02X}")).collect();
    format!("{:03X}#{}{hex}", frame.id, if frame.fd { "#" } else { "" })
}

pub fn run(args: &MonitorArgs, machine: &triquint_shared::machine::Machine) -> CliResult {
    if let Some(d) = args.duration
        && !(d.is_finite() && d > 0.0)
    {
        return Err(CliError::bad_input(format!(
            "--duration {d}: must be a positive number of seconds"
        )));
    }
    let stop = Arc::new(AtomicBool::new(false));
    for sig in [signal_hook::consts::SIGINT, signal_hook::consts::SIGTERM] {
        signal_hook::flag::register(sig, Arc::clone(&stop))
            .map_err(|e| CliError::device(format!("cannot install the signal handler: {e}")))?;
    }
    if let Some(addr) = args.web {
        let ids = crate::cli::bus_args::node_ids(args.nodes.as_deref(), machine)?;
        let opts = crate::web::WebOptions {
            addr,
            iface: args.iface.clone(),
            replay: args.replay.clone(),
            ids,
            allow_control: args.allow_control,
            allow_remote_control: args.allow_remote_control,
            duration: args.duration,
        };
        return crate::web::run(&opts, &machine.robot, stop);
    }
    let Some(iface) = args.iface.as_deref() else {
        return Err(CliError::bad_input("--iface IFACE is needed without --web"));
    };
    // A CAN-FD socket receives classic and FD frames alike.
    let mut port =
        SocketCanPort::open(iface, true, false, SystemTime::now()).map_err(CliError::device)?;
    let t0 = Instant::now();
    let mut seen = 0u64;
    let mut parts = SegmentRx::default();
    while !stop.load(Ordering::Relaxed)
        && args.count.is_none_or(|n| seen < n)
        && args.duration.is_none_or(|d| t0.elapsed().as_secs_f64() < d)
    {
        let Some(rx) = port.recv().map_err(CliError::device)? else {
            std::thread::sleep(Duration::from_millis(1));
            continue;
        };
        seen += 1;
        let t_s = rx.t_ns as f64 * 1e-9;
        let f = rx.frame;
        match describe(&f) {
            Ok(d) => {
                if args.json {
                    outln!("{}", frame_json(t_s, &f, &d))?;
                } else {
                    outln!("{t_s:12.6} {:<20} {d}", raw(&f))?;
                }
                if let Some(SegmentEvent::Complete { segment: w, .. }) = decode(&f)
                    .ok()
                    .and_then(|(m, _)| parts.push(m.kind(), f.payload()))
                    && !args.json
                {
                    outln!(
                        "{t_s:12.6} {:<20} segment seq={} duration={:.6} s flags=0x{:X} (CRC ok)",
                        "",
                        w.seq,
                        w.duration_us as f64 * 1e-6,
                        w.flags
                    )?;
                }
            }
            Err(e) => {
                if args.json {
                    outln!(
                        "{}",
                        json!({ "t_s": t_s, "id": f.id, "fd": f.fd, "error": e.to_string(), "raw": raw(&f) })
                    )?;
                } else {
                    outln!("{t_s:12.6} {:<20} not a protocol frame: {e}", raw(&f))?;
                }
            }
        }
    }
    Ok(())
}
