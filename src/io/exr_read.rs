//! Reading raw planes back from an OpenEXR file (ours, or any file with KF2+-style channels)
//! for recolouring without recomputing.
//!
//! Channels map back by name: `N` (u32), `NF`, `T`, `DEX`, `DEY` (f32), and our trap
//! channels `trapK.D` (geometric trap distance), `trapK.STRIPE` (stripe average) and
//! `trapK.R/G/B/A` (bitmap trap colour). The planes are cut into strips of whole rows so
//! colouring can run on all cores.

use std::path::Path;

use ::exr::block::reader::ChunksReader;
use ::exr::math::Vec2;
use ::exr::meta::BlockDescription;
use ::exr::meta::attribute::SampleType;
use ::exr::prelude::{FlatSamples, ReadChannels, ReadLayers, f16, read};

use super::IoError;
use super::exr::SCENE_ATTRIBUTE;
use crate::field::{Channel, ChannelSet, Planes, TrapPlane};

/// The raw data of an EXR file.
#[derive(Debug, Clone)]
pub struct RawData {
    /// Samples per row.
    pub width: usize,
    /// Sample rows.
    pub height: usize,
    /// The scene stored in the header, if the file has one.
    pub scene: Option<String>,
    /// The planes, in strips of whole rows, top to bottom.
    pub strips: Vec<Planes>,
    /// Which of N, NF, T, DEX, DEY the file holds (N always: files without it are refused).
    pub channels: ChannelSet,
}

/// What one trap's channels hold.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrapKind {
    /// `trapK.D`.
    Distance,
    /// `trapK.STRIPE`.
    Stripe,
    /// `trapK.R/G/B/A`.
    Color,
    /// `trapK.IFS`.
    Density,
}

impl RawData {
    /// The kind of each trap plane, in trap order.
    pub fn trap_kinds(&self) -> Vec<TrapKind> {
        self.strips.first().map_or(Vec::new(), |s| {
            s.traps
                .iter()
                .map(|t| match t {
                    TrapPlane::Distance(_) => TrapKind::Distance,
                    TrapPlane::Stripe { .. } => TrapKind::Stripe,
                    TrapPlane::Color(_) => TrapKind::Color,
                    TrapPlane::Density(_) => TrapKind::Density,
                })
                .collect()
        })
    }
}

/// The most a compressed EXR can expand: deflate (ZIP) reaches ~1032:1, the other
/// compressions less, so a file claiming more decoded bytes than this many times its size
/// is lying about its size (found by fuzzing: a 300-byte header claimed gigabytes).
const MAX_EXPANSION: u64 = 1100;

/// Refuses, before anything is allocated, a file whose header claims more decoded data than
/// its bytes can hold.
fn check_decoded_size(path: &Path) -> Result<(), IoError> {
    let file_len = std::fs::metadata(path).map_err(|e| IoError::new(path, e))?.len();
    let meta = ::exr::meta::MetaData::read_from_file(path, false).map_err(|e| IoError::new(path, e))?;
    let mut claimed: u64 = 0;
    for h in meta.headers.iter() {
        let pixels = (h.layer_size.0 as u64).saturating_mul(h.layer_size.1 as u64);
        let per_pixel: u64 = h.channels.list.iter().map(|c| c.sample_type.bytes_per_sample() as u64).sum();
        claimed = claimed.saturating_add(pixels.saturating_mul(per_pixel));
    }
    if claimed > file_len.saturating_mul(MAX_EXPANSION) {
        return Err(IoError::new(
            path,
            format!(
                "its header claims {claimed} bytes of pixel data, more than its {file_len} bytes can hold: the file is damaged"
            ),
        ));
    }
    Ok(())
}

/// Reads every plane of `path`, cut into strips of `strip_rows` rows (at least 1).
///
/// A single-part scan-line file (what deepfield and Kalles Fraktaler write) is decoded block
/// by block straight into the strips, the blocks decompressed on every core
/// (`read_scanlines`); anything else (tiles, mip levels, several parts) goes through the
/// exr crate's whole-image reader.
pub fn read_exr_planes(path: &Path, strip_rows: usize) -> Result<RawData, IoError> {
    check_decoded_size(path)?;
    match read_scanlines(path, strip_rows.max(1))? {
        Some(raw) => Ok(raw),
        None => read_whole_image(path, strip_rows),
    }
}

/// Where one channel's samples go.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Slot {
    /// `N` (must be uint32).
    N,
    /// NF, T, DEX, DEY.
    Plane(Channel),
    /// A single-plane trap's channel (trap index).
    Trap(usize),
    /// Component `c` of a bitmap trap's colour (trap index, component).
    Color(usize, usize),
    /// A channel deepfield does not read.
    Skip,
}

/// The trap kinds present in a list of channel names: trap0, trap1, ... until one is
/// missing (as the whole-image reader finds them).
fn trap_layout(has: &dyn Fn(&str) -> bool) -> Vec<TrapKind> {
    let mut kinds = Vec::new();
    loop {
        let k = kinds.len();
        let h = |s: &str| has(&format!("trap{k}.{s}"));
        let kind = if h("D") {
            TrapKind::Distance
        } else if h("STRIPE") {
            TrapKind::Stripe
        } else if h("IFS") {
            TrapKind::Density
        } else if h("R") && h("G") && h("B") && h("A") {
            TrapKind::Color
        } else {
            return kinds;
        };
        kinds.push(kind);
    }
}

/// N and whichever of NF, T, DEX, DEY a file holds (by channel name).
fn plane_channels(has: &dyn Fn(&str) -> bool) -> ChannelSet {
    let mut channels = ChannelSet::default();
    channels.insert(Channel::N);
    for c in [Channel::NF, Channel::T, Channel::DEX, Channel::DEY] {
        if has(c.name()) {
            channels.insert(c);
        }
    }
    channels
}

/// The scene text stored in a header's attributes, if any.
fn scene_text(attributes: &::exr::meta::header::LayerAttributes) -> Option<String> {
    match attributes.other.get(&::exr::meta::attribute::Text::from(SCENE_ATTRIBUTE)) {
        Some(::exr::meta::attribute::AttributeValue::Text(t)) => Some(String::from_utf8_lossy(t.bytes()).into_owned()),
        _ => None,
    }
}

/// Why a file without an `N` channel is refused.
const NO_N: &str = "no N channel: this is not a raw-data EXR (render with --exr)";

/// The slot of channel `name` given the trap layout.
fn slot_of(name: &str, traps: &[TrapKind]) -> Slot {
    match name {
        "N" => return Slot::N,
        "NF" => return Slot::Plane(Channel::NF),
        "T" => return Slot::Plane(Channel::T),
        "DEX" => return Slot::Plane(Channel::DEX),
        "DEY" => return Slot::Plane(Channel::DEY),
        _ => {}
    }
    let Some((k, what)) = name.strip_prefix("trap").and_then(|r| r.split_once('.')) else { return Slot::Skip };
    let Ok(k) = k.parse::<usize>() else { return Slot::Skip };
    match (traps.get(k), what) {
        (Some(TrapKind::Distance), "D") | (Some(TrapKind::Stripe), "STRIPE") | (Some(TrapKind::Density), "IFS") => {
            Slot::Trap(k)
        }
        (Some(TrapKind::Color), c) => {
            ["R", "G", "B", "A"].iter().position(|x| *x == c).map_or(Slot::Skip, |i| Slot::Color(k, i))
        }
        _ => Slot::Skip,
    }
}

/// Converts one line of samples (`bytes`, little-endian, of `kind`) to f32.
fn floats_into(dst: &mut [f32], bytes: &[u8], kind: SampleType) {
    match kind {
        SampleType::F32 => {
            for (d, b) in dst.iter_mut().zip(bytes.chunks_exact(4)) {
                *d = f32::from_le_bytes([b[0], b[1], b[2], b[3]]);
            }
        }
        SampleType::F16 => {
            for (d, b) in dst.iter_mut().zip(bytes.chunks_exact(2)) {
                *d = f16::from_bits(u16::from_le_bytes([b[0], b[1]])).to_f32();
            }
        }
        SampleType::U32 => {
            for (d, b) in dst.iter_mut().zip(bytes.chunks_exact(4)) {
                *d = u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32;
            }
        }
    }
}

/// The fast path of [`read_exr_planes`]: `None` when the file is not a single-part,
/// single-level scan-line image with full-resolution channels.
fn read_scanlines(path: &Path, rows_per: usize) -> Result<Option<RawData>, IoError> {
    let err = |e: ::exr::error::Error| IoError::new(path, e);
    let file = std::fs::File::open(path).map_err(|e| IoError::new(path, e))?;
    let reader = ::exr::block::read(std::io::BufReader::new(file), false).map_err(err)?;
    let header = match reader.headers() {
        [h] => h.clone(),
        _ => return Ok(None),
    };
    if header.deep
        || !matches!(header.blocks, BlockDescription::ScanLines)
        || header.channels.list.iter().any(|c| c.sampling != Vec2(1, 1))
    {
        return Ok(None);
    }
    let (width, height) = (header.layer_size.0, header.layer_size.1);
    let names: Vec<String> =
        header.channels.list.iter().map(|c| String::from_utf8_lossy(c.name.bytes()).into_owned()).collect();
    let has = |n: &str| names.iter().any(|x| x == n);
    let traps = trap_layout(&has);
    let slots: Vec<(Slot, SampleType)> =
        names.iter().zip(&header.channels.list).map(|(n, c)| (slot_of(n, &traps), c.sample_type)).collect();
    match slots.iter().find(|(s, _)| *s == Slot::N) {
        None => return Err(IoError::new(path, NO_N)),
        Some((_, t)) if *t != SampleType::U32 => return Err(IoError::new(path, "channel N is not uint32")),
        _ => {}
    }
    let channels = plane_channels(&has);
    let scene = scene_text(&header.own_attributes);
    let mut strips: Vec<Planes> = (0..height)
        .step_by(rows_per)
        .map(|r0| {
            let rows = rows_per.min(height - r0);
            let len = rows * width;
            let plane = |c: Channel| if channels.contains(c) { vec![0.0f32; len] } else { Vec::new() };
            Planes {
                width,
                rows,
                n: vec![0; len],
                nf: plane(Channel::NF),
                t: plane(Channel::T),
                dex: plane(Channel::DEX),
                dey: plane(Channel::DEY),
                traps: traps
                    .iter()
                    .map(|k| match k {
                        TrapKind::Distance => TrapPlane::Distance(vec![0.0; len]),
                        TrapKind::Stripe => TrapPlane::Stripe { value: vec![0.0; len], prev: Vec::new() },
                        TrapKind::Density => TrapPlane::Density(vec![0.0; len]),
                        TrapKind::Color => TrapPlane::Color(vec![[0.0; 4]; len]),
                    })
                    .collect(),
            }
        })
        .collect();
    let line_bytes: usize = header.channels.list.iter().map(|c| c.sample_type.bytes_per_sample() * width).sum();
    let mut lines_read = 0usize;
    let mut scratch = vec![0.0f32; width];
    let insert = |_: &::exr::meta::MetaData, block: ::exr::block::UncompressedBlock| -> ::exr::error::UnitResult {
        let index = block.index;
        if index.layer != 0 || index.level != Vec2(0, 0) {
            return Ok(());
        }
        let lines = index.pixel_size.1;
        if index.pixel_position.0 != 0 || index.pixel_size.0 != width || block.data.len() != lines * line_bytes {
            return Err(::exr::error::Error::Invalid("a scan-line block of the wrong size".into()));
        }
        for (l, line) in block.data.chunks_exact(line_bytes).enumerate() {
            let y = index.pixel_position.1 + l;
            if y >= height {
                return Err(::exr::error::Error::Invalid("a scan line outside the data window".into()));
            }
            let planes = &mut strips[y / rows_per];
            let at = (y % rows_per) * width..(y % rows_per + 1) * width;
            let mut offset = 0;
            for &(slot, kind) in &slots {
                let bytes = &line[offset..offset + kind.bytes_per_sample() * width];
                offset += bytes.len();
                match slot {
                    Slot::N => {
                        for (d, b) in planes.n[at.clone()].iter_mut().zip(bytes.chunks_exact(4)) {
                            *d = u32::from_le_bytes([b[0], b[1], b[2], b[3]]);
                        }
                    }
                    Slot::Plane(c) => {
                        let dst = match c {
                            Channel::NF => &mut planes.nf,
                            Channel::T => &mut planes.t,
                            Channel::DEX => &mut planes.dex,
                            _ => &mut planes.dey,
                        };
                        floats_into(&mut dst[at.clone()], bytes, kind);
                    }
                    Slot::Trap(k) => match &mut planes.traps[k] {
                        TrapPlane::Distance(v) | TrapPlane::Density(v) | TrapPlane::Stripe { value: v, .. } => {
                            floats_into(&mut v[at.clone()], bytes, kind)
                        }
                        TrapPlane::Color(_) => {}
                    },
                    Slot::Color(k, i) => {
                        if let TrapPlane::Color(v) = &mut planes.traps[k] {
                            floats_into(&mut scratch, bytes, kind);
                            for (d, s) in v[at.clone()].iter_mut().zip(&scratch) {
                                d[i] = *s;
                            }
                        }
                    }
                    Slot::Skip => {}
                }
            }
            lines_read += 1;
        }
        Ok(())
    };
    reader.all_chunks(false).map_err(err)?.decompress_parallel(false, insert).map_err(err)?;
    if lines_read != height {
        return Err(IoError::new(
            path,
            format!("the file holds {lines_read} of its {height} scan lines: it is damaged"),
        ));
    }
    Ok(Some(RawData { width, height, scene, strips, channels }))
}

/// Every plane through the exr crate's whole-image reader (tiled and multi-level files).
fn read_whole_image(path: &Path, strip_rows: usize) -> Result<RawData, IoError> {
    let image = read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|e| IoError::new(path, e))?;
    let layer = &image.layer_data;
    let (width, height) = (layer.size.0, layer.size.1);
    let scene = scene_text(&layer.attributes);
    let mut n: Option<Vec<u32>> = None;
    let mut floats: Vec<(String, Vec<f32>)> = Vec::new();
    for ch in &layer.channel_data.list {
        let name = String::from_utf8_lossy(ch.name.bytes()).into_owned();
        match (&ch.sample_data, name.as_str()) {
            (FlatSamples::U32(v), "N") => n = Some(v.clone()),
            (_, "N") => return Err(IoError::new(path, "channel N is not uint32")),
            (FlatSamples::F32(v), _) => floats.push((name, v.clone())),
            (FlatSamples::F16(v), _) => floats.push((name, v.iter().map(|h| h.to_f32()).collect())),
            (FlatSamples::U32(v), _) => floats.push((name, v.iter().map(|&x| x as f32).collect())),
        }
    }
    let n = n.ok_or_else(|| IoError::new(path, NO_N))?;
    let take = |name: &str| floats.iter().find(|(n, _)| n == name).map(|(_, v)| v.as_slice());
    let channels = plane_channels(&|name| take(name).is_some());
    // Trap planes, by index: trap0, trap1, ... until one is missing.
    let traps: Vec<(TrapKind, Vec<&[f32]>)> = trap_layout(&|n| take(n).is_some())
        .into_iter()
        .enumerate()
        .map(|(k, kind)| {
            let parts: &[&str] = match kind {
                TrapKind::Distance => &["D"],
                TrapKind::Stripe => &["STRIPE"],
                TrapKind::Density => &["IFS"],
                TrapKind::Color => &["R", "G", "B", "A"],
            };
            (kind, parts.iter().filter_map(|p| take(&format!("trap{k}.{p}"))).collect())
        })
        .collect();
    let rows_per = strip_rows.max(1);
    let mut strips = Vec::with_capacity(height.div_ceil(rows_per));
    for r0 in (0..height).step_by(rows_per) {
        let rows = rows_per.min(height - r0);
        let span = r0 * width..(r0 + rows) * width;
        let plane = |name: &str| take(name).map_or(Vec::new(), |v| v[span.clone()].to_vec());
        let trap_planes = traps
            .iter()
            .map(|(kind, chans)| match kind {
                TrapKind::Distance => TrapPlane::Distance(chans[0][span.clone()].to_vec()),
                TrapKind::Stripe => TrapPlane::Stripe { value: chans[0][span.clone()].to_vec(), prev: Vec::new() },
                TrapKind::Density => TrapPlane::Density(chans[0][span.clone()].to_vec()),
                TrapKind::Color => TrapPlane::Color(
                    span.clone().map(|i| [chans[0][i], chans[1][i], chans[2][i], chans[3][i]]).collect(),
                ),
            })
            .collect();
        strips.push(Planes {
            width,
            rows,
            n: n[span.clone()].to_vec(),
            nf: plane("NF"),
            t: plane("T"),
            dex: plane("DEX"),
            dey: plane("DEY"),
            traps: trap_planes,
        });
    }
    Ok(RawData { width, height, scene, strips, channels })
}

#[cfg(test)]
mod tests {
    use ::exr::prelude::*;

    use super::*;

    /// A file with every kind of channel the reader maps (u32 N, f16 NF, f32 DEX, a colour
    /// trap, a distance trap as u32) and one it skips, ZIP-compressed in 16-line blocks over
    /// 37 rows: the block path and the whole-image path read the same planes.
    #[test]
    fn block_and_whole_image_readers_agree() {
        let (w, h) = (7usize, 37usize);
        let k = |x: usize, y: usize| (y * w + x) as f32;
        let channels = SpecificChannels::build()
            .with_channel("N")
            .with_channel("NF")
            .with_channel("DEX")
            .with_channel("Z")
            .with_channel("trap0.R")
            .with_channel("trap0.G")
            .with_channel("trap0.B")
            .with_channel("trap0.A")
            .with_channel("trap1.D")
            .with_pixel_fn(|p: Vec2<usize>| {
                let v = k(p.0, p.1);
                (
                    (v as u32) * 3,
                    f16::from_f32(v / 300.0),
                    -v,
                    v * 7.0,
                    v + 0.25,
                    v + 0.5,
                    v + 0.75,
                    1.0f32,
                    (v as u32) + 9,
                )
            });
        let mut layer = Layer::new(
            (w, h),
            LayerAttributes::named("deepfield"),
            Encoding { compression: Compression::ZIP16, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing },
            channels,
        );
        layer.attributes.other.insert(Text::from(SCENE_ATTRIBUTE), AttributeValue::Text(Text::from("version = 1")));
        let path = std::env::temp_dir().join(format!("deepfield-exr-read-{}.exr", std::process::id()));
        Image::from_layer(layer).write().to_file(&path).unwrap();
        for rows in [1, 5, 32] {
            let fast = read_scanlines(&path, rows).unwrap().expect("a scan-line file");
            let whole = read_whole_image(&path, rows).unwrap();
            assert_eq!(fast.strips, whole.strips, "{rows} rows per strip");
            assert_eq!((fast.width, fast.height, &fast.scene), (w, h, &Some("version = 1".to_string())));
            assert_eq!(fast.channels, whole.channels);
            assert_eq!(fast.trap_kinds(), [TrapKind::Color, TrapKind::Distance]);
        }
        let raw = read_exr_planes(&path, 5).unwrap();
        // Strip 6 holds rows 30..35: its row 2 is row 32.
        assert_eq!(raw.strips[6].n[2 * w + 3], (32 * w as u32 + 3) * 3);
        std::fs::remove_file(&path).unwrap();
    }
}
