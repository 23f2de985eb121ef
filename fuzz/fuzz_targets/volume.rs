//! The volume sources, evaluated at every voxel: `prism::scene::fuzz::volume`, which says what it checks.
#![no_main]

libfuzzer_sys::fuzz_target!(|data: &[u8]| prism::scene::fuzz::volume(data));
