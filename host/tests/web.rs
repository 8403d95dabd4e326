//! `triquint monitor --web` on a replayed log, as a client sees it: bad
//! and hostile requests get the right 4xx and the server goes on serving;
//! a client that never reads its event stream stalls neither the others
//! nor the replay. (The test's client writes raw HTTP to send what a
//! browser would not; the server parses with hyper.)

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::process::{Child, Command, Stdio};
use std::time::Duration;

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
    assert_eq!(
        request(&m, "GET", "/api/state", &[("Host", "localhost")]).0,
        200
    );
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
    assert_eq!(
        request(&m, "POST", "/api/stop", &[("Origin", "null")]).0,
        403
    );
    // Accepted by the guard; a replay has no bus to send to.
    let (code, body) = request(&m, "POST", "/api/hold", &[("Origin", &origin)]);
    assert_eq!(code, 409, "{body}");
    let codes: Vec<u16> = (0..6)
        .map(|_| request(&m, "POST", "/api/resume", &[]).0)
        .collect();
    assert!(codes.contains(&429), "{codes:?}");
    assert!(codes.iter().all(|c| [409, 429].contains(c)), "{codes:?}");
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
