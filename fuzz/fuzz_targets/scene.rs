//! Scene TOML through parsing and validation: never a panic, whatever the text.
#![no_main]

use deepfield::scene::Scene;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else { return };
    let Ok(file) = Scene::parse_file("fuzz.toml", text) else { return };
    let no_bitmaps = |_: &std::path::Path| Err("no bitmaps while fuzzing".to_string());
    if let Ok(scene) = Scene::validate(file, "fuzz.toml", text, std::path::Path::new("."), &no_bitmaps) {
        // The engine choice and the scene's own text must not panic either.
        let _ = scene.engine();
        let _ = scene.to_toml();
    }
});
