#![no_main]
include!("../harness/points.rs");
libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzz_points(data));
