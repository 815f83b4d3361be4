//! Reading an uncompressed scan-line EXR in place: every worker reads the lines of the strip
//! it fills with positioned reads, straight from the file into a line buffer it keeps.
//!
//! An uncompressed block is one scan line: its y coordinate, its byte count, then the line's
//! samples as they lie in memory on a little-endian machine. With nothing to decode, the
//! block decoder's costs are all overhead here: one thread reading every block in turn, a
//! fresh zeroed buffer per block, a copy to "decompress" it. This reader looks the blocks up
//! in the file's offset table instead, and each worker reads whole strips, taken in order
//! from a shared counter (so strips complete about top to bottom, as a streamed PNG wants
//! them), one `pread` per line into a buffer small enough to stay in cache. The kernel's copy
//! out of the page cache is then the only copy before a line goes into its planes, and it
//! runs on every core.
//!
//! The offset table is trusted only as far as it is checked: every offset must lie inside the
//! file and after the table, and every block read must carry the y coordinate and the byte
//! count its place demands. A file whose table fails the first check (a file cut short, one
//! written by a program that stopped early) is left to the block decoder, which reads the
//! blocks in file order without the table; a block that fails the second is a damaged file.
//!
//! Positioned reads are Unix's (`pread`); elsewhere, and on big-endian machines, the block
//! decoder reads these files too, as it does files flagged multi-part (whose blocks carry a
//! part number).

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use ::exr::compression::Compression;
use ::exr::meta::MetaData;
use ::exr::meta::header::Header;

use super::exr_fault::LineFault;
use super::exr_lines::{Layout, lock};
use crate::field::Planes;

/// Bytes before an uncompressed block's samples: its y coordinate and its byte count.
const BLOCK_HEAD: usize = 8;

/// Whether this build can read a file at a position without moving a shared cursor.
const POSITIONED: bool = cfg!(all(unix, target_endian = "little"));

/// An uncompressed single-part scan-line file, its blocks located.
pub(super) struct PlainBlocks {
    file: File,
    /// Where each scan line's block starts, top to bottom.
    offsets: Vec<u64>,
    /// The y coordinate the first block carries (the top of the data window).
    y0: i64,
}

/// A reader that counts the bytes it hands out: how far the exr crate read to parse the
/// header, which is where the offset table starts.
struct Counting<R> {
    inner: R,
    count: u64,
}

impl<R: Read> Read for Counting<R> {
    fn read(&mut self, buf: &mut [u8]) -> std::io::Result<usize> {
        let n = self.inner.read(buf)?;
        self.count += n as u64;
        Ok(n)
    }
}

impl PlainBlocks {
    /// The blocks of `path`, whose single part is `header` with scan lines of `line_bytes`
    /// bytes; `None` where this reader does not serve the file (compressed, or an offset
    /// table that does not check out, or a machine without positioned little-endian reads).
    pub(super) fn locate(path: &Path, header: &Header, line_bytes: usize) -> std::io::Result<Option<Self>> {
        if !POSITIONED || header.compression != Compression::Uncompressed {
            return Ok(None);
        }
        let lines = header.layer_size.1;
        if header.chunk_count != lines {
            return Ok(None);
        }
        let file = File::open(path)?;
        let file_len = file.metadata()?.len();
        // Parse the header again, counting the bytes it spans: the offset table follows it.
        let mut counting = Counting { inner: BufReader::new(&file), count: 0 };
        // A file flagged multi-part (even with one part) prefixes each block with its part
        // number: the block decoder reads those.
        match MetaData::read_from_buffered(&mut counting, false) {
            Ok(meta) if meta.headers.len() == 1 && !meta.requirements.is_multilayer() => {}
            _ => return Ok(None),
        }
        let table_at = counting.count;
        // The table's size is checked against the file before it is allocated.
        let Some(table_len) = lines.checked_mul(8) else { return Ok(None) };
        let table_end = table_at.saturating_add(table_len as u64);
        if table_end > file_len {
            return Ok(None);
        }
        let mut table = vec![0u8; table_len];
        read_exact_at(&file, &mut table, table_at)?;
        let block = (BLOCK_HEAD + line_bytes) as u64;
        let offsets: Vec<u64> = table
            .chunks_exact(8)
            .map(|b| u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
            .collect();
        if offsets.iter().any(|&at| at < table_end || at.checked_add(block).is_none_or(|end| end > file_len)) {
            return Ok(None);
        }
        Ok(Some(Self { file, offsets, y0: i64::from(header.own_attributes.layer_position.1) }))
    }

    /// Reads every strip on the current rayon pool and hands each to `done` as soon as its
    /// last line is in (on a worker, every strip exactly once when the result is `Ok`);
    /// planes `done` hands back are filled again with a later strip. Stops at the first
    /// damaged block.
    pub(super) fn read_strips(
        &self,
        layout: &Layout<'_>,
        done: &(impl Fn(usize, Planes) -> Option<Planes> + Sync),
    ) -> Result<(), LineFault> {
        let count = layout.header.height.div_ceil(layout.rows_per);
        let next = AtomicUsize::new(0);
        let failed = AtomicBool::new(false);
        let fault: Mutex<Option<LineFault>> = Mutex::new(None);
        let spare = Mutex::new(Vec::new());
        rayon::scope(|s| {
            for _ in 0..rayon::current_num_threads().min(count) {
                s.spawn(|_| {
                    let mut line = vec![0u8; BLOCK_HEAD + layout.line_bytes];
                    while !failed.load(Ordering::Relaxed) {
                        let k = next.fetch_add(1, Ordering::Relaxed);
                        if k >= count {
                            break;
                        }
                        match self.read_strip(k, layout, &mut line, &spare) {
                            Ok(planes) => {
                                if let Some(back) = done(k, planes) {
                                    lock(&spare).push(back);
                                }
                            }
                            Err(e) => {
                                failed.store(true, Ordering::Relaxed);
                                lock(&fault).get_or_insert(e);
                            }
                        }
                    }
                });
            }
        });
        match fault.into_inner().unwrap_or_else(std::sync::PoisonError::into_inner) {
            Some(fault) => Err(fault),
            None => Ok(()),
        }
    }

    /// Strip `k`'s planes, each of its lines read through `line` (one block's bytes).
    fn read_strip(
        &self,
        k: usize,
        layout: &Layout<'_>,
        line: &mut [u8],
        spare: &Mutex<Vec<Planes>>,
    ) -> Result<Planes, LineFault> {
        let (height, rows_per) = (layout.header.height, layout.rows_per);
        let rows = rows_per.min(height - k * rows_per);
        let mut planes = layout.planes_from(rows, spare);
        for row in 0..rows {
            let y = k * rows_per + row;
            read_exact_at(&self.file, line, self.offsets[y]).map_err(|source| LineFault::Read { line: y, source })?;
            let (head, samples) = line.split_at(BLOCK_HEAD);
            let at = i32::from_le_bytes([head[0], head[1], head[2], head[3]]);
            let size = i32::from_le_bytes([head[4], head[5], head[6], head[7]]);
            if i64::from(at) != self.y0 + y as i64 || usize::try_from(size) != Ok(samples.len()) {
                return Err(LineFault::Misplaced { line: y, found: at, size });
            }
            layout.insert_line(&mut planes, row, samples);
        }
        Ok(planes)
    }
}

/// Fills `buf` from `file` at byte `at`.
#[cfg(unix)]
fn read_exact_at(file: &File, buf: &mut [u8], at: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, at)
}

/// Never called: [`POSITIONED`] is false on this platform, so no file is located.
#[cfg(not(unix))]
fn read_exact_at(_file: &File, _buf: &mut [u8], _at: u64) -> std::io::Result<()> {
    Err(std::io::Error::new(std::io::ErrorKind::Unsupported, "positioned reads"))
}

#[cfg(all(test, unix))]
mod tests {
    use ::exr::prelude::*;

    use super::*;
    use crate::io::ExrStrips;

    /// An uncompressed file of `h` rows whose N is its sample index, written to `name`.
    fn write(name: &str, w: usize, h: usize) -> std::path::PathBuf {
        let path = std::env::temp_dir().join(format!("deepfield-exr-plain-{}-{name}.exr", std::process::id()));
        crate::io::exr_test_file::write_n_nf(&path, (w, h), (0, 0), Compression::Uncompressed);
        path
    }

    /// Where the exr crate put each line's block: the table this reader trusts.
    fn offsets(path: &Path) -> Vec<u64> {
        let meta = MetaData::read_from_file(path, false).unwrap();
        let line_bytes = meta.headers[0].layer_size.0 * 8;
        PlainBlocks::locate(path, &meta.headers[0], line_bytes).unwrap().expect("read in place").offsets
    }

    /// The offsets found are the blocks' own: each holds its line's y and byte count.
    #[test]
    fn offsets_point_at_their_lines() {
        let (w, h) = (13, 40);
        let path = write("offsets", w, h);
        let bytes = std::fs::read(&path).unwrap();
        for (y, &at) in offsets(&path).iter().enumerate() {
            let at = at as usize;
            assert_eq!(i32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()), y as i32);
            assert_eq!(i32::from_le_bytes(bytes[at + 4..at + 8].try_into().unwrap()), (w * 8) as i32);
        }
        std::fs::remove_file(&path).unwrap();
    }

    /// A block that carries another line than its place in the table demands is a damaged
    /// file, named as such; an offset table pointing past the end leaves the file to the
    /// block decoder, which reads it whole.
    #[test]
    fn damaged_blocks_and_tables() {
        let (w, h) = (11, 30);
        let path = write("damaged", w, h);
        let good = crate::io::read_exr_planes(&path, 8).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        let table = offsets(&path);
        let table_at = table[0] as usize - 8 * h;

        let mut wrong_y = bytes.clone();
        wrong_y[table[17] as usize..table[17] as usize + 4].copy_from_slice(&3i32.to_le_bytes());
        std::fs::write(&path, &wrong_y).unwrap();
        let e = ExrStrips::open(&path, 8).unwrap().for_each_strip(|_, _| {}).expect_err("a damaged block read");
        assert!(e.to_string().contains("scan line 17 holds line 3") && e.to_string().contains("damaged"), "{e}");

        let mut past_end = bytes.clone();
        past_end[table_at + 8 * 4..table_at + 8 * 5].copy_from_slice(&(bytes.len() as u64).to_le_bytes());
        std::fs::write(&path, &past_end).unwrap();
        let meta = MetaData::read_from_file(&path, false).unwrap();
        assert!(PlainBlocks::locate(&path, &meta.headers[0], w * 8).unwrap().is_none());
        assert_eq!(crate::io::read_exr_planes(&path, 8).unwrap().strips, good.strips);
        std::fs::remove_file(&path).unwrap();
    }

    /// A data window whose top is not at y = 0: its blocks carry absolute y coordinates,
    /// which the reader checks from the window's top, and the planes hold the window's rows.
    #[test]
    fn data_windows_off_the_origin() {
        let (w, h) = (9, 20);
        let path = std::env::temp_dir().join(format!("deepfield-exr-plain-{}-window.exr", std::process::id()));
        crate::io::exr_test_file::write_n_nf(&path, (w, h), (-3, 7), Compression::Uncompressed);
        let meta = MetaData::read_from_file(&path, false).unwrap();
        let blocks = PlainBlocks::locate(&path, &meta.headers[0], w * 8).unwrap().expect("read in place");
        assert_eq!(blocks.y0, 7);
        let raw = crate::io::read_exr_planes(&path, 6).unwrap();
        let n: Vec<u32> = raw.strips.iter().flat_map(|s| s.n.iter().copied()).collect();
        assert_eq!(n, (0..(w * h) as u32).collect::<Vec<_>>());
        std::fs::remove_file(&path).unwrap();
    }
}
