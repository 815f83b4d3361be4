//! [`LineFault`]: what the two readers of scan-line files ([`super::exr_blocks`] and
//! [`super::exr_plain`]) find wrong with a file's blocks, before the file's path is put to
//! it ([`LineFault::at`]).

use std::path::Path;

use super::IoError;

/// A scan-line file's blocks that cannot be read, or do not hold what the header says.
#[derive(Debug, thiserror::Error)]
pub(super) enum LineFault {
    /// The EXR codec failed (reading or decompressing a block).
    #[error(transparent)]
    Exr(#[from] ::exr::error::Error),
    /// The system failed reading a line in place.
    #[error("scan line {line}: {source}")]
    Read {
        /// The line.
        line: usize,
        /// The system's error.
        source: std::io::Error,
    },
    /// A block's width or byte count is not the header's.
    #[error("a scan-line block of the wrong size")]
    WrongSize,
    /// A block's line lies below the image.
    #[error("a scan line outside the data window")]
    OutsideWindow,
    /// Two blocks hold the same line.
    #[error("scan line {0} appears twice")]
    Twice(usize),
    /// Lines are missing.
    #[error("the file holds {lines} of its {height} scan lines: it is damaged")]
    Missing {
        /// Lines found.
        lines: usize,
        /// Lines the header gives.
        height: usize,
    },
    /// The offset table points at a block of another line or size.
    #[error(
        "the block the offset table gives for scan line {line} holds line {found} of {size} bytes: the file is damaged"
    )]
    Misplaced {
        /// The line looked up.
        line: usize,
        /// The line the block says it holds.
        found: i32,
        /// The block's byte count.
        size: i32,
    },
}

impl LineFault {
    /// The fault, told about the file at `path`.
    pub(super) fn at(self, path: &Path) -> IoError {
        match self {
            LineFault::Exr(e) => IoError::caused(path, e),
            LineFault::Read { line, source } => IoError::context(path, &format!("scan line {line}"), source),
            damaged => IoError::new(path, damaged.to_string()),
        }
    }
}
