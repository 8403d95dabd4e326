#![no_main]
include!("../harness/machine_file.rs");
libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzz_machine_file(data));
