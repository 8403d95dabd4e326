// Shared by the `web` fuzz target and host/tests/fuzz_web_corpus.rs (via
// include!): any bytes as what one client sends the monitor's HTTP server.
// hyper's `Request<Incoming>` cannot be built from bytes, so the bytes go
// through an in-memory pipe (`tokio::io::duplex`) into the server's own
// connection (`server::connection`, the listener's HTTP settings), on a
// paused clock (timeouts fire at once, event streams run in virtual time),
// with control allowed from loopback on a replay (no bus: a control request
// that passes every check is answered 409, nothing is sent).

use std::net::SocketAddr;
use std::sync::atomic::AtomicU64;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use tokio::io::{AsyncReadExt, AsyncWriteExt};
use triquint_host::web::budget::{Budget, Limits};
use triquint_host::web::guard::{Policy, RateLimit};
use triquint_host::web::model::Model;
use triquint_host::web::server::{self, App, Peer};

/// Runs one fuzz input: the server answers one response at most, in
/// HTTP/1.1 (1.0 to a 1.0 request), never sends on a bus, and closes the connection once the
/// client is gone. Returns the answer's status code, if any.
pub fn fuzz_web(data: &[u8]) -> Option<u16> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .unwrap();
    rt.block_on(async {
        let local: SocketAddr = "127.0.0.1:8080".parse().unwrap();
        let remote: SocketAddr = "127.0.0.1:50000".parse().unwrap();
        let model = Model::new([1, 2, 3], Default::default(), "fuzz".into(), true);
        let app = Arc::new(App {
            model: Arc::new(Mutex::new(model)),
            policy: Policy {
                bound: local,
                allow_control: true,
                allow_remote_control: false,
                token: None,
            },
            iface: None,
            rate: Mutex::new(RateLimit::new(3, 2.0)),
            budget: Mutex::new(Budget::new(Limits::default())),
            control_sends: tokio::sync::Semaphore::new(server::CONTROL_SENDS),
            events_sent: AtomicU64::new(0),
            events_missed: AtomicU64::new(0),
        });
        let (conn, _evicted) = app
            .budget
            .lock()
            .unwrap()
            .admit(remote.ip(), Instant::now())
            .unwrap();
        let (client, server_end) = tokio::io::duplex(16 * 1024);
        let peer = Peer {
            remote,
            local,
            conn,
        };
        let served = tokio::spawn(server::connection(server_end, Arc::clone(&app), peer));
        let (mut rx, mut tx) = tokio::io::split(client);
        // Sent while the answer is read, so neither side waits on the
        // other; the write side stays open (hyper takes a half-closed
        // connection for a gone client): an incomplete head meets the
        // server's head timeout.
        let request = data.to_vec();
        let writer = tokio::spawn(async move {
            let _ = tx.write_all(&request).await;
            tx
        });
        let mut answer = Vec::new();
        // An event stream never ends: one virtual second of it.
        let _ = tokio::time::timeout(Duration::from_secs(1), async {
            let mut buf = [0u8; 8192];
            while let Ok(n @ 1..) = rx.read(&mut buf).await {
                answer.extend_from_slice(&buf[..n]);
            }
        })
        .await;
        let tx = writer.await.unwrap();
        drop(rx.unsplit(tx));
        // The client is gone: the connection ends (a write fails, or the
        // head's timeout), whatever it was doing.
        let ended = tokio::time::timeout(Duration::from_secs(60), served).await;
        assert!(ended.is_ok(), "the connection outlived its client");
        app.budget.lock().unwrap().release(conn);
        assert_eq!(app.budget.lock().unwrap().open(), 0);

        let text = String::from_utf8_lossy(&answer);
        // An HTTP/1.0 request is answered in HTTP/1.0.
        assert!(
            answer.is_empty() || text.starts_with("HTTP/1.1 ") || text.starts_with("HTTP/1.0 "),
            "{text:?}"
        );
        // No bus to send to, so nothing is ever sent.
        assert!(!text.contains("\"sent\""), "{text:?}");
        let status = text.get(9..12).and_then(|s| s.parse::<u16>().ok());
        if status == Some(200) {
            assert!(
                text.split("\r\n\r\n").next().is_some_and(|head| head
                    .lines()
                    .any(|l| l.eq_ignore_ascii_case("cache-control: no-store"))),
                "{text:?}"
            );
        }
        status
    })
}
