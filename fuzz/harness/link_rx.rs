// Shared by the `link_rx` fuzz target and host/link/tests/fuzz_corpus.rs (via
// include!): the host's receive side fed arbitrary drive frames. The input
// is a flags byte (bit 0: CAN-FD session, bit 1: clear faults first, bit 2:
// homing not required), then frames as the `frames` target has them, [id
// low, id high (3 bits) | fd << 3 | own << 4, length, payload…]; identifier
// 0x7FF is a pause (payload byte 0: milliseconds) and 0x7FE a feed command
// of the upload (payload byte 0 picks it, bytes 1–2 an override).
//
// Every frame goes, as the bus delivers it, to a `status::Listener`, a
// `HostClock` and an upload `Session` of the HIL plan
// (testdata/hil/paper-case1.json) polled every millisecond over a port that
// echoes the session's own frames. Checked: nothing panics; the session
// sends only host messages that decode; a session error is one line; the
// listener's status always names the three nodes and serialises.

use std::collections::VecDeque;
use std::sync::OnceLock;

use triquint_link::{CanPort, DriveConfigs, Feed, HostClock, Listener, PortError, Received};
use triquint_link::{Session, SessionOptions};
use triquint_shared::plan::Plan;
use triquint_shared::protocol::config::DriveSettings;
use triquint_shared::protocol::{Frame, Msg, decode};

/// Harness time per frame (µs): about one classic frame on a 1 Mbit/s bus.
const LINK_FRAME_US: u64 = 137;
/// Session poll period (µs).
const LINK_POLL_US: u64 = 1000;
/// Polled after the input (µs): past the session's response timeout, so
/// every waiting phase ends.
const LINK_TAIL_US: u64 = 2_500_000;
/// The pause and feed pseudo-identifiers.
#[allow(dead_code)]
pub const LINK_PAUSE_ID: u16 = 0x7FF;
#[allow(dead_code)]
pub const LINK_FEED_ID: u16 = 0x7FE;

/// The HIL plan and its configurations, read once per process.
fn link_plan() -> &'static (Plan, DriveConfigs) {
    static PLAN: OnceLock<(Plan, DriveConfigs)> = OnceLock::new();
    PLAN.get_or_init(|| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .ancestors()
            .map(|a| a.join("testdata/hil/paper-case1.json"))
            .find(|p| p.is_file())
            .expect("testdata/hil/paper-case1.json above the crate");
        let text = std::fs::read_to_string(&path).expect("reading the HIL plan");
        let plan: Plan = serde_json::from_str(&text).expect("the HIL plan parses");
        // The settings testdata/hil was recorded with: its drives' frames
        // carry that configuration's CRC (soft limits 0–0.8 m, before the
        // machine file set them from the travel).
        let settings = DriveSettings {
            soft_limits: [[0.0, 0.8]; 3],
            ..DriveSettings::default()
        };
        let configs = DriveConfigs::for_plan(&plan, &settings)
            .expect("the HIL plan has configurations");
        (plan, configs)
    })
}

/// The bus as the session sees it: input frames when their time comes,
/// and its own frames echoed back as SocketCAN does.
struct FuzzPort {
    now: u64,
    rx: VecDeque<Received>,
    sent: u64,
}

impl CanPort for FuzzPort {
    fn now_us(&mut self) -> u64 {
        self.now
    }
    fn send(&mut self, frame: &Frame) -> Result<bool, PortError> {
        match decode(frame) {
            Ok((
                Msg::TimeSync(_)
                | Msg::Command(_)
                | Msg::ConfigWrite { .. }
                | Msg::SegmentPart
                | Msg::SegmentPartFd
                | Msg::SegmentCompact
                | Msg::SegmentCompactFd
                | Msg::Emergency(_),
                _,
            )) => {}
            other => panic!("the session sent {frame:?}: {other:?}"),
        }
        self.sent += 1;
        self.rx.push_back(Received {
            frame: *frame,
            t_us: self.now,
            own: true,
        });
        Ok(true)
    }
    fn recv(&mut self) -> Result<Option<Received>, PortError> {
        Ok(self.rx.pop_front())
    }
}

/// What one input did, for the corpus tests.
#[allow(dead_code)]
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LinkOutcome {
    pub frames: usize,
    pub sent: u64,
    /// The session's end: `None` still running, `Some(Ok)` finished, or the error.
    pub ended: Option<Result<bool, String>>,
}

/// The input's frames and feed commands at their arrival times.
enum Event {
    Frame(Received),
    Feed(Feed),
}

fn link_events(data: &[u8]) -> Vec<(u64, Event)> {
    let mut out = Vec::new();
    let (mut t, mut i) = (0u64, 1);
    while i + 3 <= data.len() {
        let id = u16::from(data[i]) | (u16::from(data[i + 1] & 0x07) << 8);
        let (fd, own) = (data[i + 1] & 0x08 != 0, data[i + 1] & 0x10 != 0);
        let len = usize::from(data[i + 2]).min(64).min(data.len() - i - 3);
        let payload = &data[i + 3..i + 3 + len];
        i += 3 + len;
        t += LINK_FRAME_US;
        let arg = |k: usize| payload.get(k).copied().unwrap_or(0);
        match id {
            LINK_PAUSE_ID => t += u64::from(arg(0)) * 1000,
            LINK_FEED_ID => {
                let f = match arg(0) % 5 {
                    0 => Feed::Hold,
                    1 => Feed::Resume,
                    2 => Feed::Stop,
                    3 => Feed::QuickStop,
                    _ => Feed::Override(u16::from_le_bytes([arg(1), arg(2)])),
                };
                out.push((t, Event::Feed(f)));
            }
            _ => {
                let frame = Frame::with_payload(id, payload, fd);
                out.push((
                    t,
                    Event::Frame(Received {
                        frame,
                        t_us: t,
                        own,
                    }),
                ));
            }
        }
    }
    out
}

/// Runs one fuzz input.
pub fn fuzz_link_rx(data: &[u8]) -> LinkOutcome {
    let flags = data.first().copied().unwrap_or(0);
    let (plan, configs) = link_plan();
    let opts = SessionOptions {
        fd: flags & 1 != 0,
        clear_faults: flags & 2 != 0,
        require_homed: flags & 4 == 0,
        ..SessionOptions::default()
    };
    let mut session = Session::new(plan, configs.nodes, opts).expect("the HIL plan uploads");
    let mut listener = Listener::new([1, 2, 3]);
    let mut clock = HostClock::default();
    let mut port = FuzzPort {
        now: 0,
        rx: VecDeque::new(),
        sent: 0,
    };
    let events = link_events(data);
    let mut out = LinkOutcome {
        frames: events.len(),
        ..LinkOutcome::default()
    };
    let end = events.last().map_or(0, |e| e.0) + LINK_TAIL_US;
    let mut next = events.into_iter().peekable();
    while port.now <= end && out.ended.is_none() {
        while let Some((_, ev)) = next.next_if(|e| e.0 <= port.now) {
            match ev {
                Event::Frame(rx) => {
                    listener.take(&rx);
                    clock.take(&rx);
                    port.rx.push_back(rx);
                }
                Event::Feed(f) => {
                    session.feed(f);
                }
            }
        }
        let _ = clock.host_us(port.now);
        match session.poll(&mut port) {
            Ok(None) => {}
            Ok(Some(o)) => out.ended = Some(Ok(o.completed)),
            Err(e) => {
                let msg = e.to_string();
                assert!(!msg.is_empty() && !msg.contains('\n'), "{msg:?}");
                out.ended = Some(Err(msg));
            }
        }
        port.now += LINK_POLL_US;
    }
    for (_, ev) in next {
        if let Event::Frame(rx) = ev {
            listener.take(&rx);
            clock.take(&rx);
        }
    }
    let status = listener.status(&plan.robot);
    let ids: Vec<u8> = status.nodes.iter().map(|n| n.id).collect();
    assert_eq!(ids, [1, 2, 3]);
    serde_json::to_string(&status).expect("the status serialises");
    out.sent = port.sent;
    out
}
