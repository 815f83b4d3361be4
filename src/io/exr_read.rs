//! Reading raw planes back from an OpenEXR file (ours, or any file with KF2+-style channels)
//! for recolouring without recomputing.
//!
//! Channels map back by name: `N` (u32), `NF`, `T`, `DEX`, `DEY` (f32), and our trap
//! channels `trapK.D` (geometric trap distance), `trapK.STRIPE` (stripe average) and
//! `trapK.R/G/B/A` (bitmap trap colour). The planes are cut into strips of whole rows so
//! colouring can run on all cores, and handed on strip by strip as they are read
//! ([`ExrStrips`]), so that a recolour overlaps reading with colouring. This module chooses
//! the reader; the readers themselves, how a line maps onto planes and the types they hand
//! on live beside it (`exr_plain`, `exr_blocks`, `exr_lines`, `exr_raw`).

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::{Mutex, PoisonError};

use ::exr::block::reader::AllChunksReader;
use ::exr::math::Vec2;
use ::exr::meta::BlockDescription;
use ::exr::meta::MetaData;
use ::exr::meta::attribute::SampleType;
use ::exr::prelude::{FlatSamples, ReadChannels, ReadLayers, read};
use rayon::prelude::*;

use super::IoError;
use super::exr::SCENE_ATTRIBUTE;
use super::exr_blocks::decode_blocks;
use super::exr_lines::{Layout, Slot, lock, slot_of};
use super::exr_plain::PlainBlocks;
pub use super::exr_raw::{RawData, RawHeader};
use crate::field::{Channel, ChannelSet, Planes, TrapPlane};
use crate::trap::TrapKind;

/// The most a compressed EXR can expand: deflate (ZIP) reaches ~1032:1, the other
/// compressions less, so a file claiming more decoded bytes than this many times its size
/// is lying about its size (found by fuzzing: a 300-byte header claimed gigabytes).
const MAX_EXPANSION: u64 = 1100;

/// Refuses, before anything is allocated, a file whose header claims more decoded data than
/// its bytes can hold.
fn check_decoded_size(path: &Path, meta: &MetaData) -> Result<(), IoError> {
    let file_len = std::fs::metadata(path).map_err(|e| IoError::caused(path, e))?.len();
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

/// Reads every plane of `path`, cut into strips of `strip_rows` rows (at least 1), decoding
/// on the current rayon pool ([`ExrStrips`]).
pub fn read_exr_planes(path: &Path, strip_rows: usize) -> Result<RawData, IoError> {
    ExrStrips::open(path, strip_rows)?.collect()
}

/// An EXR opened for reading strip by strip: its header read, its pixel data not yet.
///
/// A single-part scan-line file (what deepfield and Kalles Fraktaler write) is read straight
/// into the strips on the current rayon pool, and each strip handed on as soon as its last
/// row is in ([`ExrStrips::for_each_strip`]): a recolour colours the first strips while later
/// ones are still being read, and holds only the strips in flight. An uncompressed file (what
/// deepfield writes) is read in place on little-endian Unix machines when its offset table
/// checks out, each worker reading its strip's lines from the file (`exr_plain`); other
/// scan-line files are decompressed block by block (`exr_blocks`). Anything
/// else (tiles, mip levels, several parts) goes through the exr crate's whole-image reader
/// first.
pub struct ExrStrips {
    path: PathBuf,
    header: RawHeader,
    rows_per: usize,
    source: Source,
}

/// Where an [`ExrStrips`] takes its strips from.
enum Source {
    /// A scan-line file's lines, still in the file, and how they map to planes.
    Lines { reader: LineReader, slots: Vec<(Slot, SampleType)>, line_bytes: usize },
    /// Strips already read by the whole-image reader.
    Whole(Vec<Planes>),
}

/// Which reader takes a scan-line file's lines out of it.
enum LineReader {
    /// The block decoder (`exr_blocks`), with the blocks still to be read.
    Blocks(Box<AllChunksReader<BufReader<File>>>),
    /// The in-place reader of an uncompressed file (`exr_plain`).
    InPlace(PlainBlocks),
}

impl ExrStrips {
    /// Opens `path` and reads its header; the strips will hold `strip_rows` rows (at least 1).
    pub fn open(path: &Path, strip_rows: usize) -> Result<Self, IoError> {
        let file = File::open(path).map_err(|e| IoError::caused(path, e))?;
        let reader = ::exr::block::read(BufReader::new(file), false).map_err(|e| IoError::caused(path, e))?;
        check_decoded_size(path, reader.meta_data())?;
        let rows_per = strip_rows.max(1);
        if let Some(strips) = open_scanlines(path, reader, rows_per, true)? {
            return Ok(strips);
        }
        let raw = read_whole_image(path, rows_per)?;
        Ok(Self { path: path.to_path_buf(), header: raw.header, rows_per, source: Source::Whole(raw.strips) })
    }

    /// What the header says.
    pub fn header(&self) -> &RawHeader {
        &self.header
    }

    /// Decodes the pixel data on the current rayon pool and calls `done` with each strip
    /// (its index from the top, its planes) once all its rows are in: on a worker thread, in
    /// no particular order, every strip exactly once when the result is `Ok`. A damaged
    /// file stops the decoding at its first fault (some strips may have been handed on).
    pub fn for_each_strip(self, done: impl Fn(usize, Planes) + Sync) -> Result<(), IoError> {
        self.strips(&|k, planes| {
            done(k, planes);
            None
        })
    }

    /// [`ExrStrips::for_each_strip`], lending each strip to `done` instead of giving it:
    /// once `done` returns, the strip's planes are filled again with a later strip's rows,
    /// so reading allocates a few strips' planes in all, not one per strip (no zeroing and
    /// no page faults per strip).
    pub fn for_each_strip_lent(self, done: impl Fn(usize, &Planes) + Sync) -> Result<(), IoError> {
        self.strips(&|k, planes| {
            done(k, &planes);
            Some(planes)
        })
    }

    /// The strips, each handed to `done`, which may hand the planes back for reuse.
    fn strips(self, done: &(impl Fn(usize, Planes) -> Option<Planes> + Sync)) -> Result<(), IoError> {
        match self.source {
            Source::Whole(strips) => {
                strips.into_par_iter().enumerate().for_each(|(k, p)| drop(done(k, p)));
                Ok(())
            }
            Source::Lines { reader, slots, line_bytes } => {
                let layout = Layout { header: &self.header, rows_per: self.rows_per, slots, line_bytes };
                match reader {
                    LineReader::Blocks(chunks) => decode_blocks(*chunks, &layout, done),
                    LineReader::InPlace(blocks) => blocks.read_strips(&layout, done),
                }
                .map_err(|fault| fault.at(&self.path))
            }
        }
    }

    /// Every strip, in order.
    pub fn collect(self) -> Result<RawData, IoError> {
        let header = self.header.clone();
        let count = header.height.div_ceil(self.rows_per);
        let slots: Vec<Mutex<Option<Planes>>> = (0..count).map(|_| Mutex::new(None)).collect();
        self.for_each_strip(|k, planes| *lock(&slots[k]) = Some(planes))?;
        let strips = slots.into_iter().filter_map(|m| m.into_inner().unwrap_or_else(PoisonError::into_inner)).collect();
        Ok(RawData { header, strips })
    }
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

/// Opens the fast paths of [`ExrStrips`]: `None` when the file is not a single-part,
/// single-level scan-line image with full-resolution channels. An uncompressed file is read
/// in place where `in_place` allows and [`PlainBlocks`] serves it; other files go through
/// the block decoder.
fn open_scanlines(
    path: &Path,
    reader: ::exr::block::reader::Reader<BufReader<File>>,
    rows_per: usize,
    in_place: bool,
) -> Result<Option<ExrStrips>, IoError> {
    let err = |e: ::exr::error::Error| IoError::caused(path, e);
    let err_io = |e: std::io::Error| IoError::caused(path, e);
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
    let line_bytes: usize = header.channels.list.iter().map(|c| c.sample_type.bytes_per_sample() * width).sum();
    let raw =
        RawHeader { width, height, scene: scene_text(&header.own_attributes), channels: plane_channels(&has), traps };
    let plain = if in_place { PlainBlocks::locate(path, &header, line_bytes).map_err(err_io)? } else { None };
    let reader = match plain {
        Some(blocks) => LineReader::InPlace(blocks),
        None => LineReader::Blocks(Box::new(reader.all_chunks(false).map_err(err)?)),
    };
    let source = Source::Lines { reader, slots, line_bytes };
    Ok(Some(ExrStrips { path: path.to_path_buf(), header: raw, rows_per, source }))
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
        .map_err(|e| IoError::caused(path, e))?;
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
    let kinds = trap_layout(&|n| take(n).is_some());
    // Trap planes, by index: trap0, trap1, ... until one is missing.
    let traps: Vec<(TrapKind, Vec<&[f32]>)> = kinds
        .iter()
        .copied()
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
    Ok(RawData { header: RawHeader { width, height, scene, channels, traps: kinds }, strips })
}

#[cfg(test)]
mod tests {
    use ::exr::prelude::*;

    use super::*;

    /// A file with every kind of channel the reader maps (u32 N, f16 NF, f32 DEX, a colour
    /// trap, a distance trap as u32) and one it skips, ZIP-compressed in 16-line blocks over
    /// 37 rows, RLE-compressed in 1-line blocks and uncompressed: the two paths read the same
    /// planes.
    #[test]
    fn block_and_whole_image_readers_agree() {
        for compression in [Compression::ZIP16, Compression::RLE, Compression::Uncompressed] {
            readers_agree(compression);
        }
    }

    fn readers_agree(compression: Compression) {
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
            Encoding { compression, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing },
            channels,
        );
        layer.attributes.other.insert(Text::from(SCENE_ATTRIBUTE), AttributeValue::Text(Text::from("version = 1")));
        let path = std::env::temp_dir().join(format!("deepfield-exr-read-{}-{compression:?}.exr", std::process::id()));
        Image::from_layer(layer).write().to_file(&path).unwrap();
        let open = |rows: usize, in_place: bool| {
            let reader = ::exr::block::read(BufReader::new(File::open(&path).unwrap()), false).unwrap();
            open_scanlines(&path, reader, rows, in_place).unwrap().expect("a scan-line file")
        };
        // Uncompressed files are read in place on Unix (and by the block decoder when told to).
        let paths: &[bool] =
            if compression == Compression::Uncompressed && cfg!(unix) { &[true, false] } else { &[true] };
        for rows in [1, 5, 32] {
            let whole = read_whole_image(&path, rows).unwrap();
            for &in_place in paths {
                let strips = open(rows, in_place);
                let Source::Lines { reader, .. } = &strips.source else { panic!("not read by lines") };
                let plain = matches!(reader, LineReader::InPlace(_));
                assert_eq!(plain, in_place && paths.len() == 2, "{compression:?}, in place {in_place}");
                let fast = strips.collect().unwrap();
                assert_eq!(fast.strips, whole.strips, "{rows} rows per strip, in place {in_place}");
                assert_eq!(fast.header, whole.header);
                // Lent strips, whose planes are refilled for later strips, read the same.
                let lent: Vec<Mutex<Option<Planes>>> = whole.strips.iter().map(|_| Mutex::new(None)).collect();
                open(rows, in_place).for_each_strip_lent(|k, p| *lock(&lent[k]) = Some(p.clone())).unwrap();
                let lent: Vec<Planes> =
                    lent.into_iter().map(|m| m.into_inner().unwrap().expect("every strip")).collect();
                assert_eq!(lent, whole.strips, "{rows} rows per strip, lent, in place {in_place}");
                let h0 = &fast.header;
                assert_eq!((h0.width, h0.height, &h0.scene), (w, h, &Some("version = 1".to_string())));
                assert_eq!(h0.traps, [TrapKind::Color, TrapKind::Distance]);
            }
        }
        let raw = read_exr_planes(&path, 5).unwrap();
        // Strip 6 holds rows 30..35: its row 2 is row 32.
        assert_eq!(raw.strips[6].n[2 * w + 3], (32 * w as u32 + 3) * 3);
        std::fs::remove_file(&path).unwrap();
    }

    /// A file cut short is refused with the file named, whichever block the cut falls in,
    /// and never hands on a strip twice: compressed, and uncompressed (whose offset table
    /// then points past the end, so the block decoder reads it).
    #[test]
    fn truncated_files_are_refused() {
        for compression in [Compression::RLE, Compression::Uncompressed] {
            truncated_file_is_refused(compression);
        }
    }

    fn truncated_file_is_refused(compression: Compression) {
        let (w, h) = (19usize, 70usize);
        let dir = std::env::temp_dir().join(format!("deepfield-exr-cut-{}-{compression:?}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let whole = dir.join("whole.exr");
        crate::io::exr_test_file::write_n_nf(&whole, (w, h), (0, 0), compression);
        let bytes = std::fs::read(&whole).unwrap();
        let full = read_exr_planes(&whole, 8).unwrap();
        assert_eq!(full.strips.len(), 9);
        assert_eq!(full.strips[8].n[w * 5 + 2], (69 * w + 2) as u32);
        for keep in [bytes.len() - 1, bytes.len() * 3 / 4, bytes.len() / 2] {
            let cut = dir.join(format!("cut{keep}.exr"));
            std::fs::write(&cut, &bytes[..keep]).unwrap();
            let seen = Mutex::new(vec![0u32; 9]);
            let open = ExrStrips::open(&cut, 8);
            let result = open.and_then(|s| s.for_each_strip(|k, _| lock(&seen)[k] += 1));
            let e = result.expect_err("a cut file was read");
            assert!(e.to_string().contains("cut"), "{e}");
            assert!(lock(&seen).iter().all(|&c| c <= 1));
        }
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
