//! Helpers shared by the integration tests.

use std::path::{Path, PathBuf};

use deepfield::scene::Scene;

/// A validated scene from TOML text (bitmaps resolved against the repository root).
pub fn scene(text: &str) -> Scene {
    let file = Scene::parse_file("test.toml", text).unwrap_or_else(|e| panic!("{e}"));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    Scene::validate(file, "test.toml", text, root, deepfield::io::load_bitmap).unwrap_or_else(|e| panic!("{e}"))
}

/// Deterministic pseudo-random numbers (64-bit LCG), so sampled pixels never change.
pub struct Lcg(pub u64);

impl Lcg {
    /// Next value in [0, n).
    pub fn below(&mut self, n: u32) -> u32 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 33) % n as u64) as u32
    }
}

/// A scratch folder under target/, fresh for each test name.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// Median of a list (0 when empty).
pub fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(|a, b| a.total_cmp(b));
    v[v.len() / 2]
}
