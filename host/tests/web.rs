//! `triquint monitor --web` on a replayed log, as a client sees it: bad
//! and hostile requests get the right 4xx and the server goes on serving;
//! a client that never reads its event stream stalls neither the others
//! nor the replay, and loses its stream; idle connections are closed; the
//! Stop button is answered while non-reading streams and idle connections
//! from several loopback addresses hold the server. (The test's client
//! writes raw HTTP to send what a browser would not; the server parses
//! with hyper.)

use std::io::{BufRead, BufReader, ErrorKind, Read, Write};
use std::net::{IpAddr, Ipv4Addr, SocketAddr, TcpStream};
use std::process::{Child, Command, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::time::{Duration, Instant};

use socket2::{Domain, Socket, Type};

struct Monitor {
    child: Child,
    addr: SocketAddr,
}

impl Drop for Monitor {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn start(extra: &[&str]) -> Monitor {
    let log = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../testdata/hil/case1-classic.candump.log"
    );
    let mut child = Command::new(env!("CARGO_BIN_EXE_triquint"))
        .args(["monitor", "--web", "127.0.0.1:0", "--replay", log])
        .args(["--duration", "60"])
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .expect("triquint runs");
    let mut line = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut line)
        .unwrap();
    let addr = line
        .trim()
        .strip_prefix("triquint monitor: http://")
        .and_then(|s| s.strip_suffix('/'))
        .unwrap_or_else(|| panic!("start line {line:?}"))
        .parse()
        .unwrap();
    Monitor { child, addr }
}

/// Sends `raw` as is; the status code and the body.
fn raw(addr: SocketAddr, request: &[u8]) -> (u16, String) {
    let mut s = TcpStream::connect(addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let _ = s.write_all(request);
    let mut out = Vec::new();
    let _ = s.read_to_end(&mut out);
    let text = String::from_utf8_lossy(&out).into_owned();
    let code = text
        .split_whitespace()
        .nth(1)
        .and_then(|c| c.parse().ok())
        .unwrap_or_else(|| panic!("no status line in {text:?}"));
    let body = text
        .split_once("\r\n\r\n")
        .map_or("", |(_, b)| b)
        .to_string();
    (code, body)
}

fn request(m: &Monitor, method: &str, path: &str, headers: &[(&str, &str)]) -> (u16, String) {
    let host = m.addr.to_string();
    let mut r = format!("{method} {path} HTTP/1.1\r\nConnection: close\r\n");
    if !headers.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
        r.push_str(&format!("Host: {host}\r\n"));
    }
    for (k, v) in headers {
        r.push_str(&format!("{k}: {v}\r\n"));
    }
    r.push_str("Content-Length: 0\r\n\r\n");
    raw(m.addr, r.as_bytes())
}

fn state(m: &Monitor) -> serde_json::Value {
    let (code, body) = request(m, "GET", "/api/state", &[]);
    assert_eq!(code, 200, "{body}");
    serde_json::from_str(&body).unwrap()
}

#[test]
fn bad_requests_get_4xx_and_the_server_goes_on() {
    let m = start(&[]);
    let (code, page) = request(&m, "GET", "/", &[]);
    assert_eq!(code, 200);
    // The first response already carries the state.
    assert!(page.contains("const INITIAL = {") && page.contains("\"nodes\":["));
    assert_eq!(request(&m, "GET", "/nope", &[]).0, 404);
    assert_eq!(request(&m, "GET", "/api/../etc/passwd", &[]).0, 404);
    assert_eq!(request(&m, "DELETE", "/api/state", &[]).0, 405);
    assert_eq!(request(&m, "GET", "/api/hold", &[]).0, 405);
    assert_eq!(request(&m, "GET", "/api/trace.csv?window=-1", &[]).0, 400);
    let big = "a".repeat(16 * 1024);
    assert_eq!(request(&m, "GET", "/", &[("X-Big", &big)]).0, 431);
    // DNS rebinding: a Host that is not us.
    assert_eq!(request(&m, "GET", "/", &[("Host", "evil.example")]).0, 421);
    assert_eq!(request(&m, "GET", "/", &[("Host", "127.0.0.1:1")]).0, 421);
    let localhost = format!("localhost:{}", m.addr.port());
    assert_eq!(
        request(&m, "GET", "/api/state", &[("Host", &localhost)]).0,
        200
    );
    // Without its port a Host names port 80: another server.
    assert_eq!(request(&m, "GET", "/", &[("Host", "localhost")]).0, 421);
    assert_eq!(request(&m, "GET", "/", &[("Host", "127.0.0.1")]).0, 421);
    // Another loopback address is another server.
    let other = format!("127.0.0.2:{}", m.addr.port());
    assert_eq!(request(&m, "GET", "/", &[("Host", &other)]).0, 421);
    // Absolute form: a request for a proxy, even naming us.
    for target in [
        "http://evil.example/api/state",
        &format!("http://{}/", m.addr),
    ] {
        let (code, body) = request(&m, "GET", target, &[]);
        assert_eq!(code, 400, "{target}: {body}");
    }
    // No Host at all (HTTP/1.0 allows it; we do not).
    let (code, _) = raw(m.addr, b"GET / HTTP/1.0\r\n\r\n");
    assert_eq!(code, 400);
    // Garbage.
    let (code, _) = raw(
        m.addr,
        b"\x16\x03\x01\x02\x00\x01\x00\x01\xfc\x03\x03garbage\r\n\r\n",
    );
    assert_eq!(code, 400);
    // Control without --allow-control.
    let (code, body) = request(&m, "POST", "/api/hold", &[]);
    assert_eq!(code, 403, "{body}");
    assert!(body.contains("--allow-control"));
    // The CSV of the trace window.
    std::thread::sleep(Duration::from_millis(1500));
    let (code, csv) = request(&m, "GET", "/api/trace.csv?window=5", &[]);
    assert_eq!(code, 200);
    let mut lines = csv.lines();
    assert_eq!(lines.next(), Some("t_s,axis,quantity,value,unit"));
    let rows: Vec<Vec<&str>> = lines.map(|l| l.split(',').collect()).collect();
    assert!(
        rows.iter().any(|r| r[2] == "position" && r[4] == "mm"),
        "{csv}"
    );
    assert!(
        rows.iter()
            .all(|r| r.len() == 5 && r[3].parse::<f64>().is_ok())
    );
    // Still serving, and the replay went on.
    let t0 = state(&m)["time_s"].as_f64().unwrap();
    std::thread::sleep(Duration::from_millis(300));
    let s = state(&m);
    assert!(s["time_s"].as_f64().unwrap() > t0);
    assert_eq!(s["nodes"].as_array().unwrap().len(), 3);
}

#[test]
fn control_is_guarded_and_rate_limited() {
    let m = start(&["--allow-control"]);
    let origin = format!("http://{}", m.addr);
    assert_eq!(
        request(
            &m,
            "POST",
            "/api/stop",
            &[("Origin", "http://evil.example")]
        )
        .0,
        403
    );
    let port = m.addr.port();
    for foreign in [
        "null".to_string(),
        // No port: port 80, another origin.
        "http://localhost".into(),
        "http://127.0.0.1".into(),
        // Another loopback address, another scheme.
        format!("http://127.0.0.2:{port}"),
        format!("https://127.0.0.1:{port}"),
    ] {
        let (code, body) = request(&m, "POST", "/api/stop", &[("Origin", &foreign)]);
        assert_eq!(code, 403, "{foreign}: {body}");
    }
    let here = format!("http://localhost:{port}");
    assert_eq!(
        request(&m, "POST", "/api/stop", &[("Origin", &here)]).0,
        409
    );
    // Accepted by the guard; a replay has no bus to send to.
    let (code, body) = request(&m, "POST", "/api/hold", &[("Origin", &origin)]);
    assert_eq!(code, 409, "{body}");
    let codes: Vec<u16> = (0..6)
        .map(|_| request(&m, "POST", "/api/resume", &[]).0)
        .collect();
    assert!(codes.contains(&429), "{codes:?}");
    assert!(codes.iter().all(|c| [409, 429].contains(c)), "{codes:?}");
    // Hold and resume are limited; Stop never is, right after them too.
    let stops: Vec<u16> = (0..10)
        .map(|_| request(&m, "POST", "/api/stop", &[]).0)
        .collect();
    assert!(stops.iter().all(|&c| c == 409), "{stops:?}");
    assert_eq!(request(&m, "POST", "/api/hold", &[]).0, 429);
    assert_eq!(state(&m)["nodes"].as_array().unwrap().len(), 3);
}

#[test]
fn a_client_that_never_reads_stalls_nothing() {
    let m = start(&[]);
    // Two clients open the stream and never read it.
    let mut idle = Vec::new();
    for _ in 0..2 {
        let mut s = TcpStream::connect(m.addr).unwrap();
        write!(s, "GET /api/events HTTP/1.1\r\nHost: {}\r\n\r\n", m.addr).unwrap();
        idle.push(s);
    }
    // A client that reads gets events at 20 Hz, with trace samples.
    let mut s = TcpStream::connect(m.addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(s, "GET /api/events HTTP/1.1\r\nHost: {}\r\n\r\n", m.addr).unwrap();
    let mut r = BufReader::new(s);
    let mut events = 0;
    let t = std::time::Instant::now();
    let mut line = String::new();
    let mut last = serde_json::Value::Null;
    while t.elapsed() < Duration::from_secs(2) {
        line.clear();
        r.read_line(&mut line).unwrap();
        if let Some(d) = line.strip_prefix("data: ") {
            last = serde_json::from_str(d).unwrap();
            events += 1;
        }
    }
    let hz = f64::from(events) / t.elapsed().as_secs_f64();
    assert!(hz >= 10.0, "{hz} Hz");
    assert_eq!(last["traces"].as_array().unwrap().len(), 3);
    // The replay is not held up by the idle clients.
    let a = state(&m)["frames"].as_u64().unwrap();
    std::thread::sleep(Duration::from_millis(500));
    assert!(state(&m)["frames"].as_u64().unwrap() > a);
    drop(idle);
}

/// A connection to `to` from the loopback address `from`.
fn connect_from(from: Ipv4Addr, to: SocketAddr, recv_buffer: Option<usize>) -> TcpStream {
    let s = Socket::new(Domain::IPV4, Type::STREAM, None).unwrap();
    if let Some(n) = recv_buffer {
        s.set_recv_buffer_size(n).unwrap();
    }
    s.bind(&SocketAddr::new(IpAddr::V4(from), 0).into())
        .unwrap();
    s.connect(&to.into()).unwrap();
    s.into()
}

/// Has the server closed `s` (an idle one: nothing to read but the end)?
fn closed_by_server(s: &mut TcpStream) -> bool {
    s.set_nonblocking(true).unwrap();
    let mut buf = [0u8; 65536];
    let closed = loop {
        match s.read(&mut buf) {
            Ok(0) => break true,
            Ok(_) => continue,
            Err(e) if e.kind() == ErrorKind::WouldBlock => break false,
            Err(_) => break true,
        }
    };
    s.set_nonblocking(false).unwrap();
    closed
}

#[test]
fn an_idle_connection_is_closed_within_seconds() {
    let m = start(&[]);
    let mut s = TcpStream::connect(m.addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(20))).unwrap();
    let t = Instant::now();
    let mut buf = [0u8; 1024];
    // No request: closed (an empty read, a 408, or a reset).
    let n = s.read(&mut buf).unwrap_or(0);
    let took = t.elapsed();
    assert!(
        took < Duration::from_secs(5),
        "idle for {took:?}: {:?}",
        String::from_utf8_lossy(&buf[..n])
    );
    // A second request on one connection is not served (no keep-alive).
    let mut s = TcpStream::connect(m.addr).unwrap();
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    let one = format!("GET /api/state HTTP/1.1\r\nHost: {}\r\n\r\n", m.addr);
    write!(s, "{one}{one}").unwrap();
    let mut out = String::new();
    let _ = s.read_to_string(&mut out);
    assert_eq!(out.matches("HTTP/1.1 200").count(), 1, "{out}");
}

#[test]
fn an_event_stream_client_that_does_not_read_loses_it() {
    let m = start(&[]);
    // A small receive buffer, as a stalled browser's fills up.
    let mut s = connect_from(Ipv4Addr::new(127, 0, 0, 2), m.addr, Some(4096));
    write!(s, "GET /api/events HTTP/1.1\r\nHost: {}\r\n\r\n", m.addr).unwrap();
    // Not read for 15 s: the buffers fill, the write timeout runs out.
    std::thread::sleep(Duration::from_secs(15));
    // Then drained: a closed stream ends with what the kernel still held;
    // an open one goes on at 20 events a second.
    s.set_read_timeout(Some(Duration::from_millis(500)))
        .unwrap();
    let t = Instant::now();
    let mut buf = vec![0u8; 65536];
    let mut got = 0;
    let ended = loop {
        match s.read(&mut buf) {
            Ok(0) | Err(_) => break true,
            Ok(n) => got += n,
        }
        if t.elapsed() > Duration::from_secs(3) {
            break false;
        }
    };
    assert!(
        ended,
        "still streaming after 15 s unread ({got} bytes drained)"
    );
    // Others are served still.
    assert_eq!(state(&m)["nodes"].as_array().unwrap().len(), 3);
}

/// Attackers from 127.0.0.2 ..= 127.0.0.9: `streams` event streams never
/// read, `idle` connections that send nothing, reopened as they close.
struct Siege {
    stop: Arc<AtomicBool>,
    reopened: Arc<AtomicUsize>,
    threads: Vec<std::thread::JoinHandle<()>>,
}

fn attacker(k: usize) -> Ipv4Addr {
    Ipv4Addr::new(127, 0, 0, 2 + (k % 8) as u8)
}

impl Siege {
    fn new(addr: SocketAddr, streams: usize, idle: usize) -> Self {
        let stop = Arc::new(AtomicBool::new(false));
        let reopened = Arc::new(AtomicUsize::new(0));
        let mut threads = Vec::new();
        {
            let stop = Arc::clone(&stop);
            threads.push(std::thread::spawn(move || {
                let held: Vec<TcpStream> = (0..streams)
                    .map(|k| {
                        let mut s = connect_from(attacker(k), addr, Some(4096));
                        let _ = write!(s, "GET /api/events HTTP/1.1\r\nHost: {addr}\r\n\r\n");
                        s
                    })
                    .collect();
                while !stop.load(Ordering::Relaxed) {
                    std::thread::sleep(Duration::from_millis(50));
                }
                drop(held);
            }));
        }
        {
            let (stop, reopened) = (Arc::clone(&stop), Arc::clone(&reopened));
            threads.push(std::thread::spawn(move || {
                let mut held: Vec<TcpStream> = (0..idle)
                    .map(|k| connect_from(attacker(k), addr, None))
                    .collect();
                while !stop.load(Ordering::Relaxed) {
                    for (k, s) in held.iter_mut().enumerate() {
                        if closed_by_server(s) {
                            *s = connect_from(attacker(k), addr, None);
                            reopened.fetch_add(1, Ordering::Relaxed);
                        }
                    }
                    std::thread::sleep(Duration::from_millis(25));
                }
            }));
        }
        Siege {
            stop,
            reopened,
            threads,
        }
    }
}

impl Drop for Siege {
    fn drop(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        for t in self.threads.drain(..) {
            let _ = t.join();
        }
    }
}

/// 20 Stops from 127.0.0.1 under `siege`: each status and latency.
fn stops_under_siege(m: &Monitor, streams: usize, idle: usize) -> Vec<(u16, Duration)> {
    let siege = Siege::new(m.addr, streams, idle);
    // Let the siege take hold (streams open, the first idle ones timed out).
    std::thread::sleep(Duration::from_millis(1500));
    let origin = format!("http://{}", m.addr);
    let mut out = Vec::new();
    for _ in 0..20 {
        let t = Instant::now();
        let (code, _) = request(m, "POST", "/api/stop", &[("Origin", &origin)]);
        out.push((code, t.elapsed()));
        std::thread::sleep(Duration::from_millis(250));
    }
    // Other clients are served too.
    assert_eq!(state(m)["nodes"].as_array().unwrap().len(), 3);
    eprintln!(
        "{streams} streams, {idle} idle: reopened {} idle connections",
        siege.reopened.load(Ordering::Relaxed)
    );
    out
}

fn assert_stops_fast(name: &str, stops: &[(u16, Duration)]) {
    let worst = stops.iter().map(|s| s.1).max().unwrap();
    eprintln!(
        "{name}: worst Stop latency {worst:?} over {} tries",
        stops.len()
    );
    // 409: past every guard and the budget (a replay has no bus to send to).
    assert!(stops.iter().all(|s| s.0 == 409), "{stops:?}");
    assert!(worst < Duration::from_millis(500), "{stops:?}");
}

#[test]
fn stop_is_answered_while_streams_and_idle_connections_hold_the_server() {
    let m = start(&["--allow-control"]);
    let stops = stops_under_siege(&m, 64, 64);
    assert_stops_fast("64 streams + 64 idle", &stops);
}

#[test]
fn stop_is_answered_while_idle_connections_exceed_the_budget() {
    let m = start(&["--allow-control"]);
    let stops = stops_under_siege(&m, 64, 200);
    assert_stops_fast("64 streams + 200 idle", &stops);
}
