//! Decoding the blocks of a scan-line EXR in parallel, straight into strips: compressed
//! files, and uncompressed ones the in-place reader (`exr_plain`) does not serve.
//!
//! The file is read block by block in file order by one thread, which hands each block to a
//! task on the current rayon pool: the task decompresses it (through the exr crate), puts its
//! lines into their strips and hands on each strip whose last line it supplied. Blocks may
//! finish in any order, so each strip counts the lines that have arrived ([`Pending`]).

use std::fs::File;
use std::io::BufReader;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Mutex, PoisonError};

use ::exr::block::UncompressedBlock;
use ::exr::block::chunk::Chunk;
use ::exr::block::reader::{AllChunksReader, ChunksReader};
use ::exr::math::Vec2;
use ::exr::meta::MetaData;

use super::exr_fault::LineFault;
use super::exr_lines::{Layout, lock};
use crate::field::Planes;

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
type Fault = Mutex<Option<LineFault>>;

/// Decompresses the blocks of a scan-line file on the current rayon pool, converts their
/// lines into strips and hands each complete strip to `done`. The thread reading the file
/// keeps at most a few blocks per worker in flight (it helps decompress while it waits), so
/// memory holds the strips being filled, not the file.
pub(super) fn decode_blocks(
    chunks: AllChunksReader<BufReader<File>>,
    layout: &Layout<'_>,
    done: &(impl Fn(usize, Planes) -> Option<Planes> + Sync),
) -> Result<(), LineFault> {
    let (height, rows_per) = (layout.header.height, layout.rows_per);
    let meta = chunks.meta_data().clone();
    let spare = Mutex::new(Vec::new());
    let pending: Vec<Mutex<Pending>> = (0..height.div_ceil(rows_per)).map(|_| Mutex::new(Pending::default())).collect();
    let fault: Fault = Mutex::new(None);
    let failed = AtomicBool::new(false);
    let in_flight = AtomicUsize::new(0);
    let limit = 4 * rayon::current_num_threads();
    let fail = |found: LineFault| {
        failed.store(true, Ordering::Relaxed);
        lock(&fault).get_or_insert(found);
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
                    fail(e.into());
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
    if let Some(fault) = fault.into_inner().unwrap_or_else(PoisonError::into_inner) {
        return Err(fault);
    }
    let lines: usize = pending.iter().map(|p| lock(p).count).sum();
    if lines != height {
        return Err(LineFault::Missing { lines, height });
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
) -> Result<(), LineFault> {
    let block = UncompressedBlock::decompress_chunk(chunk, meta, false)?;
    let index = block.index;
    let (width, height, rows_per) = (layout.header.width, layout.header.height, layout.rows_per);
    if index.layer != 0 || index.level != Vec2(0, 0) {
        return Ok(());
    }
    let lines = index.pixel_size.1;
    if index.pixel_position.0 != 0 || index.pixel_size.0 != width || block.data.len() != lines * layout.line_bytes {
        return Err(LineFault::WrongSize);
    }
    for (l, line) in block.data.chunks_exact(layout.line_bytes).enumerate() {
        let y = index.pixel_position.1 + l;
        if y >= height {
            return Err(LineFault::OutsideWindow);
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
                return Err(LineFault::Twice(y));
            }
            let Some(planes) = p.planes.as_mut() else { return Err(LineFault::Twice(y)) };
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
