//! The OBJ loader: `prism::scene::fuzz::obj`, which says what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| prism::scene::fuzz::obj(data));
