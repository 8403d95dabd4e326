//! Property tests of the CAN protocol codec and the segment reassembler:
//! encode → decode is the identity for every message; any identifier with
//! any payload is either rejected or decodes to a message whose re-encoding
//! gives back the same bytes; no sequence of part frames makes the
//! reassembler panic or hand out a segment that differs from one a host sent.

use proptest::prelude::*;
use triquint_shared::protocol::segment::{BODY_LEN, parts_per_segment};
use triquint_shared::protocol::wire::I48_MAX;
use triquint_shared::protocol::*;

fn finite() -> impl Strategy<Value = f32> {
    any::<f32>().prop_filter("finite", |x| x.is_finite())
}

fn node() -> impl Strategy<Value = u8> {
    1u8..=15
}

/// Any identifier, half the time one the protocol uses.
fn any_id() -> impl Strategy<Value = u16> {
    let used: Vec<u16> = all_messages()
        .iter()
        .flat_map(|d| d.addr.nodes().iter().map(|&n| d.addr.id(n)))
        .collect();
    prop_oneof![0u16..0x800, proptest::sample::select(used)]
}

fn wire_segment() -> impl Strategy<Value = WireSegment> {
    (
        any::<u16>(),
        1u32..=60_000_000,
        any::<u16>(),
        proptest::array::uniform3(proptest::array::uniform6(-I48_MAX - 1..=I48_MAX)),
    )
        .prop_map(|(seq, duration_us, flags, coeffs)| WireSegment {
            seq,
            duration_us,
            flags,
            coeffs,
        })
}

/// Re-encodes a decoded message as the frame payload it came from.
fn reencode(msg: &Msg) -> Option<Vec<u8>> {
    Some(match msg {
        Msg::Emergency(m) => m.encode().to_vec(),
        Msg::TimeSync(m) => m.encode().to_vec(),
        Msg::Command(m) => m.encode().to_vec(),
        Msg::ConfigWrite { index, value } | Msg::ConfigValue { index, value } => {
            config::encode_param(*index, *value).to_vec()
        }
        Msg::SegmentAck(m) => m.encode().to_vec(),
        Msg::CommandAck(m) => m.encode().to_vec(),
        Msg::Heartbeat(m) => m.encode().to_vec(),
        Msg::HeartbeatExt(m) => m.encode().to_vec(),
        Msg::Telemetry(m) => m.encode().to_vec(),
        Msg::TelemetryExt(m) => m.encode().to_vec(),
        Msg::SegmentPart | Msg::SegmentPartFd | Msg::SegmentCompact | Msg::SegmentCompactFd => {
            return None;
        }
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(2000))]

    #[test]
    fn fixed_messages_round_trip(
        n in node(), a in any::<u8>(), b in any::<u8>(), c in any::<u16>(), d in any::<u32>(),
        e in any::<u8>(), f in any::<u8>(), x in finite(), y in finite(), h in 0u8..=15,
    ) {
        let msgs = [
            (Emergency { code: a, state: b, ramp_100us: c, plan_time_us: d }.to_frame(h),
             Msg::Emergency(Emergency { code: a, state: b, ramp_100us: c, plan_time_us: d }), h),
            (TimeSync { seq: a, prev_tx_us: d }.to_frame(0), Msg::TimeSync(TimeSync { seq: a, prev_tx_us: d }), 0),
            (Command { command: a, token: b, arg: d, arg2: c }.to_frame(h), Msg::Command(Command { command: a, token: b, arg: d, arg2: c }), h),
            (SegmentAck { seq: c, result: a, depth: b, next_seq: c ^ 0x5A5A, capacity: e, reason_count: f }.to_frame(n),
             Msg::SegmentAck(SegmentAck { seq: c, result: a, depth: b, next_seq: c ^ 0x5A5A, capacity: e, reason_count: f }), n),
            (CommandAck { command: a, token: b, result: e, state: f, value: d }.to_frame(n),
             Msg::CommandAck(CommandAck { command: a, token: b, result: e, state: f, value: d }), n),
            (Heartbeat { state: a, fault: b, queue_depth: e, protocol_version: f, config_crc: d }.to_frame(n),
             Msg::Heartbeat(Heartbeat { state: a, fault: b, queue_depth: e, protocol_version: f, config_crc: d }), n),
            (HeartbeatExt { next_seq: c, rejects: c.rotate_left(3), tx_errors: a, rx_errors: b, last_reject: e, flags: f }.to_frame(n),
             Msg::HeartbeatExt(HeartbeatExt { next_seq: c, rejects: c.rotate_left(3), tx_errors: a, rx_errors: b, last_reject: e, flags: f }), n),
            (Telemetry { position: x, velocity: y }.to_frame(n), Msg::Telemetry(Telemetry { position: x, velocity: y }), n),
            (TelemetryExt { torque: x, following_error: y }.to_frame(n), Msg::TelemetryExt(TelemetryExt { torque: x, following_error: y }), n),
            (config_write_frame(h, a, x), Msg::ConfigWrite { index: a, value: x }, h),
            (config_value_frame(n, a, y), Msg::ConfigValue { index: a, value: y }, n),
        ];
        for (frame, msg, node) in msgs {
            prop_assert_eq!(decode(&frame), Ok((msg, node)), "{:?}", frame);
        }
    }

    #[test]
    fn segments_round_trip_through_the_reassembler(s in wire_segment(), fd in any::<bool>()) {
        prop_assert_eq!(WireSegment::decode_body(&s.encode_body()), Ok(s));
        let mut r = Reassembler::default();
        let frames: Vec<Frame> = s.frames(fd).collect();
        prop_assert_eq!(frames.len(), parts_per_segment(fd));
        for (i, f) in frames.iter().enumerate() {
            let ev = r.push(f.payload(), fd);
            if i + 1 < frames.len() {
                prop_assert_eq!(ev, PartEvent::Pending);
            } else {
                prop_assert_eq!(ev, PartEvent::Complete(s));
            }
        }
    }

    #[test]
    fn any_frame_is_rejected_or_a_valid_message(id in any_id(), payload in proptest::collection::vec(any::<u8>(), 0..=64), fd in any::<bool>()) {
        let frame = Frame::with_payload(id, &payload, fd);
        match decode(&frame) {
            Err(_) => {}
            Ok((msg, node)) => {
                let def = all_messages().into_iter().find(|d| d.addr.matches(id).is_some()).unwrap();
                prop_assert!(def.addr.nodes().contains(&node));
                prop_assert!(payload.len() >= def.len);
                if let Some(bytes) = reencode(&msg) {
                    // Bit for bit: every payload byte of the layout is a field.
                    let same = bytes.iter().zip(&payload[..def.len]).all(|(a, b)| a == b);
                    prop_assert!(same, "{:?} -> {:?}", frame, msg);
                }
            }
        }
    }

    #[test]
    fn arbitrary_parts_never_yield_a_segment_that_was_not_sent(
        parts in proptest::collection::vec((0u8..24, any::<u8>(), proptest::collection::vec(any::<u8>(), 0..64)), 0..60),
        fd in any::<bool>(),
    ) {
        let mut r = Reassembler::default();
        for (part, seq8, rest) in parts {
            let mut data = vec![part, seq8];
            data.extend(rest);
            if let PartEvent::Complete(s) = r.push(&data, fd) {
                // Only a body whose CRC-32 matches completes (a 2^-32 chance
                // for random bytes): then it is exactly what those bytes encode.
                let body = s.encode_body();
                prop_assert_eq!(WireSegment::decode_body(&body), Ok(s));
            }
        }
    }

    #[test]
    fn a_flipped_bit_in_any_part_never_completes_another_segment(
        s in wire_segment(), fd in any::<bool>(), frame_pick in any::<prop::sample::Index>(), bit_pick in any::<prop::sample::Index>(),
    ) {
        let mut frames: Vec<Frame> = s.frames(fd).collect();
        let k = frame_pick.index(frames.len());
        let bits = frames[k].len as usize * 8;
        let b = bit_pick.index(bits);
        frames[k].data[b / 8] ^= 1 << (b % 8);
        let mut r = Reassembler::default();
        for f in &frames {
            if let PartEvent::Complete(x) = r.push(f.payload(), fd) {
                // Only a flip in bytes the body does not carry (CAN-FD padding) can complete.
                prop_assert_eq!(x, s);
                prop_assert!(fd && b / 8 >= 2 + BODY_LEN / parts_per_segment(fd));
            }
        }
    }
}
