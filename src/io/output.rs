//! One output pipeline for a render: its PNG and, when asked, its raw data as EXR, for the
//! command line, zoom keyframes and the viewer's export alike.
//!
//! A render hands its strips to two places: encoders that run on the worker threads
//! ([`Encoders::encode`]: PNG rows filtered, EXR blocks compressed) and writers that own the
//! files and append the encoded bytes in order on the sink thread ([`Writers::write`]).
//! Every file is written to a temporary name and appears only when [`Writers::finish`]
//! completes (a cancelled or failed render leaves nothing). A work unit (`render --tile
//! K/N`) writes its band: a PNG of its rows and an EXR whose blocks count from the band's
//! first sample row, each marked with the band's place in the whole image.

use std::path::Path;

use ::exr::block::chunk::Chunk;

use super::IoError;
use super::exr::{ExrEncoder, ExrLayout, ExrWriter};
use super::png::{PngEncoder, PngWriter};
use super::tile::{TILE_KEYWORD, band_rows, tile_text};
use crate::field::Planes;
use crate::scene::Scene;

/// What to write.
#[derive(Debug, Clone, Copy)]
pub struct Targets<'a> {
    /// The PNG (none for raw data alone, as zoom keyframes are).
    pub png: Option<&'a Path>,
    /// The EXR of the raw planes (the scene's channels).
    pub exr: Option<&'a Path>,
    /// Work unit K of N: only that band of rows.
    pub tile: Option<(u32, u32)>,
    /// Text for the EXR header's comments (the engine and why).
    pub engine: &'a str,
}

/// Encodes strips for the [`Writers`]; shared by the worker threads.
#[derive(Debug, Clone)]
pub struct Encoders {
    png: Option<PngEncoder>,
    exr: Option<ExrEncoder>,
    /// Samples per pixel side.
    aa: usize,
    /// The first sample row the EXR holds (a unit's band start).
    first_sample: usize,
}

/// One strip, encoded.
#[derive(Debug)]
pub struct Encoded {
    png: Option<Vec<u8>>,
    exr: Option<Vec<(usize, Chunk)>>,
}

/// The open files; written in order by one thread.
pub struct Writers {
    png: Option<PngWriter>,
    exr: Option<ExrWriter>,
}

/// Opens every output of `scene`'s render before anything is computed, so an unwritable
/// path fails at once.
pub fn open(scene: &Scene, targets: Targets<'_>) -> Result<(Writers, Encoders), IoError> {
    let toml = scene.to_toml();
    let band = targets.tile.map(|(k, n)| (band_rows(k, n, scene.height), tile_text(k, n, scene.width, scene.height)));
    let png = match targets.png {
        Some(path) => Some(match &band {
            Some((rows, tile)) => {
                let extra = [(TILE_KEYWORD, tile.clone())];
                PngWriter::create_with(path, scene.width, rows.end - rows.start, scene.png_bits, &toml, &extra)?
            }
            None => PngWriter::create(path, scene.width, scene.height, scene.png_bits, &toml)?,
        }),
        None => None,
    };
    let (exr, exr_enc) = match targets.exr {
        Some(path) => {
            let layout = ExrLayout::new(scene.channels, &scene.traps);
            let w = scene.width * scene.aa;
            let (writer, enc) = match &band {
                Some((rows, tile)) => {
                    let h = (rows.end - rows.start) * scene.aa;
                    ExrWriter::create_unit(path, w, h, layout, &toml, targets.engine, tile)?
                }
                None => ExrWriter::create(path, w, scene.height * scene.aa, layout, &toml, targets.engine)?,
            };
            (Some(writer), Some(enc))
        }
        None => (None, None),
    };
    let first_sample = band.as_ref().map_or(0, |(rows, _)| rows.start as usize * scene.aa as usize);
    let encoders = Encoders {
        png: targets.png.map(|_| PngEncoder::new(scene.png_bits)),
        exr: exr_enc,
        aa: scene.aa as usize,
        first_sample,
    };
    Ok((Writers { png, exr }, encoders))
}

impl Encoders {
    /// Encodes the strip whose first output row is `row`: its pixels (linear RGB), its raw
    /// planes and, when the EXR holds `R`, `G`, `B`, its samples' colours.
    pub fn encode(
        &self,
        row: u32,
        rgb: &[[f32; 3]],
        planes: &Planes,
        samples: Option<&[[f32; 3]]>,
    ) -> Result<Encoded, IoError> {
        let png = self.png.as_ref().map(|e| e.encode(rgb));
        let exr = match &self.exr {
            Some(e) => Some(e.encode(row as usize * self.aa - self.first_sample, planes, samples)?),
            None => None,
        };
        Ok(Encoded { png, exr })
    }
}

impl Writers {
    /// Appends an encoded strip (strips in order).
    pub fn write(&mut self, strip: Encoded) -> Result<(), IoError> {
        if let (Some(w), Some(bytes)) = (self.png.as_mut(), strip.png) {
            w.write_encoded(&bytes)?;
        }
        if let (Some(w), Some(chunks)) = (self.exr.as_mut(), strip.exr) {
            w.write(chunks)?;
        }
        Ok(())
    }

    /// Completes every file and moves it into place.
    pub fn finish(self) -> Result<(), IoError> {
        if let Some(w) = self.png {
            w.finish()?;
        }
        if let Some(w) = self.exr {
            w.finish()?;
        }
        Ok(())
    }
}
