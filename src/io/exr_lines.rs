//! How one scan line of an EXR block maps onto a strip's planes.
//!
//! A scan line holds each channel's samples for that row, one channel after another in the
//! header's (alphabetical) order, little-endian. [`Layout`] knows, for every channel, which
//! plane its samples go to ([`Slot`]) and converts a line into row `row` of a strip. Both
//! readers of scan-line files use it: the block decoder for decompressed blocks, and the
//! in-place reader for the lines of uncompressed files.

use std::sync::{Mutex, MutexGuard, PoisonError};

use ::exr::meta::attribute::SampleType;
use ::exr::prelude::f16;

use super::exr_raw::RawHeader;
use crate::field::{Channel, Planes, TrapPlane};
use crate::trap::TrapKind;

/// A mutex's guard, whether or not another thread panicked while holding it (the data is
/// plain samples, valid either way).
pub(super) fn lock<T>(m: &Mutex<T>) -> MutexGuard<'_, T> {
    m.lock().unwrap_or_else(PoisonError::into_inner)
}

/// Where one channel's samples go.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum Slot {
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

/// The slot of channel `name` given the trap layout.
pub(super) fn slot_of(name: &str, traps: &[TrapKind]) -> Slot {
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
pub(super) fn float_of(b: &[u8], kind: SampleType) -> f32 {
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

/// How the lines of a scan-line file's blocks map to strips and planes.
pub(super) struct Layout<'a> {
    /// The file's header.
    pub(super) header: &'a RawHeader,
    /// Rows per strip (at least 1).
    pub(super) rows_per: usize,
    /// Each channel's slot and sample type, in the file's channel order.
    pub(super) slots: Vec<(Slot, SampleType)>,
    /// Bytes in one scan line (all channels).
    pub(super) line_bytes: usize,
}

impl Layout<'_> {
    /// Planes for a strip of `rows` rows: handed-back planes of that size where `spare` holds
    /// some (every plane is overwritten line by line, but for a bitmap trap's colour plane,
    /// whose RGBA channels the file may hold only some of: that is zeroed), else new ones.
    pub(super) fn planes_from(&self, rows: usize, spare: &Mutex<Vec<Planes>>) -> Planes {
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
    pub(super) fn insert_line(&self, planes: &mut Planes, row: usize, line: &[u8]) {
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
