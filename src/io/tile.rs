//! Work units of a PNG render (their raw data: [`super::tile_exr`]): bands of rows rendered
//! apart (`render --tile K/N`, one per
//! machine or job) and streamed back into the whole image (`deepfield assemble`).
//!
//! A band is a PNG of the image's full width and its own rows, carrying the whole scene
//! (as every deepfield PNG does) and an iTXt chunk [`TILE_KEYWORD`] that says which band
//! it is: `K/N rows A..B of WxH`. Bands are cut by [`band_rows`] alone, so every unit and
//! the assembler agree without talking to each other. Assembly checks that the bands are
//! exactly one render's complete set (same scene text, same N, every K once), then
//! decodes them one row at a time into a single streaming PNG writer: its memory is one
//! row whatever the image size, and its bytes are those of the same render done in one
//! piece (the samples depend only on the scene, and the writer is the renderer's own).

use std::fs::File;
use std::io::BufReader;
use std::path::{Path, PathBuf};

use super::IoError;
use super::png::{PngWriter, SCENE_KEYWORD};

/// iTXt keyword of a band's position.
pub const TILE_KEYWORD: &str = "deepfield-tile";

/// Unit `k` of `n` of an image `height` rows high: rows k·H/n .. (k+1)·H/n.
pub fn band_rows(k: u32, n: u32, height: u32) -> std::ops::Range<u32> {
    let at = |i: u32| (i as u64 * height as u64 / n as u64) as u32;
    at(k)..at(k + 1)
}

/// The text of a band's [`TILE_KEYWORD`] chunk.
pub fn tile_text(k: u32, n: u32, width: u32, height: u32) -> String {
    let r = band_rows(k, n, height);
    format!("{k}/{n} rows {}..{} of {width}x{height}", r.start, r.end)
}

/// A band read back: where it belongs and what made it.
#[derive(Debug, Clone)]
pub(super) struct Band {
    pub(super) path: PathBuf,
    pub(super) k: u32,
    pub(super) n: u32,
    pub(super) width: u32,
    pub(super) height: u32,
    /// PNG bit depth (0 for raw data).
    pub(super) bits: u8,
    pub(super) scene: String,
}

pub(super) fn parse_tile_text(path: &Path, t: &str) -> Result<(u32, u32, u32, u32), IoError> {
    let bad = || IoError::new(path, format!("its {TILE_KEYWORD} text `{t}` is not `K/N rows A..B of WxH`"));
    let mut words = t.split_whitespace();
    let (k, n) = words.next().and_then(|s| s.split_once('/')).ok_or_else(bad)?;
    let (k, n): (u32, u32) = (k.parse().map_err(|_| bad())?, n.parse().map_err(|_| bad())?);
    let _rows = (words.next(), words.next(), words.next());
    let (w, h) = words.next().and_then(|s| s.split_once('x')).ok_or_else(bad)?;
    let (w, h): (u32, u32) = (w.parse().map_err(|_| bad())?, h.parse().map_err(|_| bad())?);
    if n == 0 || k >= n || n > h.max(1) {
        return Err(bad());
    }
    Ok((k, n, w, h))
}

fn read_band(path: &Path) -> Result<Band, IoError> {
    let file = File::open(path).map_err(|e| IoError::caused(path, e))?;
    let reader = ::png::Decoder::new(BufReader::new(file))
        .read_info()
        .map_err(|e| IoError::context(path, "not a readable PNG", e))?;
    let info = reader.info();
    let text = |key: &str| -> Result<Option<String>, IoError> {
        match info.utf8_text.iter().find(|c| c.keyword == key) {
            Some(c) => c.get_text().map(Some).map_err(|e| IoError::caused(path, e)),
            None => Ok(None),
        }
    };
    let tile = text(TILE_KEYWORD)?
        .ok_or_else(|| IoError::new(path, "not a work unit: written without `render --tile K/N`"))?;
    let scene = text(SCENE_KEYWORD)?.ok_or_else(|| IoError::new(path, "has no deepfield scene"))?;
    let (k, n, width, height) = parse_tile_text(path, &tile)?;
    let bits = match info.bit_depth {
        ::png::BitDepth::Eight => 8,
        ::png::BitDepth::Sixteen => 16,
        d => return Err(IoError::new(path, format!("unexpected bit depth {d:?}"))),
    };
    let rows = band_rows(k, n, height);
    if info.color_type != ::png::ColorType::Rgb || info.width != width || info.height != rows.end - rows.start {
        return Err(IoError::new(
            path,
            format!(
                "is {}x{} {:?}, but band {k}/{n} of {width}x{height} is {width}x{} RGB",
                info.width,
                info.height,
                info.color_type,
                rows.end - rows.start
            ),
        ));
    }
    Ok(Band { path: path.to_path_buf(), k, n, width, height, bits, scene })
}

/// Checks that `bands` (sorted by unit) are one render's complete set: the same scene,
/// size, format and unit count, every unit once.
pub(super) fn check_set(bands: &[Band], first: Option<&PathBuf>, out: &Path) -> Result<(), IoError> {
    let (Some(b0), Some(first)) = (bands.first(), first) else {
        return Err(IoError::new(out, "no work units given"));
    };
    for b in bands {
        if (b.n, b.width, b.height, b.bits) != (b0.n, b0.width, b0.height, b0.bits) || b.scene != b0.scene {
            return Err(IoError::new(
                &b.path,
                format!("is a unit of another render than {} (scene, size or unit count differ)", b0.path.display()),
            ));
        }
    }
    for pair in bands.windows(2) {
        if pair[0].k == pair[1].k {
            let twice = format!("unit {} is given twice (also {})", pair[1].k, pair[0].path.display());
            return Err(IoError::new(&pair[1].path, twice));
        }
    }
    let have: Vec<u32> = bands.iter().map(|b| b.k).collect();
    if let Some(missing) = (0..b0.n).find(|k| !have.contains(k)) {
        return Err(IoError::new(first, format!("unit {missing} of {} is missing", b0.n)));
    }
    Ok(())
}

/// Streams the bands at `paths` (any order) into the whole image at `out`. Refuses, naming
/// the file, bands of different renders, a band given twice, or a missing band.
pub fn assemble_png(paths: &[PathBuf], out: &Path, progress: &dyn Fn(u32, u32)) -> Result<(), IoError> {
    let Some(first) = paths.first() else {
        return Err(IoError::new(out, "no work units given"));
    };
    let mut bands = paths.iter().map(|p| read_band(p)).collect::<Result<Vec<_>, _>>()?;
    bands.sort_by_key(|b| b.k);
    check_set(&bands, Some(first), out)?;
    let b0 = bands[0].clone();
    let mut writer = PngWriter::create(out, b0.width, b0.height, b0.bits, &b0.scene)?;
    let mut done = 0;
    for b in &bands {
        let file = File::open(&b.path).map_err(|e| IoError::caused(&b.path, e))?;
        let mut decoder = ::png::Decoder::new(BufReader::new(file));
        decoder.set_transformations(::png::Transformations::IDENTITY);
        let mut reader = decoder.read_info().map_err(|e| IoError::caused(&b.path, e))?;
        while let Some(row) = reader.next_row().map_err(|e| IoError::caused(&b.path, e))? {
            writer.write_encoded(row.data())?;
            done += 1;
            progress(done, b0.height);
        }
    }
    writer.finish()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bands_cover_every_row_once() {
        for (n, h) in [(1, 7), (3, 10), (7, 7), (4, 1001)] {
            let mut next = 0;
            for k in 0..n {
                let r = band_rows(k, n, h);
                assert_eq!(r.start, next);
                assert!(r.end > r.start);
                next = r.end;
            }
            assert_eq!(next, h);
        }
    }

    #[test]
    fn tile_text_round_trips_and_bad_text_is_refused() {
        let p = Path::new("x.png");
        assert_eq!(parse_tile_text(p, &tile_text(2, 5, 640, 480)).unwrap(), (2, 5, 640, 480));
        for bad in ["", "2/0 rows 0..1 of 4x4", "5/5 rows 0..1 of 4x4", "1/2 rows of", "a/b rows 0..1 of 4x4"] {
            assert!(parse_tile_text(p, bad).is_err(), "{bad}");
        }
    }
}
