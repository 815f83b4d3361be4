//! The scene chunk of a PNG (what `render image.png` and the viewer read back).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let path = std::env::temp_dir().join(format!("deepfield-fuzz-{}.png", std::process::id()));
    if std::fs::write(&path, data).is_ok() {
        let _ = deepfield::io::read_png_scene(&path);
    }
});
