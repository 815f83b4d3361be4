//! Reading raw planes back from an OpenEXR file (ours, or any file with KF2+-style channels)
//! for recolouring without recomputing.
//!
//! Channels map back by name: `N` (u32), `NF`, `T`, `DEX`, `DEY` (f32), and our trap
//! channels `trapK.D` (geometric trap distance), `trapK.STRIPE` (stripe average) and
//! `trapK.R/G/B/A` (bitmap trap colour). The planes are cut into strips of whole rows so
//! colouring can run on all cores.

use std::path::Path;

use ::exr::prelude::{FlatSamples, ReadChannels, ReadLayers, read};

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
pub fn read_exr_planes(path: &Path, strip_rows: usize) -> Result<RawData, IoError> {
    check_decoded_size(path)?;
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
    let scene = match layer.attributes.other.get(&::exr::meta::attribute::Text::from(SCENE_ATTRIBUTE)) {
        Some(::exr::meta::attribute::AttributeValue::Text(t)) => Some(String::from_utf8_lossy(t.bytes()).into_owned()),
        _ => None,
    };
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
    let n = n.ok_or_else(|| IoError::new(path, "no N channel: this is not a raw-data EXR (render with --exr)"))?;
    let take = |name: &str| floats.iter().find(|(n, _)| n == name).map(|(_, v)| v.as_slice());
    let mut channels = ChannelSet::default();
    channels.insert(Channel::N);
    for (c, name) in [(Channel::NF, "NF"), (Channel::T, "T"), (Channel::DEX, "DEX"), (Channel::DEY, "DEY")] {
        if take(name).is_some() {
            channels.insert(c);
        }
    }
    // Trap planes, by index: trap0, trap1, ... until one is missing.
    let mut traps: Vec<(TrapKind, Vec<&[f32]>)> = Vec::new();
    loop {
        let k = traps.len();
        let get = |s: &str| take(&format!("trap{k}.{s}"));
        if let Some(d) = get("D") {
            traps.push((TrapKind::Distance, vec![d]));
        } else if let Some(s) = get("STRIPE") {
            traps.push((TrapKind::Stripe, vec![s]));
        } else if let Some(s) = get("IFS") {
            traps.push((TrapKind::Density, vec![s]));
        } else if let (Some(r), Some(g), Some(b), Some(a)) = (get("R"), get("G"), get("B"), get("A")) {
            traps.push((TrapKind::Color, vec![r, g, b, a]));
        } else {
            break;
        }
    }
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
