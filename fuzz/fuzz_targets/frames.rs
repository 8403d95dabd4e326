#![no_main]
include!("../harness/frames.rs");
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fuzz_frames(data);
});
