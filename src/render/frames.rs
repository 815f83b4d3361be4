//! Video frames from a zoom sequence: each frame of a continuous zoom is resampled from the
//! coloured keyframes around its depth, the way a zoom-video assembler (Claude Heiland-Allen's
//! zoomasm, or Kalles Fraktaler's own zoom-out playback) does it.
//!
//! Keyframe k (0 the outermost) shows a view `factor` times wider than keyframe k + 1, about
//! the same centre, at the same pixel size. A frame at depth z (a real number in keyframe
//! units: z = 2.5 lies halfway, in log zoom, between keyframes 2 and 3) shows the view
//! factor^-(z - k) times the width of keyframe k = floor(z). Each of its pixels is taken
//! from the deepest keyframe whose area holds it, so the centre always comes from the most
//! detailed data there is; where a keyframe is magnified (a pixel of it wider than a pixel
//! of the frame) it is read bilinearly, and where it is reduced, several bilinear taps over
//! the frame pixel's footprint are averaged. All of it in linear light.
//!
//! An exponential map (`deepfield zoom --exponential-map F`) is read the same way with
//! another lookup: a frame pixel at distance ρ from the centre and angle θ lies in the
//! strip and row that ring holds (strip k covers radii F^-k down to F^-(k+1) of the
//! outermost), at the column of its angle; rows are read bilinearly across strip edges and
//! columns wrap around. Inside the deepest ring the flat centre view is read instead.
//!
//! Frames are deterministic: every output pixel is a fixed function of its keyframes, so
//! the bytes do not depend on the thread count.

use rayon::prelude::*;

/// A coloured keyframe: linear RGB, row-major, top row first.
#[derive(Debug, Clone, PartialEq)]
pub struct Keyframe {
    /// Pixels per row.
    pub width: usize,
    /// Rows.
    pub height: usize,
    /// The pixels.
    pub rgb: Vec<[f32; 3]>,
}

impl Keyframe {
    /// Bilinear sample at continuous pixel coordinates (pixel (i, j) has its centre at
    /// (i + 0.5, j + 0.5)); coordinates outside are clamped to the edge pixels.
    fn bilinear(&self, x: f64, y: f64) -> [f32; 3] {
        let fx = (x - 0.5).clamp(0.0, (self.width - 1) as f64);
        let fy = (y - 0.5).clamp(0.0, (self.height - 1) as f64);
        let (i0, j0) = (fx as usize, fy as usize);
        let (i1, j1) = ((i0 + 1).min(self.width - 1), (j0 + 1).min(self.height - 1));
        let (wx, wy) = ((fx - i0 as f64) as f32, (fy - j0 as f64) as f32);
        let p = |i: usize, j: usize| self.rgb[j * self.width + i];
        let mix = |a: [f32; 3], b: [f32; 3], w: f32| std::array::from_fn(|c| a[c] + (b[c] - a[c]) * w);
        mix(mix(p(i0, j0), p(i1, j0), wx), mix(p(i0, j1), p(i1, j1), wx), wy)
    }
}

/// Where a frame lies in a sequence of `count` keyframes: the keyframe it zooms from and
/// how far (in log zoom, 0 ..= 1 of one factor) past it. The last keyframe is reached
/// exactly at z = count - 1.
pub fn locate(z: f64, count: usize) -> (usize, f64) {
    let last = count.saturating_sub(1);
    let z = z.clamp(0.0, last as f64);
    let k = (z.floor() as usize).min(last);
    (k, z - k as f64)
}

/// The depth (keyframe units) of frame `f` of `frames` for a zoom in from keyframe 0 to
/// keyframe `count - 1` at constant speed in log zoom (or out, reversed).
pub fn depth(f: usize, frames: usize, count: usize, zoom_out: bool) -> f64 {
    if frames < 2 {
        return if zoom_out { 0.0 } else { count.saturating_sub(1) as f64 };
    }
    let t = f as f64 / (frames - 1) as f64;
    let t = if zoom_out { 1.0 - t } else { t };
    t * count.saturating_sub(1) as f64
}

/// Frame at depth `z` (see [`depth`]), `width` x `height` pixels, from keyframes that are
/// each `factor` times wider than the next; `key(k)` gives keyframe k (all the same size,
/// with the frame's aspect ratio). Returns linear RGB, row-major.
pub fn frame<'a>(
    key: &(dyn Fn(usize) -> &'a Keyframe + Sync),
    count: usize,
    factor: f64,
    z: f64,
    width: usize,
    height: usize,
) -> Vec<[f32; 3]> {
    let (k, s) = locate(z, count);
    let base = key(k);
    let (kw, kh) = (base.width as f64, base.height as f64);
    // Keyframe-k pixels per frame pixel (same aspect: one scale for both axes).
    let scale = kh / height as f64 * factor.powf(-s);
    let mut out = vec![[0.0f32; 3]; width * height];
    out.par_chunks_mut(width).enumerate().for_each(|(j, row)| {
        for (i, o) in row.iter_mut().enumerate() {
            // The pixel's centre as an offset from the view's centre, in keyframe-k pixels.
            let ox = (i as f64 + 0.5 - width as f64 / 2.0) * scale;
            let oy = (j as f64 + 0.5 - height as f64 / 2.0) * scale;
            // The deepest keyframe that holds the whole footprint of this pixel.
            let (mut d, mut m) = (k, 1.0);
            while d + 1 < count {
                let m2 = m * factor;
                let half = scale * m2 / 2.0;
                if (ox * m2).abs() + half > kw / 2.0 || (oy * m2).abs() + half > kh / 2.0 {
                    break;
                }
                d += 1;
                m = m2;
            }
            let kf = key(d);
            let (cx, cy) = (ox * m + kw / 2.0, oy * m + kh / 2.0);
            // Keyframe pixels across one frame pixel: taps enough to cover them.
            let span = scale * m;
            let taps = span.ceil().clamp(1.0, 4.0) as usize;
            *o = if taps == 1 {
                kf.bilinear(cx, cy)
            } else {
                let mut sum = [0.0f32; 3];
                for ty in 0..taps {
                    for tx in 0..taps {
                        let dx = ((tx as f64 + 0.5) / taps as f64 - 0.5) * span;
                        let dy = ((ty as f64 + 0.5) / taps as f64 - 0.5) * span;
                        let p = kf.bilinear(cx + dx, cy + dy);
                        for c in 0..3 {
                            sum[c] += p[c];
                        }
                    }
                }
                let n = (taps * taps) as f32;
                sum.map(|v| v / n)
            };
        }
    });
    out
}

/// An exponential map's strips and the flat view inside its deepest ring.
pub struct Map<'a> {
    /// Strip k (0 the outermost), for the strips held; see `held`.
    pub strip: &'a (dyn Fn(usize) -> &'a Keyframe + Sync),
    /// How many strips the map has.
    pub count: usize,
    /// The strips held: a frame reads the deepest of them for rings deeper still (they are
    /// then a fraction of a frame pixel across).
    pub held: std::ops::Range<usize>,
    /// Zoom factor per strip.
    pub factor: f64,
    /// The square flat view inside the deepest ring (half its side is that ring's inner
    /// radius).
    pub center: &'a Keyframe,
}

impl Map<'_> {
    /// The colour of a tap in the frame at depth `z`.
    fn at(&self, tap: &Tap, z: f64) -> [f32; 3] {
        let ln_f = self.factor.ln();
        let t = tap.t + z;
        if t >= self.count as f64 {
            // Inside the deepest ring: the flat centre view, half-side F^-count.
            let c = self.center;
            let scale = (-z * ln_f).exp();
            let half = (-(self.count as f64) * ln_f).exp();
            let px = c.width as f64 / (2.0 * half);
            let (x, y) = (tap.x * scale, tap.y * scale);
            return c.bilinear(x * px + c.width as f64 / 2.0, -y * px + c.height as f64 / 2.0);
        }
        let t = t.max(0.0);
        let last = self.held.end - 1;
        let (k, frac) = match t.floor() as usize {
            k if k > last => (last, 1.0),
            k => (k.max(self.held.start), if k < self.held.start { 0.0 } else { t - k as f64 }),
        };
        let s = (self.strip)(k);
        let (w, h) = (s.width, s.height);
        let fu = tap.a * w as f64 - 0.5;
        let fv = frac * h as f64 - 0.5;
        let (u0, v0) = (fu.floor(), fv.floor());
        let (wu, wv) = ((fu - u0) as f32, (fv - v0) as f32);
        let col = |u: f64| (u as i64).rem_euclid(w as i64) as usize;
        // Row v of strip k, continuing into the neighbouring strips held.
        let px = |u: f64, v: f64| -> [f32; 3] {
            let v = v as i64;
            let (kk, vv) = if v < 0 && k > self.held.start {
                (k - 1, h - 1)
            } else if v >= h as i64 && k < last {
                (k + 1, 0)
            } else {
                (k, v.clamp(0, h as i64 - 1) as usize)
            };
            let strip = if kk == k { s } else { (self.strip)(kk) };
            strip.rgb[vv * strip.width + col(u).min(strip.width - 1)]
        };
        let mix = |a: [f32; 3], b: [f32; 3], w: f32| std::array::from_fn(|c| a[c] + (b[c] - a[c]) * w);
        mix(mix(px(u0, v0), px(u0 + 1.0, v0), wu), mix(px(u0, v0 + 1.0), px(u0 + 1.0, v0 + 1.0), wu), wv)
    }
}

/// A point a frame pixel reads from an exponential map, in terms that do not change from
/// frame to frame: its offset from the centre in units of the frame's circumscribed
/// radius, its ring coordinate at depth 0 (-log_F of that radius) and its angle in turns.
#[derive(Debug, Clone, Copy)]
struct Tap {
    x: f64,
    y: f64,
    t: f64,
    a: f64,
}

/// The taps of every pixel of a `width` x `height` frame read from an exponential map of
/// `strip_width` columns and factor F: frames differ only by their depth, so the polar
/// coordinates are computed once. Where a frame pixel spans several strip columns, it
/// takes up to 4 x 4 taps over its footprint.
pub struct MapTaps {
    width: usize,
    starts: Vec<usize>,
    taps: Vec<Tap>,
}

impl MapTaps {
    /// The taps for frames of this size.
    pub fn new(width: usize, height: usize, strip_width: usize, factor: f64) -> MapTaps {
        let ln_f = factor.ln();
        let pixel = 2.0 / (width as f64).hypot(height as f64);
        let tap = |x: f64, y: f64| {
            let rho = x.hypot(y);
            let t = if rho > 0.0 { -rho.ln() / ln_f } else { f64::INFINITY };
            Tap { x, y, t, a: y.atan2(x).rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU }
        };
        let mut starts = Vec::with_capacity(width * height + 1);
        let mut taps = Vec::new();
        for j in 0..height {
            for i in 0..width {
                starts.push(taps.len());
                let x = (i as f64 + 0.5 - width as f64 / 2.0) * pixel;
                let y = -(j as f64 + 0.5 - height as f64 / 2.0) * pixel;
                // Strip columns across this pixel (a column's width at its radius).
                let span = pixel * strip_width as f64 / (std::f64::consts::TAU * x.hypot(y).max(1e-300));
                let n = span.ceil().clamp(1.0, 4.0) as usize;
                for ty in 0..n {
                    for tx in 0..n {
                        let dx = ((tx as f64 + 0.5) / n as f64 - 0.5) * pixel;
                        let dy = ((ty as f64 + 0.5) / n as f64 - 0.5) * pixel;
                        taps.push(tap(x + dx, y + dy));
                    }
                }
            }
        }
        starts.push(taps.len());
        MapTaps { width, starts, taps }
    }
}

/// Frame at depth `z` (see [`depth`]) from an exponential map, through `taps` (made for
/// the frame's size and the map): the frame's circumscribed circle is the outer edge of
/// strip z (so frame 0 fills its corners from the outermost strip). Linear RGB, row-major.
pub fn frame_from_map(map: &Map<'_>, taps: &MapTaps, z: f64) -> Vec<[f32; 3]> {
    let mut out = vec![[0.0f32; 3]; taps.starts.len() - 1];
    out.par_chunks_mut(taps.width).enumerate().for_each(|(j, row)| {
        for (i, o) in row.iter_mut().enumerate() {
            let k = j * taps.width + i;
            let mine = &taps.taps[taps.starts[k]..taps.starts[k + 1]];
            if let [one] = mine {
                *o = map.at(one, z);
                continue;
            }
            let mut sum = [0.0f32; 3];
            for t in mine {
                let p = map.at(t, z);
                for c in 0..3 {
                    sum[c] += p[c];
                }
            }
            let n = mine.len() as f32;
            *o = sum.map(|v| v / n);
        }
    });
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn flat(w: usize, h: usize, f: impl Fn(usize, usize) -> [f32; 3]) -> Keyframe {
        Keyframe {
            width: w,
            height: h,
            rgb: (0..h).flat_map(|j| (0..w).map(move |i| (i, j))).map(|(i, j)| f(i, j)).collect(),
        }
    }

    /// A map whose strips hold, per pixel, the radius of its row: a frame reads back the
    /// distance of each of its pixels from the centre (in units of the outer radius).
    #[test]
    fn map_frames_read_the_ring_of_each_pixel() {
        let (w, h, count, factor) = (720usize, 80usize, 3usize, 2f64);
        let strips: Vec<Keyframe> = (0..count)
            .map(|k| {
                flat(w, h, |_, j| {
                    let r = factor.powf(-(k as f64) - (j as f64 + 0.5) / h as f64);
                    [r as f32, 0.0, 0.0]
                })
            })
            .collect();
        let center = flat(8, 8, |_, _| [-1.0, 0.0, 0.0]);
        let key = |k: usize| &strips[k];
        let map = Map { strip: &key, count, held: 0..count, factor, center: &center };
        let (fw, fh) = (64usize, 36usize);
        let taps = MapTaps::new(fw, fh, w, factor);
        let f = frame_from_map(&map, &taps, 0.5);
        let pixel = 2.0 * factor.powf(-0.5) / (fw as f64).hypot(fh as f64);
        for j in [0usize, 5, 17] {
            for i in [0usize, 10, 40, 63] {
                let x = (i as f64 + 0.5 - fw as f64 / 2.0) * pixel;
                let y = (j as f64 + 0.5 - fh as f64 / 2.0) * pixel;
                let want = x.hypot(y);
                let got = f[j * fw + i][0] as f64;
                assert!((got - want).abs() < 0.01 * want, "pixel {i},{j}: {got} vs {want}");
            }
        }
        // Deep enough, the centre pixels come from the flat view inside the deepest ring.
        let deep = frame_from_map(&map, &taps, 2.0);
        assert_eq!(deep[18 * 64 + 32], [-1.0, 0.0, 0.0]);
    }

    #[test]
    fn depth_runs_from_the_outermost_to_the_deepest() {
        assert_eq!(depth(0, 11, 3, false), 0.0);
        assert_eq!(depth(10, 11, 3, false), 2.0);
        assert_eq!(depth(5, 11, 3, false), 1.0);
        assert_eq!(depth(0, 11, 3, true), 2.0);
        assert_eq!(locate(2.0, 3), (2, 0.0));
        assert_eq!(locate(1.25, 3), (1, 0.25));
        assert_eq!(locate(-1.0, 3), (0, 0.0));
    }

    /// At a keyframe's own depth and size, the frame is that keyframe where no deeper one
    /// covers, and the deeper keyframe (reduced) where one does.
    #[test]
    fn a_frame_at_a_keyframe_is_that_keyframe_outside_the_next() {
        let outer = flat(8, 6, |i, j| [i as f32, j as f32, 0.0]);
        let inner = flat(8, 6, |_, _| [100.0, 100.0, 100.0]);
        let keys = [outer.clone(), inner];
        let f = frame(&|k| &keys[k], 2, 2.0, 0.0, 8, 6);
        for j in 0..6 {
            for i in 0..8 {
                let covered = (2..6).contains(&i) && (2..4).contains(&j);
                let want = if covered { [100.0; 3] } else { outer.rgb[j * 8 + i] };
                assert_eq!(f[j * 8 + i], want, "pixel {i},{j}");
            }
        }
        // At the deepest depth the frame is exactly the deepest keyframe.
        let last = frame(&|k| &keys[k], 2, 2.0, 1.0, 8, 6);
        assert_eq!(last, keys[1].rgb);
    }

    /// Halfway (in log zoom) between two keyframes, a linear ramp stays a ramp with the
    /// slope magnified by sqrt(factor).
    #[test]
    fn halfway_magnifies_by_the_square_root_of_the_factor() {
        let ramp = flat(64, 48, |i, _| [i as f32, 0.0, 0.0]);
        let keys = [ramp.clone(), flat(64, 48, |i, _| [31.5 + (i as f32 - 31.5) / 2.0, 0.0, 0.0])];
        let f = frame(&|k| &keys[k], 2, 2.0, 0.5, 64, 48);
        let row = &f[24 * 64..25 * 64];
        let slope = (row[40][0] - row[30][0]) / 10.0;
        assert!((slope as f64 - 2f64.sqrt().recip()).abs() < 1e-3, "slope {slope}");
    }
}
