//! Every palette importer: the first byte picks the format, the rest is the file.
#![no_main]

use deepfield::palette::import::{Format, import_text};
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some((&pick, rest)) = data.split_first() else { return };
    let format = [Format::Map, Format::Ggr, Format::Ugr, Format::Kfp, Format::Cpt][pick as usize % 5];
    let text = String::from_utf8_lossy(rest);
    if let Ok(palettes) = import_text(format, "fuzz", &text) {
        for p in palettes {
            let _ = p.at(0.5);
        }
    }
});
