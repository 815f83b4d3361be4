//! The EXR reader behind `recolor`: raw planes and the scene from a file.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("deepfield-fuzz-{}.exr", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = deepfield::io::read_exr_planes(&path, 16);
        let _ = deepfield::io::read_exr_scene(&path);
    }
});
