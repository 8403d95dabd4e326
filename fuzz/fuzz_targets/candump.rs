#![no_main]
// The parser module itself: it depends on triquint-shared only.
#[path = "../../host/src/web/candump.rs"]
#[allow(dead_code)]
mod candump;
include!("../harness/candump.rs");
libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzz_candump(data));
