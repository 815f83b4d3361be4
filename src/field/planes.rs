//! Raw per-sample planes and the channel names they carry in EXR files.

use std::fmt;
use std::str::FromStr;

use super::Needs;
use crate::trap::{Trap, TrapKind};

/// A raw data channel (names follow Kalles Fraktaler 2+ and Fraktaler-3).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Channel {
    /// Escape count, u32, 0xFFFFFFFF for interior.
    N,
    /// Smooth iteration fraction in [0, 1).
    NF,
    /// Final phase in turns.
    T,
    /// Distance estimate, x component, in pixels.
    DEX,
    /// Distance estimate, y component, in pixels.
    DEY,
    /// Every trap plane the scene computes.
    Traps,
    /// The composited colour of each sample: `R`, `G`, `B` (half floats, linear light).
    Rgb,
}

impl Channel {
    /// Every channel, in the order the command line lists them.
    pub const ALL: [Channel; 7] =
        [Channel::N, Channel::NF, Channel::T, Channel::DEX, Channel::DEY, Channel::Traps, Channel::Rgb];

    /// The name used on the command line and in scene files.
    pub fn name(self) -> &'static str {
        match self {
            Channel::N => "N",
            Channel::NF => "NF",
            Channel::T => "T",
            Channel::DEX => "DEX",
            Channel::DEY => "DEY",
            Channel::Traps => "TRAPS",
            Channel::Rgb => "RGB",
        }
    }
}

impl fmt::Display for Channel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// A channel name that is none of [`Channel::ALL`]'s.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("unknown channel `{0}`; expected one of N, NF, T, DEX, DEY, TRAPS, RGB")]
pub struct UnknownChannel(pub String);

impl FromStr for Channel {
    type Err = UnknownChannel;
    fn from_str(s: &str) -> Result<Self, UnknownChannel> {
        Channel::ALL
            .into_iter()
            .find(|c| c.name().eq_ignore_ascii_case(s.trim()))
            .ok_or_else(|| UnknownChannel(s.to_string()))
    }
}

/// A set of channels.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct ChannelSet(u8);

impl ChannelSet {
    /// N, NF, T, DEX, DEY: what `--exr` writes by default.
    pub fn default_exr() -> Self {
        [Channel::N, Channel::NF, Channel::T, Channel::DEX, Channel::DEY].into_iter().collect()
    }

    /// True when `c` is in the set.
    pub fn contains(self, c: Channel) -> bool {
        self.0 & (1 << c as u8) != 0
    }

    /// Adds `c`.
    pub fn insert(&mut self, c: Channel) {
        self.0 |= 1 << c as u8;
    }

    /// The channels in canonical order.
    pub fn iter(self) -> impl Iterator<Item = Channel> {
        Channel::ALL.into_iter().filter(move |&c| self.contains(c))
    }

    /// What the field must compute to provide these channels (traps come from layers).
    pub fn needs(self) -> Needs {
        Needs {
            nf: self.contains(Channel::NF),
            t: self.contains(Channel::T),
            de: self.contains(Channel::DEX) || self.contains(Channel::DEY),
            traps: Vec::new(),
        }
    }
}

impl FromIterator<Channel> for ChannelSet {
    fn from_iter<I: IntoIterator<Item = Channel>>(iter: I) -> Self {
        let mut s = ChannelSet::default();
        for c in iter {
            s.insert(c);
        }
        s
    }
}

/// One trap's plane.
#[derive(Debug, Clone, PartialEq)]
pub enum TrapPlane {
    /// Minimum orbit distance to a shape, in plane units (f32::MAX when the orbit escaped
    /// before a single value was observed).
    Distance(Vec<f32>),
    /// Colour of the first bitmap hit, linear premultiplied RGBA (zero: no hit).
    Color(Vec<[f32; 4]>),
    /// IFS density at each sample's point.
    Density(Vec<f32>),
    /// Stripe average, smoothed across bands ([`crate::trap::stripe`]); `prev` holds the
    /// mean without the last term until the field finishes the strip, then is emptied.
    Stripe {
        /// The stripe value in [0, 1].
        value: Vec<f32>,
        /// Work space: mean without the escaping term.
        prev: Vec<f32>,
    },
}

impl TrapPlane {
    /// What the plane holds.
    pub fn kind(&self) -> TrapKind {
        match self {
            TrapPlane::Distance(_) => TrapKind::Distance,
            TrapPlane::Color(_) => TrapKind::Color,
            TrapPlane::Density(_) => TrapKind::Density,
            TrapPlane::Stripe { .. } => TrapKind::Stripe,
        }
    }

    /// Stores sample `k`'s final trap state.
    #[inline]
    pub fn store(&mut self, k: usize, state: &crate::trap::TrapState) {
        use crate::trap::TrapState;
        match (self, state) {
            (TrapPlane::Distance(d), TrapState::Distance(v)) => d[k] = v.min(f32::MAX as f64) as f32,
            (TrapPlane::Color(c), TrapState::Color { rgba, .. }) => c[k] = *rgba,
            (TrapPlane::Stripe { value, prev }, TrapState::Stripe { sum, last, count }) => {
                let (p, full) = crate::trap::stripe::means(*sum, *last, *count);
                value[k] = full as f32;
                prev[k] = p as f32;
            }
            _ => {}
        }
    }
}

/// Raw planes of `width * rows` samples, row-major. Planes not requested are empty.
#[derive(Debug, Clone, PartialEq)]
pub struct Planes {
    /// Samples per row.
    pub width: usize,
    /// Rows.
    pub rows: usize,
    /// Escape counts.
    pub n: Vec<u32>,
    /// Smooth iteration fractions.
    pub nf: Vec<f32>,
    /// Phases in turns.
    pub t: Vec<f32>,
    /// Distance estimate x components, in sample-raster pixels.
    pub dex: Vec<f32>,
    /// Distance estimate y components, in sample-raster pixels.
    pub dey: Vec<f32>,
    /// Trap planes, in the order of [`Needs::traps`].
    pub traps: Vec<TrapPlane>,
}

impl Planes {
    /// Zeroed planes for what `needs` asks.
    pub fn new(width: usize, rows: usize, needs: &Needs) -> Self {
        let len = width * rows;
        let plane = |on: bool| if on { vec![0.0f32; len] } else { Vec::new() };
        Self {
            width,
            rows,
            n: vec![0; len],
            nf: plane(needs.nf),
            t: plane(needs.t),
            dex: plane(needs.de),
            dey: plane(needs.de),
            traps: needs
                .traps
                .iter()
                .map(|t| match t {
                    Trap::Geometric(_) => TrapPlane::Distance(vec![f32::MAX; len]),
                    Trap::Bitmap(_) => TrapPlane::Color(vec![[0.0; 4]; len]),
                    Trap::Stripe(_) => TrapPlane::Stripe { value: vec![0.0; len], prev: vec![0.0; len] },
                    Trap::Ifs(_) => TrapPlane::Density(vec![0.0; len]),
                })
                .collect(),
        }
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.width * self.rows
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}
