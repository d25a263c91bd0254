//! Fuzz target: `whitted::io::fuzz::scene` (parse + validate + load what the scene names)
//! must never panic, hang or allocate without bound. Relative names resolve only in an
//! empty temporary folder.
#![no_main]

use libfuzzer_sys::fuzz_target;
use std::path::PathBuf;
use std::sync::OnceLock;

fn empty_dir() -> &'static PathBuf {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let d = std::env::temp_dir().join(format!("whitted-fuzz-empty-{}", std::process::id()));
        std::fs::create_dir_all(&d).expect("temp dir");
        d
    })
}

fuzz_target!(|data: &[u8]| {
    let _ = whitted::io::fuzz::scene(data, empty_dir());
});
