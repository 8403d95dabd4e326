#![no_main]
include!("../harness/plan.rs");
libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzz_plan(data));
