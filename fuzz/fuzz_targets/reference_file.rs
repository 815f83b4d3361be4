//! Reference files (`render --reference`): decoded, then re-encoded to the same bytes (a
//! version 1 file, to the version 2 file that holds the same orbits).
#![no_main]

use deepfield::orbit::saved::SavedReferences;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(saved) = SavedReferences::decode(data) {
        let encoded = saved.encode();
        if data[8..12] == 2u32.to_le_bytes() {
            assert_eq!(encoded, data, "a file that decodes re-encodes to itself");
        } else {
            let again = SavedReferences::decode(&encoded).expect("its re-encoding decodes");
            assert_eq!(again.encode(), encoded, "and re-encodes to itself");
        }
    }
});
