//! Work units of raw data: the EXR bands of `render --tile K/N --exr` joined into the
//! whole image's EXR (`deepfield assemble` given `.exr` units).
//!
//! A unit's EXR holds its band's sample rows (blocks counted from the band's first row)
//! and the [`TILE_ATTRIBUTE`], the same `K/N rows A..B of WxH` text as a PNG unit's chunk.
//! Bands start wherever the row split puts them, so their 16-line blocks do not line up
//! with the whole image's: the assembler decompresses each unit's blocks in order, cuts
//! the scan lines (each a whole line of every channel, so the cut needs no knowledge of
//! the channels) into the whole image's blocks, and compresses those again with the
//! whole image's header. Memory is a batch of blocks whatever the image size, and the
//! bytes are those the same render writes in one piece (the same header, lines and
//! compressor). Layers that colour from the whole image (histogram equalisation) are
//! coloured from the assembled file: `recolor whole.exr`.

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use ::exr::block::chunk::Chunk;
use ::exr::block::reader::ChunksReader;
use ::exr::block::{BlockIndex, UncompressedBlock};
use ::exr::math::Vec2;
use ::exr::meta::attribute::{AttributeValue, Text};
use ::exr::meta::header::Header;
use ::exr::meta::{BlockDescription, Headers};
use rayon::prelude::*;

use super::IoError;
use super::exr::{ExrWriter, SCENE_ATTRIBUTE, TILE_ATTRIBUTE};
use super::tile::{Band, band_rows, check_set, parse_tile_text};

/// Blocks compressed together (in parallel) before they are written in order.
const BATCH: usize = 64;

/// A unit's header and where its band lies.
struct Unit {
    band: Band,
    header: Header,
    /// Samples per pixel side.
    aa: usize,
}

fn text_attribute(header: &Header, name: &str) -> Option<String> {
    match header.own_attributes.other.get(&Text::from(name)) {
        Some(AttributeValue::Text(t)) => Some(String::from_utf8_lossy(t.bytes()).into_owned()),
        _ => None,
    }
}

fn read_unit(path: &Path) -> Result<Unit, IoError> {
    let file = File::open(path).map_err(|e| IoError::caused(path, e))?;
    let reader = ::exr::block::read(BufReader::new(file), false).map_err(|e| IoError::caused(path, e))?;
    let header = match reader.headers() {
        [h] if matches!(h.blocks, BlockDescription::ScanLines) && !h.deep => h.clone(),
        _ => return Err(IoError::new(path, "not a work unit: deepfield's units are single-part scan-line files")),
    };
    let tile = text_attribute(&header, TILE_ATTRIBUTE)
        .ok_or_else(|| IoError::new(path, "not a work unit: written without `render --tile K/N --exr`"))?;
    let scene = text_attribute(&header, SCENE_ATTRIBUTE).ok_or_else(|| IoError::new(path, "has no deepfield scene"))?;
    let (k, n, width, height) = parse_tile_text(path, &tile)?;
    let rows = band_rows(k, n, height);
    let (sw, sh) = (header.layer_size.0, header.layer_size.1);
    let aa = sw / width.max(1) as usize;
    if aa == 0 || sw != aa * width as usize || sh != aa * (rows.end - rows.start) as usize {
        return Err(IoError::new(
            path,
            format!("holds {sw}x{sh} samples, which is not band {k}/{n} of {width}x{height} at any supersampling"),
        ));
    }
    Ok(Unit { band: Band { path: path.to_path_buf(), k, n, width, height, bits: 0, scene }, header, aa })
}

/// Streams the EXR units at `paths` (any order) into the whole image's EXR at `out`.
/// Refuses, naming the file, units of different renders, a unit given twice, or a missing
/// one.
pub fn assemble_exr(paths: &[PathBuf], out: &Path, progress: &dyn Fn(u32, u32)) -> Result<(), IoError> {
    let mut units = paths.iter().map(|p| read_unit(p)).collect::<Result<Vec<_>, _>>()?;
    units.sort_by_key(|u| u.band.k);
    let bands: Vec<Band> = units.iter().map(|u| u.band.clone()).collect();
    check_set(&bands, paths.first(), out)?;
    let first = &units[0];
    if let Some(u) = units.iter().find(|u| u.aa != first.aa || u.header.channels != first.header.channels) {
        return Err(IoError::new(&u.band.path, "has other channels or supersampling than the first unit"));
    }
    let (w, h) = (first.band.width as usize * first.aa, first.band.height as usize * first.aa);
    let mut attributes = first.header.own_attributes.clone();
    attributes.other.remove(&Text::from(TILE_ATTRIBUTE));
    let name = attributes.layer_name.clone().unwrap_or_else(|| Text::from("deepfield"));
    let mut header = Header::new(name, Vec2(w, h), first.header.channels.list.clone()).with_encoding(
        first.header.compression,
        first.header.blocks,
        first.header.line_order,
    );
    header.own_attributes = attributes;
    let line_bytes: usize = header.channels.list.iter().map(|c| c.sample_type.bytes_per_sample() * w).sum();
    // The whole image keeps the units' compression, and so its block height.
    let block_lines = header.compression.scan_lines_per_block();
    let (mut writer, headers) = ExrWriter::with_header(out, header)?;

    let mut pending: Vec<u8> = Vec::new();
    let mut batch: Vec<(usize, Vec<u8>)> = Vec::new();
    let mut next_line = 0usize;
    let flush = |batch: &mut Vec<(usize, Vec<u8>)>, writer: &mut ExrWriter| -> Result<(), IoError> {
        let chunks = compress(&headers, w, line_bytes, block_lines, std::mem::take(batch))
            .map_err(|e| IoError::caused(out, e))?;
        writer.write(chunks)
    };
    for u in &units {
        let path = &u.band.path;
        let file = File::open(path).map_err(|e| IoError::caused(path, e))?;
        let reader = ::exr::block::read(BufReader::new(file), false).map_err(|e| IoError::caused(path, e))?;
        let mut expect = 0usize;
        let total = u.header.layer_size.1;
        for block in reader.all_chunks(false).map_err(|e| IoError::caused(path, e))?.sequential_decompressor(false) {
            let block = block.map_err(|e| IoError::caused(path, e))?;
            let lines = block.index.pixel_size.1;
            if block.index.pixel_position.1 != expect || block.data.len() != lines * line_bytes {
                return Err(IoError::new(path, "its blocks are not the scan lines of its band in order"));
            }
            expect += lines;
            pending.extend_from_slice(&block.data);
            while pending.len() >= block_lines * line_bytes {
                let rest = pending.split_off(block_lines * line_bytes);
                batch.push((next_line, std::mem::replace(&mut pending, rest)));
                next_line += block_lines;
                if batch.len() == BATCH {
                    flush(&mut batch, &mut writer)?;
                }
            }
        }
        if expect != total {
            return Err(IoError::new(path, format!("holds {expect} of its {total} scan lines: it is damaged")));
        }
        progress(((next_line + pending.len() / line_bytes) / u.aa) as u32, first.band.height);
    }
    if !pending.is_empty() {
        batch.push((next_line, pending));
    }
    flush(&mut batch, &mut writer)?;
    writer.finish()
}

/// Compresses blocks (first line, scan-line bytes) for the whole image, in parallel, in order.
fn compress(
    headers: &Headers,
    width: usize,
    line_bytes: usize,
    block_lines: usize,
    blocks: Vec<(usize, Vec<u8>)>,
) -> Result<Vec<(usize, Chunk)>, ::exr::error::Error> {
    blocks
        .into_par_iter()
        .map(|(y, data)| {
            let index = BlockIndex {
                layer: 0,
                pixel_position: Vec2(0, y),
                pixel_size: Vec2(width, data.len() / line_bytes),
                level: Vec2(0, 0),
            };
            let chunk = UncompressedBlock { index, data }.compress_to_chunk(headers)?;
            Ok((y / block_lines, chunk))
        })
        .collect()
}
