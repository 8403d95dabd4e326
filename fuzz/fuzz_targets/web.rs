#![no_main]
include!("../harness/web.rs");
libfuzzer_sys::fuzz_target!(|data: &[u8]| {
    fuzz_web(data);
});
