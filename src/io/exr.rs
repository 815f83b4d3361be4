//! Streaming OpenEXR output of the raw planes, channels named as in KF2+ / Fraktaler-3.
//!
//! Scan-line blocks, uncompressed ([`COMPRESSION`]). Blocks are built and compressed by the
//! render workers ([`ExrWriter::encode`], parallel) and written in order by a dedicated
//! thread that owns the file, because the exr crate's block writer drives the file from a
//! closure. The scene TOML and the engine's choice go into the header as text attributes.

use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::thread::JoinHandle;

use ::exr::block::chunk::Chunk;
use ::exr::block::{BlockIndex, UncompressedBlock};
use ::exr::math::Vec2;
use ::exr::meta::attribute::{AttributeValue, ChannelDescription, SampleType, Text};
use ::exr::meta::header::Header;
use ::exr::meta::{BlockDescription, Headers};
use ::exr::prelude::{Compression, LineOrder, SmallVec};

use super::atomic::{AtomicFile, Tail, TailError, take_tail_error};
use super::{Cause, IoError};
use crate::field::{Channel, ChannelSet, Planes, TrapPlane};
use crate::trap::Trap;

/// Header attribute holding the scene TOML.
pub const SCENE_ATTRIBUTE: &str = "deepfield.scene";
/// Header attribute of a work unit's place in the whole image (`render --tile K/N --exr`),
/// in the text of [`super::tile_text`].
pub const TILE_ATTRIBUTE: &str = "deepfield.tile";
/// How the planes are stored: uncompressed, chosen by measurement for recolouring, which
/// reads the whole file every time. A 3840x2160 seahorse-valley render (`N`, `NF`, `DEX`,
/// `DEY`) is 134.7 MB with ZIP, 152.6 MB with RLE and 165.9 MB uncompressed (float planes
/// barely compress); its two-layer recolour on one thread takes 4.94e9 instructions from
/// the RLE file and 3.98e9 from the uncompressed one (valgrind; the difference is RLE
/// decoding and the `exr` crate's copies), 0.43 against 0.37 s wall on two cores (nine
/// alternating runs each; `scripts/ab-run.sh`). Where RLE saves most, a render with a
/// large interior (1920x1080 minibrot-e102: 26.6 MB RLE, 41.5 MB uncompressed), the file
/// is small either way. Every OpenEXR reader (Kalles Fraktaler's and Fraktaler-3's tools,
/// zoomasm) reads uncompressed files; deepfield reads files of any compression.
pub const COMPRESSION: Compression = Compression::Uncompressed;

#[derive(Debug, Clone, Copy, PartialEq)]
enum Source {
    N,
    NF,
    T,
    Dex,
    Dey,
    TrapDistance(usize),
    TrapColor(usize, usize),
    TrapStripe(usize),
    Color(usize),
}

/// Which channels a file holds, in the (sorted) order EXR stores them.
#[derive(Debug, Clone, PartialEq)]
pub struct ExrLayout {
    channels: Vec<(String, Source)>,
}

impl ExrLayout {
    /// Channels for a channel set; trap channels (`trapK.D`, or `trapK.R/G/B/A` for bitmap
    /// traps) are included when the set holds [`Channel::Traps`].
    pub fn new(set: ChannelSet, traps: &[Trap]) -> Self {
        let mut channels = Vec::new();
        for c in set.iter() {
            match c {
                Channel::N => channels.push(("N".to_string(), Source::N)),
                Channel::NF => channels.push(("NF".into(), Source::NF)),
                Channel::T => channels.push(("T".into(), Source::T)),
                Channel::DEX => channels.push(("DEX".into(), Source::Dex)),
                Channel::DEY => channels.push(("DEY".into(), Source::Dey)),
                Channel::Rgb => {
                    for (i, n) in ["R", "G", "B"].iter().enumerate() {
                        channels.push((n.to_string(), Source::Color(i)));
                    }
                }
                Channel::Traps => {
                    for (k, t) in traps.iter().enumerate() {
                        match t {
                            Trap::Geometric(_) => channels.push((format!("trap{k}.D"), Source::TrapDistance(k))),
                            Trap::Stripe(_) => channels.push((format!("trap{k}.STRIPE"), Source::TrapStripe(k))),
                            Trap::Ifs(_) => channels.push((format!("trap{k}.IFS"), Source::TrapStripe(k))),
                            Trap::Bitmap(_) => {
                                for (i, n) in ["R", "G", "B", "A"].iter().enumerate() {
                                    channels.push((format!("trap{k}.{n}"), Source::TrapColor(k, i)));
                                }
                            }
                        }
                    }
                }
            }
        }
        channels.sort_by(|a, b| a.0.cmp(&b.0));
        Self { channels }
    }

    /// Channel names in file order.
    pub fn names(&self) -> Vec<&str> {
        self.channels.iter().map(|(n, _)| n.as_str()).collect()
    }

    /// The header. Only one custom attribute (the scene) is used: the exr crate keeps custom
    /// attributes in a hash map whose order varies between runs, and files must be
    /// byte-identical run to run. The engine's choice goes into the standard `comments`.
    fn header(&self, width: usize, height: usize, scene_toml: &str, engine: &str) -> Header {
        let descs: SmallVec<[ChannelDescription; 5]> = self
            .channels
            .iter()
            .map(|(name, src)| {
                let ty = match src {
                    Source::N => SampleType::U32,
                    Source::Color(_) => SampleType::F16,
                    _ => SampleType::F32,
                };
                ChannelDescription::new(name.as_str(), ty, false)
            })
            .collect();
        let mut header = Header::new(Text::from("deepfield"), Vec2(width, height), descs).with_encoding(
            COMPRESSION,
            BlockDescription::ScanLines,
            LineOrder::Increasing,
        );
        header.own_attributes.other.insert(Text::from(SCENE_ATTRIBUTE), AttributeValue::Text(utf8_text(scene_toml)));
        header.own_attributes.comments = Some(utf8_text(engine));
        header.own_attributes.software_name = Some(Text::from(concat!("deepfield ", env!("CARGO_PKG_VERSION"))));
        header
    }
}

/// Writes the planes of a sample raster, strip by strip, top to bottom.
pub struct ExrWriter {
    sender: Option<mpsc::SyncSender<(usize, Chunk)>>,
    thread: Option<JoinHandle<Result<(), ::exr::error::Error>>>,
    tail_error: TailError,
    file: Option<AtomicFile>,
}

/// Builds and compresses blocks for an [`ExrWriter`]; shareable across threads.
#[derive(Debug, Clone)]
pub struct ExrEncoder {
    /// The file the blocks are for, named in errors.
    path: PathBuf,
    headers: Headers,
    layout: ExrLayout,
    width: usize,
}

impl ExrWriter {
    /// Starts an EXR of `width` x `height` samples at `path`; returns the writer and the
    /// encoder that prepares its blocks.
    pub fn create(
        path: &Path,
        width: u32,
        height: u32,
        layout: ExrLayout,
        scene_toml: &str,
        engine: &str,
    ) -> Result<(Self, ExrEncoder), IoError> {
        if layout.channels.is_empty() {
            return Err(IoError::new(path, "no channels to write (choose some with --channels)"));
        }
        let header = layout.header(width as usize, height as usize, scene_toml, engine);
        let (writer, headers) = Self::with_header(path, header)?;
        Ok((writer, ExrEncoder { path: path.to_path_buf(), headers, layout, width: width as usize }))
    }

    /// [`ExrWriter::create`] for one work unit of `render --tile`: `rows` sample rows of
    /// the whole image (blocks counted from the unit's first row) and the unit's place in
    /// the [`TILE_ATTRIBUTE`].
    pub fn create_unit(
        path: &Path,
        width: u32,
        rows: u32,
        layout: ExrLayout,
        scene_toml: &str,
        engine: &str,
        tile: &str,
    ) -> Result<(Self, ExrEncoder), IoError> {
        if layout.channels.is_empty() {
            return Err(IoError::new(path, "no channels to write (choose some with --channels)"));
        }
        let mut header = layout.header(width as usize, rows as usize, scene_toml, engine);
        header.own_attributes.other.insert(Text::from(TILE_ATTRIBUTE), AttributeValue::Text(utf8_text(tile)));
        let (writer, headers) = Self::with_header(path, header)?;
        Ok((writer, ExrEncoder { path: path.to_path_buf(), headers, layout, width: width as usize }))
    }

    /// Starts a file with this header (written atomically); returns the writer and the
    /// headers blocks are compressed for.
    pub(super) fn with_header(path: &Path, header: Header) -> Result<(Self, Headers), IoError> {
        let headers: Headers = SmallVec::from_elem(header, 1);
        let (file, out) = AtomicFile::create(path)?;
        let (tail, tail_error) = Tail::new(out);
        let (sender, receiver) = mpsc::sync_channel::<(usize, Chunk)>(16);
        let thread_headers = headers.clone();
        let thread = std::thread::spawn(move || {
            ::exr::block::write(tail, thread_headers, true, |_meta, writer| {
                use ::exr::block::writer::ChunksWriter;
                for (index, chunk) in receiver {
                    writer.write_chunk(index, chunk)?;
                }
                Ok(())
            })
        });
        let writer = Self { sender: Some(sender), thread: Some(thread), tail_error, file: Some(file) };
        Ok((writer, headers))
    }

    /// Queues encoded blocks for writing.
    pub fn write(&mut self, chunks: Vec<(usize, Chunk)>) -> Result<(), IoError> {
        // No sender once a write has failed: the thread is gone.
        let outcome = match &self.sender {
            Some(sender) => {
                if chunks.into_iter().all(|c| sender.send(c).is_ok()) {
                    return Ok(());
                }
                self.stop()
            }
            None => Ok(()),
        };
        let dest = self.file.as_ref().expect("an unfinished writer has its file").dest();
        Err(match outcome {
            Err(e) => e.at(dest),
            Ok(()) => IoError::new(dest, "the EXR writer stopped"),
        })
    }

    /// Ends the writing thread and takes the final flush's outcome.
    fn stop(&mut self) -> Result<(), Stopped> {
        self.sender = None;
        match self.thread.take().map(JoinHandle::join) {
            Some(Ok(Err(e))) => return Err(Stopped::Failed(e.into())),
            Some(Err(_)) => return Err(Stopped::Panicked),
            Some(Ok(Ok(()))) | None => {}
        }
        match take_tail_error(&self.tail_error) {
            Some(e) => Err(Stopped::Failed(e.into())),
            None => Ok(()),
        }
    }

    /// Completes the file and moves it into place.
    pub fn finish(mut self) -> Result<(), IoError> {
        let file = self.file.take().expect("finish is called once");
        if let Err(e) = self.stop() {
            return Err(e.at(file.dest()));
        }
        file.commit_written()
    }
}

/// Why the writing thread ended badly.
enum Stopped {
    /// The codec or the system failed.
    Failed(Cause),
    /// The thread panicked.
    Panicked,
}

impl Stopped {
    /// The failure, told about the file at `path`.
    fn at(self, path: &Path) -> IoError {
        match self {
            Stopped::Failed(cause) => IoError::caused(path, cause),
            Stopped::Panicked => IoError::new(path, "the EXR writer thread panicked"),
        }
    }
}

impl Drop for ExrWriter {
    fn drop(&mut self) {
        // Let the writer thread end before the temporary file is removed.
        let _ = self.stop();
    }
}

impl ExrEncoder {
    /// Builds and compresses the blocks of a strip whose first sample row is `row` (a
    /// multiple of the block height); `colors` are the samples' composited colours, needed
    /// when the layout has `R`, `G`, `B`. Safe to call from many threads at once.
    pub fn encode(
        &self,
        row: usize,
        planes: &Planes,
        colors: Option<&[[f32; 3]]>,
    ) -> Result<Vec<(usize, Chunk)>, IoError> {
        let mut out = Vec::new();
        let w = self.width;
        let block_rows = COMPRESSION.scan_lines_per_block();
        for b0 in (0..planes.rows).step_by(block_rows) {
            let lines = block_rows.min(planes.rows - b0);
            let mut data = Vec::with_capacity(lines * w * 4 * self.layout.channels.len());
            for line in b0..b0 + lines {
                let r = line * w..(line + 1) * w;
                for (_, src) in &self.layout.channels {
                    match *src {
                        Source::N => planes.n[r.clone()].iter().for_each(|v| data.extend_from_slice(&v.to_ne_bytes())),
                        Source::NF => push_f32(&mut data, &planes.nf[r.clone()]),
                        Source::T => push_f32(&mut data, &planes.t[r.clone()]),
                        Source::Dex => push_f32(&mut data, &planes.dex[r.clone()]),
                        Source::Dey => push_f32(&mut data, &planes.dey[r.clone()]),
                        Source::TrapDistance(k) | Source::TrapStripe(k) => match &planes.traps[k] {
                            TrapPlane::Distance(d) | TrapPlane::Stripe { value: d, .. } | TrapPlane::Density(d) => {
                                push_f32(&mut data, &d[r.clone()])
                            }
                            TrapPlane::Color(_) => push_f32(&mut data, &vec![0.0; w]),
                        },
                        Source::Color(i) => {
                            let c = colors.ok_or_else(|| {
                                IoError::new(&self.path, "the RGB channels need the composited colours")
                            })?;
                            c[r.clone()].iter().for_each(|p| {
                                data.extend_from_slice(&::exr::prelude::f16::from_f32(p[i]).to_ne_bytes())
                            });
                        }
                        Source::TrapColor(k, i) => match &planes.traps[k] {
                            TrapPlane::Color(c) => {
                                c[r.clone()].iter().for_each(|p| data.extend_from_slice(&p[i].to_ne_bytes()))
                            }
                            _ => push_f32(&mut data, &vec![0.0; w]),
                        },
                    }
                }
            }
            let y = row + b0;
            let block = UncompressedBlock {
                index: BlockIndex {
                    layer: 0,
                    pixel_position: Vec2(0, y),
                    pixel_size: Vec2(w, lines),
                    level: Vec2(0, 0),
                },
                data,
            };
            let chunk = block.compress_to_chunk(&self.headers).map_err(|e| IoError::caused(&self.path, e))?;
            out.push((y / block_rows, chunk));
        }
        Ok(out)
    }
}

/// EXR text attributes are byte strings; ours hold UTF-8 (the exr crate's `Text::from`
/// accepts only Latin-1 and panics on anything else, e.g. a path with CJK characters).
fn utf8_text(s: &str) -> Text {
    Text::from_slice_unchecked(s.as_bytes())
}

fn push_f32(data: &mut Vec<u8>, values: &[f32]) {
    for v in values {
        data.extend_from_slice(&v.to_ne_bytes());
    }
}

/// The scene TOML stored in an EXR written by deepfield, if any.
pub fn read_exr_scene(path: &Path) -> Result<Option<String>, IoError> {
    let meta = ::exr::meta::MetaData::read_from_file(path, false).map_err(|e| IoError::caused(path, e))?;
    Ok(meta.headers.first().and_then(|h| match h.own_attributes.other.get(&Text::from(SCENE_ATTRIBUTE)) {
        Some(AttributeValue::Text(t)) => Some(String::from_utf8_lossy(t.bytes()).into_owned()),
        _ => None,
    }))
}

/// The `IterationsBias` attribute of an EXR's first layer: what Kalles Fraktaler,
/// Fraktaler-3 and fractall-rust add to every escape count they store in N (1024 in the
/// latter two). 0 when the file has none (deepfield's own files) or a negative one.
pub fn read_exr_iteration_bias(path: &Path) -> Result<u32, IoError> {
    let meta = ::exr::meta::MetaData::read_from_file(path, false).map_err(|e| IoError::caused(path, e))?;
    let key = Text::from("IterationsBias");
    Ok(meta
        .headers
        .first()
        .and_then(|h| h.own_attributes.other.get(&key).or_else(|| h.shared_attributes.other.get(&key)))
        .and_then(|v| match v {
            AttributeValue::I32(b) => u32::try_from(*b).ok(),
            _ => None,
        })
        .unwrap_or(0))
}
