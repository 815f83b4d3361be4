//! Reading raw planes back from an OpenEXR file (ours, or any file with KF2+-style channels)
//! for recolouring without recomputing.
//!
//! Channels map back by name: `N` (u32), `NF`, `T`, `DEX`, `DEY` (f32), and our trap
//! channels `trapK.D` (geometric trap distance), `trapK.STRIPE` (stripe average) and
//! `trapK.R/G/B/A` (bitmap trap colour). The planes are cut into strips of whole rows so
//! colouring can run on all cores, and handed on strip by strip as the blocks decode
//! ([`ExrStrips`]), so that a recolour overlaps reading with colouring.

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, MutexGuard, PoisonError};

use ::exr::block::UncompressedBlock;
use ::exr::block::chunk::Chunk;
use ::exr::block::reader::{AllChunksReader, ChunksReader};
use ::exr::math::Vec2;
use ::exr::meta::BlockDescription;
use ::exr::meta::MetaData;
use ::exr::meta::attribute::SampleType;
use ::exr::prelude::{FlatSamples, ReadChannels, ReadLayers, f16, read};
use rayon::prelude::*;

use super::IoError;
use super::exr::SCENE_ATTRIBUTE;
use crate::field::{Channel, ChannelSet, Planes, TrapPlane};

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

/// The most a compressed EXR can expand: deflate (ZIP) reaches ~1032:1, the other
/// compressions less, so a file claiming more decoded bytes than this many times its size
/// is lying about its size (found by fuzzing: a 300-byte header claimed gigabytes).
const MAX_EXPANSION: u64 = 1100;

/// Refuses, before anything is allocated, a file whose header claims more decoded data than
/// its bytes can hold.
fn check_decoded_size(path: &Path, meta: &MetaData) -> Result<(), IoError> {
    let file_len = std::fs::metadata(path).map_err(|e| IoError::new(path, e))?.len();
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
/// A single-part scan-line file (what deepfield and Kalles Fraktaler write) is decoded
/// block by block straight into the strips, each block decompressed and converted by a
/// task on the current rayon pool, and each strip handed on as soon as its last row is in
/// ([`ExrStrips::for_each_strip`]): a recolour colours the first strips while later blocks
/// are still being decompressed, and holds only the strips in flight. Anything else (tiles,
/// mip levels, several parts) goes through the exr crate's whole-image reader first.
pub struct ExrStrips {
    path: PathBuf,
    header: RawHeader,
    rows_per: usize,
    source: Source,
}

/// Where an [`ExrStrips`] takes its strips from.
enum Source {
    /// The blocks still in the file, and how their lines map to planes.
    Blocks { chunks: Box<AllChunksReader<BufReader<File>>>, slots: Vec<(Slot, SampleType)>, line_bytes: usize },
    /// Strips already read by the whole-image reader.
    Whole(Vec<Planes>),
}

impl ExrStrips {
    /// Opens `path` and reads its header; the strips will hold `strip_rows` rows (at least 1).
    pub fn open(path: &Path, strip_rows: usize) -> Result<Self, IoError> {
        let file = File::open(path).map_err(|e| IoError::new(path, e))?;
        let reader = ::exr::block::read(BufReader::new(file), false).map_err(|e| IoError::new(path, e))?;
        check_decoded_size(path, reader.meta_data())?;
        let rows_per = strip_rows.max(1);
        if let Some(strips) = open_scanlines(path, reader, rows_per)? {
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
            Source::Blocks { chunks, slots, line_bytes } => {
                let layout = Layout { header: &self.header, rows_per: self.rows_per, slots, line_bytes };
                decode_blocks(*chunks, &layout, done).map_err(|e| IoError::new(&self.path, e))
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

/// A mutex's guard, whether or not another thread panicked while holding it (the data is
/// plain samples, valid either way).
fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
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

/// One sample (`bytes`, little-endian, of `kind`) as f32.
#[inline(always)]
fn float_of(b: &[u8], kind: SampleType) -> f32 {
    match kind {
        SampleType::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        SampleType::F16 => f16::from_bits(u16::from_le_bytes([b[0], b[1]])).to_f32(),
        SampleType::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32,
    }
}

/// Converts one line of samples (`bytes`, little-endian, of `kind`) to f32.
fn floats_into(dst: &mut [f32], bytes: &[u8], kind: SampleType) {
    let size = kind.bytes_per_sample();
    let pairs = dst.iter_mut().zip(bytes.chunks_exact(size));
    // One loop per kind, each a plain conversion loop (float_of inlines with its kind fixed).
    match kind {
        SampleType::F32 => pairs.for_each(|(d, b)| *d = float_of(b, SampleType::F32)),
        SampleType::F16 => pairs.for_each(|(d, b)| *d = float_of(b, SampleType::F16)),
        SampleType::U32 => pairs.for_each(|(d, b)| *d = float_of(b, SampleType::U32)),
    }
}

/// Opens the fast path of [`ExrStrips`]: `None` when the file is not a single-part,
/// single-level scan-line image with full-resolution channels.
fn open_scanlines(
    path: &Path,
    reader: ::exr::block::reader::Reader<BufReader<File>>,
    rows_per: usize,
) -> Result<Option<ExrStrips>, IoError> {
    let err = |e: ::exr::error::Error| IoError::new(path, e);
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
    let chunks = reader.all_chunks(false).map_err(err)?;
    Ok(Some(ExrStrips {
        path: path.to_path_buf(),
        header: raw,
        rows_per,
        source: Source::Blocks { chunks: Box::new(chunks), slots, line_bytes },
    }))
}

/// How the lines of a scan-line file's blocks map to strips and planes.
struct Layout<'a> {
    header: &'a RawHeader,
    rows_per: usize,
    slots: Vec<(Slot, SampleType)>,
    line_bytes: usize,
}

impl Layout<'_> {
    /// Planes for a strip of `rows` rows: handed-back planes of that size where `spare` holds
    /// some (every plane is overwritten line by line, but for a bitmap trap's colour plane,
    /// whose RGBA channels the file may hold only some of: that is zeroed), else new ones.
    fn planes_from(&self, rows: usize, spare: &Mutex<Vec<Planes>>) -> Planes {
        let reused = {
            let mut spare = lock(spare);
            let i = spare.iter().position(|p| p.rows == rows);
            i.map(|i| spare.swap_remove(i))
        };
        let Some(mut planes) = reused else { return self.planes(rows) };
        for t in &mut planes.traps {
            if let TrapPlane::Color(v) = t {
                v.fill([0.0; 4]);
            }
        }
        planes
    }

    /// Empty planes for a strip of `rows` rows (zeroed allocations: the pages are touched
    /// only as the lines arrive).
    fn planes(&self, rows: usize) -> Planes {
        let (width, channels) = (self.header.width, self.header.channels);
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
            traps: self
                .header
                .traps
                .iter()
                .map(|k| match k {
                    TrapKind::Distance => TrapPlane::Distance(vec![0.0; len]),
                    TrapKind::Stripe => TrapPlane::Stripe { value: vec![0.0; len], prev: Vec::new() },
                    TrapKind::Density => TrapPlane::Density(vec![0.0; len]),
                    TrapKind::Color => TrapPlane::Color(vec![[0.0; 4]; len]),
                })
                .collect(),
        }
    }

    /// Converts one scan line of a block into row `row` of `planes`.
    fn insert_line(&self, planes: &mut Planes, row: usize, line: &[u8]) {
        let width = self.header.width;
        let at = row * width..(row + 1) * width;
        let mut offset = 0;
        for &(slot, kind) in &self.slots {
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
                        for (d, b) in v[at.clone()].iter_mut().zip(bytes.chunks_exact(kind.bytes_per_sample())) {
                            d[i] = float_of(b, kind);
                        }
                    }
                }
                Slot::Skip => {}
            }
        }
    }
}

/// A strip whose rows are arriving.
#[derive(Default)]
struct Pending {
    /// Its planes, allocated when its first row arrives; taken when its last one has.
    planes: Option<Planes>,
    /// Which of its rows have arrived.
    seen: Vec<bool>,
    /// How many have.
    count: usize,
}

/// A damaged file's first fault, kept while the other tasks wind down.
type Fault = Mutex<Option<String>>;

/// Decompresses the blocks of a scan-line file on the current rayon pool, converts their
/// lines into strips and hands each complete strip to `done`. The thread reading the file
/// keeps at most a few blocks per worker in flight (it helps decompress while it waits), so
/// memory holds the strips being filled, not the file.
fn decode_blocks(
    chunks: AllChunksReader<BufReader<File>>,
    layout: &Layout<'_>,
    done: &(impl Fn(usize, Planes) -> Option<Planes> + Sync),
) -> Result<(), String> {
    let (height, rows_per) = (layout.header.height, layout.rows_per);
    let meta = chunks.meta_data().clone();
    let spare = Mutex::new(Vec::new());
    let pending: Vec<Mutex<Pending>> = (0..height.div_ceil(rows_per)).map(|_| Mutex::new(Pending::default())).collect();
    let fault: Fault = Mutex::new(None);
    let failed = AtomicBool::new(false);
    let in_flight = AtomicUsize::new(0);
    let limit = 4 * rayon::current_num_threads();
    let fail = |message: String| {
        failed.store(true, Ordering::Relaxed);
        lock(&fault).get_or_insert(message);
    };
    let (meta, pending, fail, in_flight, spare) = (&meta, &pending, &fail, &in_flight, &spare);
    rayon::scope(|s| {
        for chunk in chunks {
            if failed.load(Ordering::Relaxed) {
                break;
            }
            let chunk = match chunk {
                Ok(c) => c,
                Err(e) => {
                    fail(e.to_string());
                    break;
                }
            };
            while in_flight.load(Ordering::Acquire) >= limit {
                if !matches!(rayon::yield_now(), Some(rayon::Yield::Executed)) {
                    std::thread::yield_now();
                }
            }
            in_flight.fetch_add(1, Ordering::AcqRel);
            s.spawn(move |_| {
                let _counted = Leaving(in_flight);
                if let Err(e) = decode_block(chunk, meta, layout, pending, spare, done) {
                    fail(e);
                }
            });
        }
    });
    if let Some(message) = fault.into_inner().unwrap_or_else(PoisonError::into_inner) {
        return Err(message);
    }
    let lines: usize = pending.iter().map(|p| lock(p).count).sum();
    if lines != height {
        return Err(format!("the file holds {lines} of its {height} scan lines: it is damaged"));
    }
    Ok(())
}

/// Takes a block off the count in flight when its task ends, even by a panic (which the
/// scope then passes on): the reading loop must not wait for a task that is gone.
struct Leaving<'a>(&'a AtomicUsize);

impl Drop for Leaving<'_> {
    fn drop(&mut self) {
        self.0.fetch_sub(1, Ordering::AcqRel);
    }
}

/// Decompresses one block, puts its lines into their strips and hands on the strips it
/// completes.
fn decode_block(
    chunk: Chunk,
    meta: &MetaData,
    layout: &Layout<'_>,
    pending: &[Mutex<Pending>],
    spare: &Mutex<Vec<Planes>>,
    done: &(impl Fn(usize, Planes) -> Option<Planes> + Sync),
) -> Result<(), String> {
    let block = UncompressedBlock::decompress_chunk(chunk, meta, false).map_err(|e| e.to_string())?;
    let index = block.index;
    let (width, height, rows_per) = (layout.header.width, layout.header.height, layout.rows_per);
    if index.layer != 0 || index.level != Vec2(0, 0) {
        return Ok(());
    }
    let lines = index.pixel_size.1;
    if index.pixel_position.0 != 0 || index.pixel_size.0 != width || block.data.len() != lines * layout.line_bytes {
        return Err("a scan-line block of the wrong size".into());
    }
    for (l, line) in block.data.chunks_exact(layout.line_bytes).enumerate() {
        let y = index.pixel_position.1 + l;
        if y >= height {
            return Err("a scan line outside the data window".into());
        }
        let (k, row) = (y / rows_per, y % rows_per);
        let rows = rows_per.min(height - k * rows_per);
        let complete = {
            let mut p = lock(&pending[k]);
            if p.seen.is_empty() {
                p.seen = vec![false; rows];
                p.planes = Some(layout.planes_from(rows, spare));
            }
            if std::mem::replace(&mut p.seen[row], true) {
                return Err(format!("scan line {y} appears twice"));
            }
            let Some(planes) = p.planes.as_mut() else { return Err(format!("scan line {y} appears twice")) };
            layout.insert_line(planes, row, line);
            p.count += 1;
            if p.count == rows { p.planes.take() } else { None }
        };
        if let Some(back) = complete.and_then(|planes| done(k, planes)) {
            lock(spare).push(back);
        }
    }
    Ok(())
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
        let open = |rows: usize| {
            let reader = ::exr::block::read(BufReader::new(File::open(&path).unwrap()), false).unwrap();
            open_scanlines(&path, reader, rows).unwrap().expect("a scan-line file")
        };
        for rows in [1, 5, 32] {
            let strips = open(rows);
            assert!(matches!(strips.source, Source::Blocks { .. }));
            let fast = strips.collect().unwrap();
            let whole = read_whole_image(&path, rows).unwrap();
            assert_eq!(fast.strips, whole.strips, "{rows} rows per strip");
            assert_eq!(fast.header, whole.header);
            // Lent strips, whose planes are refilled for later strips, read the same.
            let lent: Vec<Mutex<Option<Planes>>> = whole.strips.iter().map(|_| Mutex::new(None)).collect();
            open(rows).for_each_strip_lent(|k, p| *lock(&lent[k]) = Some(p.clone())).unwrap();
            let lent: Vec<Planes> = lent.into_iter().map(|m| m.into_inner().unwrap().expect("every strip")).collect();
            assert_eq!(lent, whole.strips, "{rows} rows per strip, lent");
            let h0 = &fast.header;
            assert_eq!((h0.width, h0.height, &h0.scene), (w, h, &Some("version = 1".to_string())));
            assert_eq!(h0.traps, [TrapKind::Color, TrapKind::Distance]);
        }
        let raw = read_exr_planes(&path, 5).unwrap();
        // Strip 6 holds rows 30..35: its row 2 is row 32.
        assert_eq!(raw.strips[6].n[2 * w + 3], (32 * w as u32 + 3) * 3);
        std::fs::remove_file(&path).unwrap();
    }

    /// A file cut short is refused with the file named, whichever block the cut falls in,
    /// and never hands on a strip twice.
    #[test]
    fn truncated_files_are_refused() {
        let (w, h) = (19usize, 70usize);
        let channels = SpecificChannels::build()
            .with_channel("N")
            .with_channel("NF")
            .with_pixel_fn(|p: Vec2<usize>| ((p.1 * w + p.0) as u32, p.0 as f32 * 0.5));
        let layer = Layer::new(
            (w, h),
            LayerAttributes::named("deepfield"),
            Encoding { compression: Compression::RLE, blocks: Blocks::ScanLines, line_order: LineOrder::Increasing },
            channels,
        );
        let dir = std::env::temp_dir().join(format!("deepfield-exr-cut-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let whole = dir.join("whole.exr");
        Image::from_layer(layer).write().to_file(&whole).unwrap();
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
