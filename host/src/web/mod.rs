//! `triquint monitor --web`: the machine in a browser, live from a SocketCAN
//! interface or replayed from a `candump -L` log. One concept per file:
//! - [`candump`]: log lines to frames;
//! - [`source`]: the frame source thread (live or replay) feeding the model;
//! - [`model`]: the state (`status`'s model plus staleness, traces, trail,
//!   planned path, bus statistics);
//! - [`traces`]: the trace ring buffers; [`stats`]: frame rates, bus load;
//! - [`server`]: the HTTP server and its routes; [`guard`]: request
//!   target, Host, Origin, token and rate limit; [`budget`]: the
//!   connections, per client and in total, with a reserve for control;
//!   [`write_timeout`]: a socket whose writes give up; [`control`]: hold,
//!   resume, stop on the bus;
//! - [`page`]: the page with its assets compiled in.

pub mod budget;
pub mod candump;
pub mod control;
pub mod event;
pub mod guard;
pub mod model;
pub mod page;
pub mod server;
pub mod source;
pub mod stats;
pub mod traces;
pub mod write_timeout;

use std::io::Write;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use triquint_cli_common::input::{MAX_LOG_BYTES, read_text};
use triquint_cli_common::output::io_reason;

use triquint_shared::Robot;

use crate::exit::{CliError, CliResult};
use budget::{Budget, Limits};
use guard::{Policy, RateLimit};
use model::Model;
use source::Source;

/// What `monitor --web` was asked.
#[derive(Clone, Debug)]
pub struct WebOptions {
    pub addr: SocketAddr,
    pub iface: Option<String>,
    pub replay: Option<PathBuf>,
    pub ids: [u8; 3],
    pub allow_control: bool,
    pub allow_remote_control: bool,
    /// Stop after this long (s).
    pub duration: Option<f64>,
}

/// Serves the monitor until SIGINT/SIGTERM or `duration`.
pub fn run(opts: &WebOptions, robot: &Robot, stop: Arc<AtomicBool>) -> CliResult {
    let (source, name) = match (&opts.iface, &opts.replay) {
        (_, Some(path)) => {
            let text = read_text(path, MAX_LOG_BYTES, "a replay log").map_err(|e| {
                CliError::bad_input(format!("{}: {}", path.display(), io_reason(&e)))
            })?;
            let log = candump::parse_log(&text)
                .map_err(|e| CliError::bad_input(format!("{}: {e}", path.display())))?;
            let name = path
                .file_name()
                .map_or("log".into(), |n| n.to_string_lossy().into_owned());
            (Source::Replay(log), format!("replay of {name}"))
        }
        (Some(iface), None) => (
            Source::Live(source::open_live(iface).map_err(CliError::device)?),
            iface.clone(),
        ),
        (None, None) => return Err(CliError::bad_input("--web needs --iface or --replay")),
    };
    let replay = opts.replay.is_some();
    let model = Arc::new(Mutex::new(Model::new(
        opts.ids,
        robot.clone(),
        name,
        replay,
    )));
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| CliError::device(format!("runtime: {e}")))?;
    let listener = rt
        .block_on(tokio::net::TcpListener::bind(opts.addr))
        .map_err(|e| CliError::device(format!("cannot listen on {}: {e}", opts.addr)))?;
    let bound = listener
        .local_addr()
        .map_err(|e| CliError::device(e.to_string()))?;
    let token = if opts.allow_remote_control {
        Some(guard::new_token().map_err(|e| CliError::device(format!("token: {e}")))?)
    } else {
        None
    };
    let policy = Policy {
        bound,
        allow_control: opts.allow_control,
        allow_remote_control: opts.allow_remote_control,
        token: token.clone(),
    };
    let app = Arc::new(server::App {
        model: Arc::clone(&model),
        policy,
        iface: if replay { None } else { opts.iface.clone() },
        rate: Mutex::new(RateLimit::new(3, 2.0)),
        budget: Mutex::new(Budget::new(Limits::default())),
        control_sends: tokio::sync::Semaphore::new(server::CONTROL_SENDS),
        events_sent: AtomicU64::new(0),
        events_missed: AtomicU64::new(0),
    });
    {
        let mut out = std::io::stdout().lock();
        let _ = writeln!(out, "triquint monitor: http://{bound}/");
        if let Some(t) = &token {
            let _ = writeln!(out, "remote control token (X-Triquint-Token header): {t}");
        }
        let _ = out.flush();
    }
    let reader = {
        let (model, stop) = (Arc::clone(&model), Arc::clone(&stop));
        std::thread::spawn(move || source::run(source, model, stop))
    };
    if let Some(d) = opts.duration {
        let stop = Arc::clone(&stop);
        let t0 = Instant::now();
        std::thread::spawn(move || {
            while t0.elapsed().as_secs_f64() < d && !stop.load(Ordering::Relaxed) {
                std::thread::sleep(Duration::from_millis(20));
            }
            stop.store(true, Ordering::Relaxed);
        });
    }
    rt.block_on(server::serve(listener, Arc::clone(&app), Arc::clone(&stop)));
    stop.store(true, Ordering::Relaxed);
    let read = reader
        .join()
        .map_err(|_| CliError::device("the frame source thread panicked"))?;
    triquint_cli_common::errln!(
        "triquint monitor: {} events sent, {} missed (slow clients)",
        app.events_sent.load(Ordering::Relaxed),
        app.events_missed.load(Ordering::Relaxed)
    );
    read.map_err(CliError::device)
}
