#![no_main]
include!("../harness/link_rx.rs");
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fuzz_link_rx(data);
});
