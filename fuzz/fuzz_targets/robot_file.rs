#![no_main]
include!("../harness/robot_file.rs");
libfuzzer_sys::fuzz_target!(|data: &[u8]| fuzz_robot_file(data));
