//! The scene file with its `--set` overrides (NUL-separated after the TOML): `prism::scene::fuzz::scene`, which says what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| prism::scene::fuzz::scene(data));
