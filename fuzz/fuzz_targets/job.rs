#![no_main]
include!("../harness/job.rs");
libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzz_job(data));
