//! The bitmap orbit trap: an image placed in the z-plane, sampled along the orbit.
//!
//! Pixels are stored as linear-light, premultiplied RGBA so that bilinear filtering blends
//! colours physically and transparent texels carry no colour into their neighbours. The
//! affine map from z to texture coordinates is: rotate z - centre by -angle, divide by the
//! bitmap's extent in the plane, shift so the centre lands on (0.5, 0.5), v pointing down.

use std::sync::Arc;

/// Decoded image, linear premultiplied RGBA, row-major from the top-left texel.
#[derive(Debug, Clone, PartialEq)]
pub struct Bitmap {
    /// Width in texels.
    pub width: usize,
    /// Height in texels.
    pub height: usize,
    /// Texels, `width * height` of them.
    pub texels: Vec<[f32; 4]>,
}

impl Bitmap {
    /// Bilinear sample at texture coordinates (u, v), each clamped to [0, 1]; texel centres
    /// sit at (i + 0.5) / width, and coordinates beyond the outer centres clamp to the edge.
    pub fn sample(&self, u: f64, v: f64) -> [f32; 4] {
        self.sample_columns(u, v, 0, self.width)
    }

    /// Bilinear sample of the sub-image of columns `first .. first + cols` (a frame of a
    /// sprite sheet) at its own texture coordinates (u, v), clamped to [0, 1]; filtering
    /// never reads a neighbouring frame.
    pub fn sample_columns(&self, u: f64, v: f64, first: usize, cols: usize) -> [f32; 4] {
        let fx = u.clamp(0.0, 1.0) * cols as f64 - 0.5;
        let fy = v.clamp(0.0, 1.0) * self.height as f64 - 0.5;
        let x0 = fx.floor();
        let y0 = fy.floor();
        let tx = (fx - x0) as f32;
        let ty = (fy - y0) as f32;
        let clampi = |a: f64, n: usize| (a.max(0.0) as usize).min(n - 1);
        let (xa, xb) = (first + clampi(x0, cols), first + clampi(x0 + 1.0, cols));
        let (ya, yb) = (clampi(y0, self.height), clampi(y0 + 1.0, self.height));
        let t = |x: usize, y: usize| self.texels[y * self.width + x];
        let (p00, p10, p01, p11) = (t(xa, ya), t(xb, ya), t(xa, yb), t(xb, yb));
        let mut out = [0.0f32; 4];
        for k in 0..4 {
            let top = p00[k] + (p10[k] - p00[k]) * tx;
            let bottom = p01[k] + (p11[k] - p01[k]) * tx;
            out[k] = top + (bottom - top) * ty;
        }
        out
    }
}

/// A bitmap placed in the z-plane.
#[derive(Debug, Clone, PartialEq)]
pub struct BitmapTrap {
    /// The image.
    pub bitmap: Arc<Bitmap>,
    /// Point of the plane at the image centre.
    pub center: [f64; 2],
    /// Width of the image in the plane (its height follows the image's aspect ratio).
    pub size: f64,
    /// (cos, sin) of the image's rotation.
    pub rotation: [f64; 2],
    /// Alpha a sample must exceed to count as a hit.
    pub threshold: f32,
    /// The frame of a sprite sheet to use, when the image is one.
    pub frame: Option<Frame>,
}

/// A frame of a sprite sheet: the image holds `count` frames side by side, each
/// `width` texels wide from the left edge (the animated trap of Inigo Quilez's "Bitmap Orbit Traps": 6 frames of 40 texels
/// in a 256-texel texture, frame = floor(20 t) mod 6).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Frame {
    /// Which frame (taken modulo `count`).
    pub index: u32,
    /// Frames in the sheet.
    pub count: u32,
    /// Width of one frame in texels.
    pub width: u32,
}

impl BitmapTrap {
    /// Texture coordinates of a point of the plane (not clamped).
    #[inline]
    pub fn uv(&self, z: [f64; 2]) -> (f64, f64) {
        let dx = z[0] - self.center[0];
        let dy = z[1] - self.center[1];
        let [c, s] = self.rotation;
        let rx = c * dx + s * dy;
        let ry = -s * dx + c * dy;
        let w = self.frame.map_or(self.bitmap.width, |f| f.width as usize);
        let h = self.size * self.bitmap.height as f64 / w as f64;
        (0.5 + rx / self.size, 0.5 - ry / h)
    }

    /// The texel colour seen at `z`.
    #[inline]
    pub fn sample(&self, z: [f64; 2]) -> [f32; 4] {
        let (u, v) = self.uv(z);
        match self.frame {
            None => self.bitmap.sample(u, v),
            Some(f) => {
                let first = ((f.index % f.count) * f.width) as usize;
                self.bitmap.sample_columns(u, v, first, f.width as usize)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker() -> Bitmap {
        // 2x2: opaque red, transparent / transparent, opaque blue.
        Bitmap { width: 2, height: 2, texels: vec![[1.0, 0.0, 0.0, 1.0], [0.0; 4], [0.0; 4], [0.0, 0.0, 1.0, 1.0]] }
    }

    #[test]
    fn texel_centres_are_exact() {
        let b = checker();
        assert_eq!(b.sample(0.25, 0.25), [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(b.sample(0.75, 0.75), [0.0, 0.0, 1.0, 1.0]);
        assert_eq!(b.sample(-3.0, 0.0), [1.0, 0.0, 0.0, 1.0]);
        assert_eq!(b.sample(0.5, 0.25), [0.5, 0.0, 0.0, 0.5]);
    }

    #[test]
    fn frames_sample_their_own_columns() {
        // 4x1 sheet of 2 frames, 2 texels each: red, green | blue, white.
        let sheet = Bitmap {
            width: 4,
            height: 1,
            texels: vec![[1.0, 0.0, 0.0, 1.0], [0.0, 1.0, 0.0, 1.0], [0.0, 0.0, 1.0, 1.0], [1.0; 4]],
        };
        assert_eq!(sheet.sample_columns(0.0, 0.5, 2, 2), [0.0, 0.0, 1.0, 1.0]);
        assert_eq!(sheet.sample_columns(1.0, 0.5, 2, 2), [1.0; 4]);
        // The right edge of frame 0 never bleeds into frame 1.
        assert_eq!(sheet.sample_columns(1.0, 0.5, 0, 2), [0.0, 1.0, 0.0, 1.0]);
        let trap = BitmapTrap {
            bitmap: Arc::new(sheet),
            center: [0.0, 0.0],
            size: 2.0,
            rotation: [1.0, 0.0],
            threshold: 0.1,
            frame: Some(Frame { index: 3, count: 2, width: 2 }),
        };
        // Frame 3 mod 2 = 1; the left edge of the plane square is the frame's left texel.
        assert_eq!(trap.sample([-1.0, 0.0]), [0.0, 0.0, 1.0, 1.0]);
    }

    #[test]
    fn uv_maps_centre_and_corners() {
        let trap = BitmapTrap {
            bitmap: Arc::new(checker()),
            center: [1.0, 2.0],
            size: 2.0,
            rotation: [1.0, 0.0],
            threshold: 0.1,
            frame: None,
        };
        assert_eq!(trap.uv([1.0, 2.0]), (0.5, 0.5));
        assert_eq!(trap.uv([0.0, 3.0]), (0.0, 0.0));
        assert_eq!(trap.uv([2.0, 1.0]), (1.0, 1.0));
    }
}
