//! Reference files (`render --reference`): decoded, then re-encoded to the same bytes.
#![no_main]

use deepfield::orbit::saved::SavedReferences;
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(saved) = SavedReferences::decode(data) {
        assert_eq!(saved.encode(), data, "a file that decodes re-encodes to itself");
    }
});
