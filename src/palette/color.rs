//! Colour-space conversions (pure functions): sRGB transfer, OKLab (Björn Ottosson, 2020).

/// sRGB-encoded component (0..1) to linear light.
#[inline]
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 { v / 12.92 } else { ((v + 0.055) / 1.055).powf(2.4) }
}

/// [`srgb_to_linear`] by table (4096 steps, linear interpolation; within 4e-7 (a few f32 ulps; 16-bit output steps are 1.5e-5) of the exact
/// curve): for per-sample colouring, where `powf` would dominate. Clamps to [0, 1].
#[inline]
pub fn srgb_to_linear_lut(v: f32) -> f32 {
    const STEPS: usize = 4096;
    static T: std::sync::OnceLock<[f32; STEPS + 2]> = std::sync::OnceLock::new();
    let t = T.get_or_init(|| std::array::from_fn(|i| srgb_to_linear((i as f32 / STEPS as f32).min(1.0))));
    let f = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) * STEPS as f32 };
    // f is in 0 ..= STEPS: through i32, one instruction on x86-64 (u64 takes a dozen); the
    // min (never taken) lets the compiler drop the table's bounds checks.
    let i = (f as i32 as usize).min(STEPS);
    let w = f - i as f32;
    t[i] + (t[i + 1] - t[i]) * w
}

/// Linear-light component to sRGB encoding (0..1, clamped).
#[inline]
pub fn linear_to_srgb(v: f32) -> f32 {
    let v = v.clamp(0.0, 1.0);
    if v <= 0.003_130_8 { v * 12.92 } else { 1.055 * v.powf(1.0 / 2.4) - 0.055 }
}

/// Tables for 8-bit sRGB codes, built once.
struct Tables {
    /// Linear value of each 8-bit code.
    decode: [f32; 256],
    /// Linear thresholds between consecutive codes (code k+1 starts at `encode[k]`); entry
    /// 255 is NaN, which no value reaches, so code 255 needs no test of its own and a code
    /// indexes the table without a bounds check.
    encode: [f32; 256],
    /// Code at the start of each bucket of f32 bit patterns from 0 to 1.0: bucket i holds
    /// the values whose bits shifted right by [`SHIFT`] are i, 1/128 of a binade each.
    /// Neighbouring code boundaries are further apart than that (relatively at least
    /// 2.4 / 255 apart on the power curve, 1/k on the linear segment near code k), so at most
    /// one boundary falls inside a bucket: one comparison finishes the search. Buckets by
    /// bit pattern cost one shift where equal steps of [0, 1] cost a multiply and a
    /// saturating float-to-integer conversion.
    start: [u8; TOP + 1],
}

/// Bits dropped from an f32's pattern to find its bucket.
const SHIFT: u32 = 16;
/// The bucket of 1.0 (and of everything above it).
const TOP: usize = (0x3f80_0000 >> SHIFT) as usize;

fn tables() -> &'static Tables {
    static T: std::sync::OnceLock<Tables> = std::sync::OnceLock::new();
    T.get_or_init(|| {
        let bounds: [f32; 255] = std::array::from_fn(|k| srgb_to_linear((k as f32 + 0.5) / 255.0));
        let start =
            std::array::from_fn(|b| bounds.partition_point(|&t| t <= f32::from_bits((b as u32) << SHIFT)) as u8);
        let encode = std::array::from_fn(|k| bounds.get(k).copied().unwrap_or(f32::NAN));
        Tables { decode: std::array::from_fn(|k| srgb_to_linear(k as f32 / 255.0)), encode, start }
    })
}

/// Linear light of an 8-bit sRGB code (table lookup).
#[inline]
pub fn srgb8_to_linear(code: u8) -> f32 {
    tables().decode[code as usize]
}

/// The 8-bit sRGB code nearest to linear value `v` (exact rounding by binary search over
/// the code boundaries; no `powf`).
#[inline]
pub fn linear_to_srgb8(v: f32) -> u8 {
    Srgb8Encoder::get().encode(v)
}

/// [`linear_to_srgb8`] with the table lookup hoisted out, for per-pixel loops.
#[derive(Clone, Copy)]
pub struct Srgb8Encoder(&'static Tables);

impl Srgb8Encoder {
    /// The encoder (the tables are built on first use).
    #[inline]
    pub fn get() -> Self {
        Self(tables())
    }

    /// The 8-bit sRGB code nearest to linear `v`; NaN and negatives give 0, >= 1 gives 255.
    #[inline(always)]
    pub fn encode(self, v: f32) -> u8 {
        // NaN, negatives and -0 become +0; above 1 every value falls in the top bucket.
        let v = if v > 0.0 { v } else { 0.0 };
        let k = self.0.start[((v.to_bits() >> SHIFT) as usize).min(TOP)];
        k + u8::from(v >= self.0.encode[k as usize])
    }
}

/// Linear sRGB to OKLab.
pub fn linear_to_oklab([r, g, b]: [f32; 3]) -> [f32; 3] {
    let l = 0.412_221_46 * r + 0.536_332_55 * g + 0.051_445_995 * b;
    let m = 0.211_903_5 * r + 0.680_699_5 * g + 0.107_396_96 * b;
    let s = 0.088_302_46 * r + 0.281_718_85 * g + 0.629_978_7 * b;
    let (l, m, s) = (l.cbrt(), m.cbrt(), s.cbrt());
    [
        0.210_454_26 * l + 0.793_617_8 * m - 0.004_072_047 * s,
        1.977_998_5 * l - 2.428_592_2 * m + 0.450_593_7 * s,
        0.025_904_037 * l + 0.782_771_77 * m - 0.808_675_77 * s,
    ]
}

/// OKLab to linear sRGB.
pub fn oklab_to_linear([l, a, b]: [f32; 3]) -> [f32; 3] {
    let l_ = l + 0.396_337_78 * a + 0.215_803_76 * b;
    let m_ = l - 0.105_561_346 * a - 0.063_854_17 * b;
    let s_ = l - 0.089_484_18 * a - 1.291_485_5 * b;
    let (l, m, s) = (l_ * l_ * l_, m_ * m_ * m_, s_ * s_ * s_);
    [
        4.076_741_7 * l - 3.307_711_6 * m + 0.230_969_94 * s,
        -1.268_438 * l + 2.609_757_4 * m - 0.341_319_38 * s,
        -0.004_196_086_3 * l - 0.703_418_6 * m + 1.707_614_7 * s,
    ]
}

/// OKLab to OKLCH: lightness, chroma, hue in turns [0, 1).
pub fn oklab_to_oklch([l, a, b]: [f32; 3]) -> [f32; 3] {
    let h = b.atan2(a) / std::f32::consts::TAU;
    [l, a.hypot(b), if h < 0.0 { h + 1.0 } else { h }]
}

/// OKLCH (hue in turns) to OKLab.
pub fn oklch_to_oklab([l, c, h]: [f32; 3]) -> [f32; 3] {
    let (s, co) = (h * std::f32::consts::TAU).sin_cos();
    [l, c * co, c * s]
}

/// HSV (hue in turns, saturation, value; all in [0, 1]) to RGB in the same encoding.
pub fn hsv_to_rgb([h, s, v]: [f32; 3]) -> [f32; 3] {
    let h6 = (h - h.floor()) * 6.0;
    let k = |n: f32| {
        let k = (n + h6) % 6.0;
        v - v * s * k.min(4.0 - k).clamp(0.0, 1.0)
    };
    [k(5.0), k(3.0), k(1.0)]
}

/// Formats sRGB-encoded components as `#rrggbb`.
pub fn to_hex(srgb: [f32; 3]) -> String {
    let c = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    format!("#{:02x}{:02x}{:02x}", c(srgb[0]), c(srgb[1]), c(srgb[2]))
}

/// Parses `#rrggbb` into sRGB-encoded components.
pub fn parse_hex(text: &str) -> Option<[f32; 3]> {
    let h = text.strip_prefix('#')?;
    if h.len() != 6 || !h.bytes().all(|b| b.is_ascii_hexdigit()) {
        return None;
    }
    let c = |i: usize| u8::from_str_radix(&h[i..i + 2], 16).ok().map(|v| v as f32 / 255.0);
    Some([c(0)?, c(2)?, c(4)?])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn encoding_agrees_with_a_search_of_the_boundaries_everywhere() {
        // The code by binary search over the boundaries, for any f32.
        let want = |v: f32| if v > 0.0 { tables().encode.partition_point(|&t| t <= v) as u8 } else { 0 };
        let enc = Srgb8Encoder::get();
        // Every boundary and its neighbours (where a bucket holding two would show), the
        // first and last value of every bucket, and a sweep of bit patterns.
        let mut bits: Vec<u32> = tables().encode[..255]
            .iter()
            .flat_map(|t| (-3i32..=3).map(move |d| t.to_bits().wrapping_add_signed(d)))
            .collect();
        bits.extend((0..=TOP as u32).flat_map(|b| [b << SHIFT, (b << SHIFT) | ((1 << SHIFT) - 1)]));
        bits.extend((0..0x4000_0000u32).step_by(4099));
        for b in bits {
            let v = f32::from_bits(b);
            assert_eq!(enc.encode(v), want(v), "{v:e} ({b:#x})");
        }
        for (v, code) in
            [(f32::NAN, 0), (-f32::NAN, 0), (-0.0, 0), (-1.0, 0), (f32::INFINITY, 255), (f32::NEG_INFINITY, 0)]
        {
            assert_eq!(enc.encode(v), code, "{v}");
        }
    }

    #[test]
    fn round_trips() {
        for v in [0.0f32, 0.002, 0.04, 0.2, 0.5, 0.9, 1.0] {
            assert!((srgb_to_linear(linear_to_srgb(v)) - v).abs() < 1e-6);
        }
        let c = [0.2f32, 0.5, 0.9];
        let back = oklab_to_linear(linear_to_oklab(c));
        for k in 0..3 {
            assert!((back[k] - c[k]).abs() < 1e-4);
        }
        // White is L = 1, a = b = 0.
        let w = linear_to_oklab([1.0, 1.0, 1.0]);
        assert!((w[0] - 1.0).abs() < 1e-4 && w[1].abs() < 1e-4 && w[2].abs() < 1e-4);
        assert_eq!(parse_hex("#ff8000"), Some([1.0, 128.0 / 255.0, 0.0]));
        assert_eq!(parse_hex("ff8000"), None);
        assert_eq!(to_hex([1.0, 128.0 / 255.0, 0.0]), "#ff8000");
        for i in 0..=10_000 {
            let v = i as f32 / 10_000.0;
            assert!(
                (srgb_to_linear_lut(v) - srgb_to_linear(v)).abs() < 4e-7,
                "{v}: {} vs {}",
                srgb_to_linear_lut(v),
                srgb_to_linear(v)
            );
        }
        let lab = linear_to_oklab([0.3, 0.6, 0.1]);
        let back = oklch_to_oklab(oklab_to_oklch(lab));
        assert!((0..3).all(|k| (back[k] - lab[k]).abs() < 1e-6));
        assert_eq!(hsv_to_rgb([0.0, 1.0, 1.0]), [1.0, 0.0, 0.0]);
        assert_eq!(hsv_to_rgb([1.0 / 3.0, 1.0, 0.5]), [0.0, 0.5, 0.0]);
        assert_eq!(hsv_to_rgb([0.5, 0.0, 0.25]), [0.25, 0.25, 0.25]);
        for i in 0..=100_000 {
            let v = i as f32 / 100_000.0;
            assert_eq!(linear_to_srgb8(v) as usize, tables().encode.partition_point(|&t| t <= v), "{v}");
        }
        for code in 0..=255u8 {
            assert_eq!(linear_to_srgb8(srgb8_to_linear(code)), code);
            let exact = (linear_to_srgb(srgb8_to_linear(code) * 1.01) * 255.0).round() as u8;
            assert!(linear_to_srgb8(srgb8_to_linear(code) * 1.01).abs_diff(exact) <= 1);
        }
    }
}
