//! Drive firmware core of triquint: target-independent, `no_std`, allocation-free.
#![no_std]
#![forbid(unsafe_code)]
