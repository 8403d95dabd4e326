// Shared by the `frames` fuzz target and firmware/tests/fuzz_corpus.rs (via
// include!): the input is a stream of frames, each [id low, id high (3 bits)
// | fd << 3, length, payload…]. Every frame goes through the decoder, the
// segment reassembler and a drive node: none may panic, and a completed
// segment must be exactly what its body encodes.

/// Runs one fuzz input.
pub fn fuzz_frames(data: &[u8]) {
    use triquint_shared::protocol::{Frame, Msg, PartEvent, Reassembler, WireSegment, decode};
    let mut asm = Reassembler::default();
    let mut node: triquint_firmware::Node = triquint_firmware::Node::new(2);
    let mut rest = data;
    let mut t = 0u64;
    while rest.len() >= 3 {
        let id = u16::from_le_bytes([rest[0], rest[1] & 0x07]);
        let fd = rest[1] & 0x08 != 0;
        let n = (rest[2] as usize).min(64).min(rest.len() - 3);
        let frame = Frame::with_payload(id, &rest[3..3 + n], fd);
        rest = &rest[3 + n..];
        if let Ok((Msg::SegmentPart | Msg::SegmentPartFd, _)) = decode(&frame)
            && let PartEvent::Complete(s) = asm.push(frame.payload(), fd)
        {
            assert_eq!(WireSegment::decode_body(&s.encode_body()), Ok(s));
        }
        t += 137;
        node.on_frame(&triquint_firmware::RxFrame {
            frame,
            timestamp_us: t,
        });
        while node.pop_tx().is_some() {}
    }
}
