//! What a raw-data EXR holds, as the readers hand it on: the header's facts and the planes
//! in strips of whole rows.
//!
//! Kept apart from the readers so that the block decoder and the in-place reader of
//! uncompressed files depend on these types, not on the module that chooses between them
//! (`exr_read`, which also holds the whole-image fallback).

use crate::field::{ChannelSet, Planes};
use crate::trap::TrapKind;

/// What a raw-data EXR's header says: enough to check that a scene fits the data before
/// any block is read.
#[derive(Debug, Clone, PartialEq)]
pub struct RawHeader {
    /// Samples per row.
    pub width: usize,
    /// Sample rows.
    pub height: usize,
    /// The scene stored in the header, if the file has one.
    pub scene: Option<String>,
    /// Which of N, NF, T, DEX, DEY the file holds (N always: files without it are refused).
    pub channels: ChannelSet,
    /// The kind of each trap plane, in trap order.
    pub traps: Vec<TrapKind>,
}

/// The raw data of an EXR file.
#[derive(Debug, Clone)]
pub struct RawData {
    /// What the header says.
    pub header: RawHeader,
    /// The planes, in strips of whole rows, top to bottom.
    pub strips: Vec<Planes>,
}
