//! How a raster covers the plane: a flat image, or a strip of an exponential map.
//!
//! An exponential map (Kalles Fraktaler's and Fraktaler-3's "exponential map" zoom
//! output, after Claude Heiland-Allen's "Optimizing zoom animations again") unrolls an
//! annulus about the view's centre into a rectangle: column i of W is the angle
//! θ = 2π (i + ½) / W, counter-clockwise from the positive real axis, and row j of H the
//! radius R · F^−(j + ½)/H, from the outer circle R (the top row) inwards to R / F. With
//! H = W ln F / 2π its pixels are square, and one strip per factor F of zoom holds a
//! whole zoom video at the fewest samples there are: every ring is computed once, at the
//! density the frames need there.
//!
//! Offsets are in units of the view's spacing 2R / H (the flat raster's convention, so the
//! perturbation engine and its precision rules take both alike); R is the view's radius.
//! Distance-estimate vectors come back in the strip's own image terms: x along the angle
//! (increasing i), y outwards (decreasing j), in units of the strip's local pixel (the
//! width of a column at that radius).

use std::f64::consts::TAU;

/// The shape of a raster in the plane.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Projection {
    /// A flat image (sample offsets are half-integers of the spacing).
    #[default]
    Flat,
    /// One strip of an exponential map covering radii R down to R / F.
    Exponential {
        /// ln F.
        ln_factor: f64,
    },
}

impl Projection {
    /// True for a flat image.
    #[inline]
    pub fn is_flat(&self) -> bool {
        matches!(self, Projection::Flat)
    }

    /// The offset of sample (i, j) of a `width` x `height` strip from the centre, in
    /// spacings, x right and y up. Only for [`Projection::Exponential`] (flat rasters use
    /// [`super::image_offset`]).
    #[inline]
    pub fn polar_offset(ln_factor: f64, width: u32, height: u32, i: u32, j: u32) -> [f64; 2] {
        let r = radius(ln_factor, height, j);
        let (s, c) = angle(width, i).sin_cos();
        [r * c, r * s]
    }

    /// Turns a distance-estimate vector at sample (i, j), in plane terms and spacings, into
    /// the strip's image terms and local pixels (see the module documentation).
    pub fn gradient_to_image(ln_factor: f64, width: u32, height: u32, i: u32, j: u32, g: [f64; 2]) -> [f64; 2] {
        let (s, c) = angle(width, i).sin_cos();
        let pixel = radius(ln_factor, height, j) * TAU / width as f64;
        let radial = g[0] * c + g[1] * s;
        let tangential = -g[0] * s + g[1] * c;
        [tangential / pixel, radial / pixel]
    }
}

/// The angle of column i.
#[inline]
fn angle(width: u32, i: u32) -> f64 {
    TAU * (i as f64 + 0.5) / width as f64
}

/// The radius of row j in spacings (the outer circle is height / 2 of them).
#[inline]
fn radius(ln_factor: f64, height: u32, j: u32) -> f64 {
    0.5 * height as f64 * (-ln_factor * (j as f64 + 0.5) / height as f64).exp()
}

/// The strip size for video frames of `width` x `height` pixels with `aa` samples per
/// pixel side, and a zoom factor F per strip: W columns put `aa` samples per frame pixel
/// around the frame's circumscribed circle, and H = W ln F / 2π rows keep them square.
pub fn strip_size(width: u32, height: u32, aa: u32, ln_factor: f64) -> (u32, u32) {
    let diagonal = (width as f64).hypot(height as f64);
    let w = (std::f64::consts::PI * diagonal * aa as f64).ceil();
    let h = (w * ln_factor / TAU).round().max(1.0);
    (w as u32, h as u32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rows_run_from_the_outer_circle_inwards_by_the_factor() {
        let ln2 = 2f64.ln();
        let (w, h) = (2304, 256);
        let top = Projection::polar_offset(ln2, w, h, 0, 0);
        let bottom = Projection::polar_offset(ln2, w, h, 0, h - 1);
        let r = |p: [f64; 2]| p[0].hypot(p[1]);
        // Half a row inside R at the top, half a row outside R / 2 at the bottom.
        assert!((r(top) - 128.0 * (-ln2 / 512.0).exp()).abs() < 1e-9);
        assert!((r(bottom) - 64.0 * (ln2 / 512.0).exp()).abs() < 1e-9);
        // A quarter of the columns turns a quarter circle, counter-clockwise.
        let a = Projection::polar_offset(ln2, w, h, 0, 5);
        let b = Projection::polar_offset(ln2, w, h, w / 4, 5);
        let turned = [-a[1], a[0]];
        assert!((b[0] - turned[0]).abs() < 1e-9 && (b[1] - turned[1]).abs() < 1e-9);
    }

    #[test]
    fn the_strip_for_640_by_360_is_2307_by_255() {
        // Claude Heiland-Allen's example: 2304 x 256 for 640 x 360 at one sample per pixel.
        assert_eq!(strip_size(640, 360, 1, 2f64.ln()), (2307, 255));
    }

    #[test]
    fn gradients_turn_into_strip_terms() {
        let ln2 = 2f64.ln();
        // At angle 90 degrees, the outward direction is +y in the plane.
        let (w, h) = (4, 4);
        let i = 0; // angle 45 degrees for w = 4: use a radial vector at that angle
        let (s, c) = (std::f64::consts::FRAC_PI_4).sin_cos();
        let g = Projection::gradient_to_image(ln2, w, h, i, 0, [c, s]);
        assert!(g[0].abs() < 1e-12 && g[1] > 0.0, "{g:?}");
        let t = Projection::gradient_to_image(ln2, w, h, i, 0, [-s, c]);
        assert!(t[1].abs() < 1e-12 && t[0] > 0.0, "{t:?}");
    }
}
