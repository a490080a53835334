//! Fuzz target: see `xtask::inputs::fuzz_track`.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| xtask::inputs::fuzz_track(data));
