//! `deepfield assemble`'s reading of work units: any bytes as a unit's PNG (and twice, as
//! two units), into a scratch output that must never be left half-written.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let dir = std::env::temp_dir();
    let unit = dir.join(format!("deepfield-fuzz-unit-{}.png", std::process::id()));
    let out = dir.join(format!("deepfield-fuzz-whole-{}.png", std::process::id()));
    if std::fs::write(&unit, data).is_ok() {
        let _ = deepfield::io::assemble_png(&[unit.clone()], &out, &|_, _| {});
        let _ = deepfield::io::assemble_png(&[unit.clone(), unit], &out, &|_, _| {});
        let _ = std::fs::remove_file(&out);
    }
});
