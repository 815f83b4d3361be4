//! Kalles Fraktaler `.kfr` locations converted to scenes, and the scene validated.
#![no_main]

use deepfield::scene::Scene;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let text = String::from_utf8_lossy(data);
    let Ok(toml) = deepfield::scene::kfr::kfr_to_toml("fuzz.kfr", &text) else { return };
    let file = Scene::parse_file("fuzz.kfr", &toml).expect("a converted .kfr is always valid TOML");
    let no_bitmaps = |_: &std::path::Path| Err("no bitmaps while fuzzing".to_string());
    let _ = Scene::validate(file, "fuzz.kfr", &toml, std::path::Path::new("."), &no_bitmaps);
});
