//! The scene text held by a file: a TOML scene, a Kalles Fraktaler `.kfr` location
//! (converted), or the scene embedded in a PNG or EXR that deepfield wrote. Shared by the
//! command line and the viewer (which opens dropped files the same way).

use std::path::{Path, PathBuf};

use super::IoError;
use crate::scene::kfr;

/// Scene text read from a file, with what error messages and relative paths need.
#[derive(Debug, Clone)]
pub struct SceneSource {
    /// Names the source in messages (the path, marked when converted).
    pub origin: String,
    /// TOML scene text.
    pub text: String,
    /// Folder that relative paths in the scene are resolved against.
    pub base_dir: PathBuf,
}

/// Reads the scene text of `path` (by content: PNG and EXR magic numbers; `.kfr` by name).
pub fn read_scene_source(path: &Path) -> Result<SceneSource, IoError> {
    let origin = path.display().to_string();
    if !path.exists() {
        return Err(IoError::new(path, "no such scene file"));
    }
    let base_dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
    let mut magic = [0u8; 8];
    let head = std::fs::File::open(path).and_then(|mut f| std::io::Read::read(&mut f, &mut magic)).unwrap_or(0);
    let embedded = |found: Option<String>, what: &str| {
        found.ok_or_else(|| IoError::new(path, format!("this {what} carries no deepfield scene")))
    };
    let text = if head == 8 && magic == *b"\x89PNG\r\n\x1a\n" {
        embedded(super::read_png_scene(path)?, "PNG")?
    } else if head >= 4 && magic[..4] == [0x76, 0x2f, 0x31, 0x01] {
        embedded(super::read_exr_scene(path)?, "EXR")?
    } else {
        std::fs::read_to_string(path).map_err(|e| IoError::context(path, "cannot read scene", e))?
    };
    if path.extension().is_some_and(|e| e.eq_ignore_ascii_case("kfr")) {
        // Validated as the scene it converts to; the converter checked what it read.
        let toml = kfr::kfr_to_toml(&origin, &text).map_err(|e| IoError::caused(path, e))?;
        return Ok(SceneSource { origin: format!("{origin} (as a scene)"), text: toml, base_dir });
    }
    Ok(SceneSource { origin, text, base_dir })
}
