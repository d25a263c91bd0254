//! Fuzz target: `whitted::io::fuzz::stl` must never panic, hang or allocate without bound.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = whitted::io::fuzz::stl(data);
});
