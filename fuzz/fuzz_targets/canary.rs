#![no_main]
// The fuzzer's self-check (scripts/fuzz.sh): a planted bug behind an 8-byte
// comparison. A build whose coverage and comparison instrumentation work
// finds it within seconds; if this target does not crash, the short CI run
// of the real targets would prove nothing.
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    if data.len() >= 8
        && &data[..4] == b"TQ3u"
        && u32::from_le_bytes([data[4], data[5], data[6], data[7]]) == 0x5EED_CAFE
    {
        panic!("canary: the fuzzer found the planted bug");
    }
});
