//! Importers for the palette formats other programs write (being written on a branch).

use std::path::Path;

use super::Palette;

/// A palette file format we read.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Fractint/XaoS.
    Map,
}

impl Format {
    /// The format of a file, by extension.
    pub fn from_path(_path: &Path) -> Option<Format> {
        None
    }
}

/// Why an import failed.
#[derive(Debug, thiserror::Error)]
#[error("cannot import {path}")]
pub struct ImportError {
    path: String,
}

/// Reads every palette in a file.
pub fn import_file(path: &Path) -> Result<Vec<Palette>, ImportError> {
    Err(ImportError { path: path.display().to_string() })
}
