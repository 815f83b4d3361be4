//! The EXR reader behind `recolor`: raw planes and the scene from a file.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("deepfield-fuzz-{}.exr", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = deepfield::io::read_exr_planes(&path, 16);
        // Streamed with lent strips, as `recolor` reads (planes refilled for later strips).
        if let Ok(strips) = deepfield::io::ExrStrips::open(&path, 7) {
            let _ = strips.for_each_strip_lent(|_, planes| {
                std::hint::black_box(planes.n.first());
            });
        }
        let _ = deepfield::io::read_exr_scene(&path);
    }
});
