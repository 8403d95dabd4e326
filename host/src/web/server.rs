//! The HTTP server (hyper 1, HTTP/1.1, on a single-threaded tokio runtime)
//! and its routes:
//! - `GET /`: the page, with the current state embedded;
//! - `GET /api/state`: the state as JSON (`status --json`'s schema plus);
//! - `GET /api/events`: server-sent events at [`super::event::EVENT_HZ`], each the state
//!   and the trace samples new since the client's previous event, through a
//!   bounded queue per client (a slow client misses events, never stalls
//!   the frame source);
//! - `GET /api/trace.csv?window=S`: the last S seconds of every trace;
//! - `POST /api/hold`, `/api/resume`, `/api/stop`: see [`super::guard`].
//!
//! One request a connection (no keep-alive), within the connection
//! [`super::budget`]: a client has [`HEADER_TIMEOUT`] to send its request
//! head, and every write gives up after [`WRITE_TIMEOUT`] without progress
//! ([`super::write_timeout`]), so a client that stops reading its event
//! stream loses it.

use std::convert::Infallible;
use std::net::SocketAddr;
use std::pin::Pin;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::task::{Context, Poll};
use std::time::{Duration, Instant};

use http_body_util::{BodyExt, Full, combinators::BoxBody};
use hyper::body::{Body, Bytes, Frame as BodyFrame, Incoming};
use hyper::server::conn::http1;
use hyper::service::service_fn;
use hyper::{Method, Request, Response, StatusCode, header};
use hyper_util::rt::{TokioIo, TokioTimer};
use serde_json::{Value as Json, json};
use tokio::net::TcpListener;
use tokio::sync::{Semaphore, mpsc};

use super::budget::{Budget, Busy, Kind};
use super::control::{self, Action};
use super::event::{EVENT_HZ, event};
use super::guard::{Policy, RateLimit};
use super::model::Model;
use super::page;
use super::traces::QUANTITIES;
use super::write_timeout::WriteTimeout;

/// Events a client may have waiting before it misses some.
const CLIENT_QUEUE: usize = 4;
/// Time to send a complete request head; then the connection is closed.
pub const HEADER_TIMEOUT: Duration = Duration::from_secs(3);
/// A write that makes no progress this long closes the connection.
pub const WRITE_TIMEOUT: Duration = Duration::from_secs(5);
/// Control requests sending on the bus at once (Stop waits its turn, hold
/// and resume are refused).
pub const CONTROL_SENDS: usize = 2;
/// Kernel send buffer of a connection: small, so that a client that stops
/// reading blocks the writes (and meets [`WRITE_TIMEOUT`]) within seconds
/// of events instead of after megabytes.
const SEND_BUFFER: usize = 64 * 1024;

type Resp = Response<BoxBody<Bytes, Infallible>>;

/// What every request handler shares.
pub struct App {
    pub model: Arc<Mutex<Model>>,
    pub policy: Policy,
    /// The interface control frames go to (`None`: replay, nothing to send to).
    pub iface: Option<String>,
    /// Hold and resume (Stop is never rate-limited).
    pub rate: Mutex<RateLimit>,
    pub budget: Mutex<Budget>,
    /// Control requests on the bus at once ([`CONTROL_SENDS`]).
    pub control_sends: Semaphore,
    /// Events sent and missed (client queue full), over all clients.
    pub events_sent: std::sync::atomic::AtomicU64,
    pub events_missed: std::sync::atomic::AtomicU64,
}

fn lock<T>(m: &Mutex<T>) -> std::sync::MutexGuard<'_, T> {
    m.lock().unwrap_or_else(|p| p.into_inner())
}

fn full(status: StatusCode, ctype: &str, body: impl Into<Bytes>) -> Resp {
    Response::builder()
        .status(status)
        .header(header::CONTENT_TYPE, ctype)
        .header(header::CACHE_CONTROL, "no-store")
        .header("x-content-type-options", "nosniff")
        .body(Full::new(body.into()).boxed())
        .unwrap_or_else(|_| Response::new(Full::new(Bytes::new()).boxed()))
}

fn text(status: StatusCode, msg: impl Into<String>) -> Resp {
    let mut m = msg.into();
    m.push('\n');
    full(status, "text/plain; charset=utf-8", m)
}

fn json_resp(status: StatusCode, v: &Json) -> Resp {
    full(status, "application/json", v.to_string())
}

/// An SSE body over a client's bounded queue.
struct EventBody(mpsc::Receiver<Bytes>);

impl Body for EventBody {
    type Data = Bytes;
    type Error = Infallible;
    fn poll_frame(
        mut self: Pin<&mut Self>,
        cx: &mut Context<'_>,
    ) -> Poll<Option<Result<BodyFrame<Bytes>, Infallible>>> {
        self.0
            .poll_recv(cx)
            .map(|o| o.map(|b| Ok(BodyFrame::data(b))))
    }
}

fn events(app: Arc<App>) -> Resp {
    let (tx, rx) = mpsc::channel::<Bytes>(CLIENT_QUEUE);
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(Duration::from_millis(1000 / EVENT_HZ));
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
        let mut cursor: Option<u64> = None;
        let mut planned: Option<u64> = None;
        loop {
            tick.tick().await;
            if tx.is_closed() {
                return;
            }
            // Nothing is built while the client's queue is full.
            let Ok(permit) = tx.try_reserve() else {
                app.events_missed.fetch_add(1, Ordering::Relaxed);
                continue;
            };
            let ev = {
                let m = lock(&app.model);
                let ev = event(&m, cursor, planned);
                cursor = m
                    .traces
                    .newest_us
                    .or(cursor)
                    .max(m.trail.back().map(|t| t.0));
                planned = Some(m.planned_version);
                ev
            };
            permit.send(Bytes::from(format!("data: {ev}\n\n")));
            app.events_sent.fetch_add(1, Ordering::Relaxed);
        }
    });
    Response::builder()
        .header(header::CONTENT_TYPE, "text/event-stream")
        .header(header::CACHE_CONTROL, "no-store")
        .body(EventBody(rx).boxed())
        .unwrap_or_else(|_| text(StatusCode::INTERNAL_SERVER_ERROR, "event stream"))
}

/// The last `window_s` of every trace as CSV.
pub fn trace_csv(model: &Model, window_s: f64) -> String {
    let newest = model.traces.newest_us.unwrap_or(0);
    let from = newest.saturating_sub((window_s * 1e6) as u64);
    let mut out = String::from("t_s,axis,quantity,value,unit\n");
    for (q, axes) in model.traces.series.iter().enumerate() {
        let (name, unit) = QUANTITIES[q];
        for (a, s) in axes.iter().enumerate() {
            for &(t, v) in s.samples.iter().filter(|(t, _)| *t >= from) {
                out.push_str(&format!(
                    "{:.6},{},{name},{v},{unit}\n",
                    t as f64 * 1e-6,
                    a + 1
                ));
            }
        }
    }
    out
}

/// A trace window out of range or not a number, as the query gave it.
#[derive(Debug, thiserror::Error)]
#[error("window={0}: must be 0 to 60 seconds")]
struct BadWindow(String);

fn query_window(query: Option<&str>) -> Result<f64, BadWindow> {
    let Some(q) = query else { return Ok(10.0) };
    for kv in q.split('&') {
        if let Some(v) = kv.strip_prefix("window=") {
            return match v.parse::<f64>() {
                Ok(w) if w > 0.0 && w <= 60.0 => Ok(w),
                _ => Err(BadWindow(v.to_string())),
            };
        }
    }
    Ok(10.0)
}

/// Where a request came from and reached us.
#[derive(Clone, Copy, Debug)]
pub struct Peer {
    pub remote: SocketAddr,
    pub local: SocketAddr,
    /// Its connection in the budget.
    pub conn: u64,
}

async fn control(app: Arc<App>, peer: Peer, req: Request<Incoming>, action: Action) -> Resp {
    if let Err((s, why)) = app
        .policy
        .check_control(peer.remote, peer.local.ip(), req.headers())
    {
        return text(s, why);
    }
    // Stop is never refused for the rate of hold and resume.
    if action != Action::Stop
        && let Err(wait) = lock(&app.rate).take(Instant::now())
    {
        let mut r = text(StatusCode::TOO_MANY_REQUESTS, "hold and resume too often");
        if let Ok(v) = header::HeaderValue::from_str(&format!("{}", wait.as_secs() + 1)) {
            r.headers_mut().insert(header::RETRY_AFTER, v);
        }
        return r;
    }
    let Some(iface) = app.iface.clone() else {
        return text(StatusCode::CONFLICT, "replaying a log: no bus to send to");
    };
    let _permit = if action == Action::Stop {
        match app.control_sends.acquire().await {
            Ok(p) => p,
            Err(_) => return text(StatusCode::SERVICE_UNAVAILABLE, "shutting down"),
        }
    } else {
        match app.control_sends.try_acquire() {
            Ok(p) => p,
            Err(_) => {
                return text(
                    StatusCode::TOO_MANY_REQUESTS,
                    "another control request is on the bus",
                );
            }
        }
    };
    let ids = lock(&app.model).listener.nodes.0.map(|v| v.id);
    match tokio::task::spawn_blocking(move || control::send(&iface, ids, action)).await {
        Ok(Ok(())) => json_resp(
            StatusCode::OK,
            &json!({ "sent": format!("{:?}", action.code()) }),
        ),
        Ok(Err(e)) => text(StatusCode::SERVICE_UNAVAILABLE, e.to_string()),
        Err(e) => text(StatusCode::INTERNAL_SERVER_ERROR, e.to_string()),
    }
}

/// What serving `path` by `method` takes from the budget (`None`: an
/// error answer, nothing to serve).
fn kind_of(path: &str, method: &Method) -> Option<Kind> {
    let get = method == Method::GET || method == Method::HEAD;
    match path {
        "/api/events" if get => Some(Kind::Stream),
        "/" | "/api/state" | "/api/trace.csv" if get => Some(Kind::Request),
        p if Action::from_path(p).is_some() && method == Method::POST => Some(Kind::Control),
        _ => None,
    }
}

/// 503: the budget is spent for this kind of request.
fn busy(b: Busy) -> Resp {
    let mut r = text(
        StatusCode::SERVICE_UNAVAILABLE,
        match b {
            Busy::Requests => "too many requests at once; control requests still go through",
            Busy::Streams => "too many event streams open (from this address, or in all)",
        },
    );
    r.headers_mut()
        .insert(header::RETRY_AFTER, header::HeaderValue::from_static("2"));
    r
}

/// Answers one request.
pub async fn handle(app: Arc<App>, peer: Peer, req: Request<Incoming>) -> Resp {
    if let Err((s, why)) = app.policy.check_target(req.uri()) {
        return text(s, why);
    }
    if let Err((s, why)) = app.policy.check_host(req.headers(), peer.local.ip()) {
        return text(s, why);
    }
    let path = req.uri().path().to_string();
    if let Some(kind) = kind_of(&path, req.method())
        && let Err(b) = lock(&app.budget).serve(peer.conn, kind)
    {
        return busy(b);
    }
    let get = req.method() == Method::GET || req.method() == Method::HEAD;
    match (path.as_str(), get) {
        ("/", true) => {
            let html = page::render(&lock(&app.model), &app.policy);
            full(StatusCode::OK, "text/html; charset=utf-8", html)
        }
        ("/api/state", true) => {
            let v = lock(&app.model).state_json();
            json_resp(StatusCode::OK, &v)
        }
        ("/api/events", true) => events(app),
        ("/api/trace.csv", true) => match query_window(req.uri().query()) {
            Ok(w) => {
                let csv = trace_csv(&lock(&app.model), w);
                let mut r = full(StatusCode::OK, "text/csv; charset=utf-8", csv);
                r.headers_mut().insert(
                    header::CONTENT_DISPOSITION,
                    header::HeaderValue::from_static(
                        "attachment; filename=\"triquint-traces.csv\"",
                    ),
                );
                r
            }
            Err(e) => text(StatusCode::BAD_REQUEST, e.to_string()),
        },
        (p, _) if Action::from_path(p).is_some() => {
            if req.method() != Method::POST {
                let mut r = text(StatusCode::METHOD_NOT_ALLOWED, "POST only");
                r.headers_mut()
                    .insert(header::ALLOW, header::HeaderValue::from_static("POST"));
                return r;
            }
            let action = Action::from_path(p).unwrap_or(Action::Stop);
            control(app, peer, req, action).await
        }
        ("/" | "/api/state" | "/api/events" | "/api/trace.csv", false) => {
            let mut r = text(StatusCode::METHOD_NOT_ALLOWED, "GET only");
            r.headers_mut()
                .insert(header::ALLOW, header::HeaderValue::from_static("GET, HEAD"));
            r
        }
        _ => text(StatusCode::NOT_FOUND, format!("no such page: {path}")),
    }
}

/// One connection served over `io` with the server's HTTP settings (the
/// listener's sockets; the `web` fuzz target's in-memory pipes).
pub async fn connection<I>(io: I, app: Arc<App>, peer: Peer) -> hyper::Result<()>
where
    I: tokio::io::AsyncRead + tokio::io::AsyncWrite + Unpin + Send + 'static,
{
    let svc = service_fn(move |req| {
        let app = Arc::clone(&app);
        async move { Ok::<_, Infallible>(handle(app, peer, req).await) }
    });
    http1::Builder::new()
        .timer(TokioTimer::new())
        .header_read_timeout(HEADER_TIMEOUT)
        .keep_alive(false)
        .max_buf_size(8192)
        .serve_connection(TokioIo::new(io), svc)
        .await
}

/// Serves on `listener` until `stop` (checked every 100 ms).
pub async fn serve(listener: TcpListener, app: Arc<App>, stop: Arc<AtomicBool>) {
    while !stop.load(Ordering::Relaxed) {
        let Ok(accepted) =
            tokio::time::timeout(Duration::from_millis(100), listener.accept()).await
        else {
            continue;
        };
        let Ok((stream, remote)) = accepted else {
            // Out of file descriptors and the like: wait, never spin.
            tokio::time::sleep(Duration::from_millis(50)).await;
            continue;
        };
        let Ok(local) = stream.local_addr() else {
            continue;
        };
        let Some((conn, evicted)) = lock(&app.budget).admit(remote.ip(), Instant::now()) else {
            drop(stream);
            continue;
        };
        let _ = stream.set_nodelay(true);
        let _ = socket2::SockRef::from(&stream).set_send_buffer_size(SEND_BUFFER);
        let peer = Peer {
            remote,
            local,
            conn,
        };
        let app = Arc::clone(&app);
        tokio::spawn(async move {
            let io = WriteTimeout::new(stream, WRITE_TIMEOUT);
            let conn_fut = connection(io, Arc::clone(&app), peer);
            let mut conn_fut = std::pin::pin!(conn_fut);
            let mut evicted = evicted;
            // Served, or evicted by the budget (dropping it closes the socket).
            std::future::poll_fn(|cx| {
                if conn_fut.as_mut().poll(cx).is_ready()
                    || Pin::new(&mut evicted).poll(cx).is_ready()
                {
                    Poll::Ready(())
                } else {
                    Poll::Pending
                }
            })
            .await;
            lock(&app.budget).release(peer.conn);
        });
    }
}
