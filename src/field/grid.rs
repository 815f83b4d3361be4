//! The sample raster: which point of the plane each sample stands for (the coordinate convention of docs/design.md).

use super::{Projection, Transform};

/// A raster of samples over a view: sample (i, j) sits at the centre of its cell, at image
/// offset `(2(i + 0.5) - width, height - 2(j + 0.5)) / 2` spacings from the centre (x right,
/// y up), which the view's [`Transform`] (rotation and stretch, usually the identity) maps
/// into the plane: without one, `x = cx + radius * (2(i + 0.5) - width) / height`,
/// `y = cy - radius * (2(j + 0.5) - height) / height`.
/// With NxN supersampling the grid is simply N times finer than the image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SampleGrid {
    /// View centre (rounded to f64).
    pub center: [f64; 2],
    /// Half the height of the view in the plane.
    pub radius: f64,
    /// Samples per row.
    pub width: u32,
    /// Sample rows.
    pub height: u32,
    /// Rotation and stretch of the view.
    pub transform: Transform,
    /// A flat image or a strip of an exponential map.
    pub projection: Projection,
}

impl SampleGrid {
    /// The point of sample (i, j).
    #[inline]
    pub fn point(&self, i: u32, j: u32) -> [f64; 2] {
        if !self.transform.is_identity() || !self.projection.is_flat() {
            let o = self.offset(i, j);
            let s = self.spacing();
            return [self.center[0] + o[0] * s, self.center[1] + o[1] * s];
        }
        let h = self.radius / self.height as f64;
        let ox = (2.0 * i as f64 + 1.0 - self.width as f64) * h;
        let oy = (2.0 * j as f64 + 1.0 - self.height as f64) * h;
        [self.center[0] + ox, self.center[1] - oy]
    }

    /// The offset of sample (i, j) from the centre in the plane, in units of the spacing
    /// (exact halves without a transform).
    #[inline]
    pub fn offset(&self, i: u32, j: u32) -> [f64; 2] {
        match self.projection {
            Projection::Flat => self.transform.apply(image_offset(self.width, self.height, i, j)),
            Projection::Exponential { ln_factor } => {
                self.transform.apply(Projection::polar_offset(ln_factor, self.width, self.height, i, j))
            }
        }
    }

    /// The largest |offset| of any sample, in units of the spacing.
    pub fn max_offset(&self) -> f64 {
        match self.projection {
            Projection::Flat => self.transform.max_offset(self.width as f64, self.height as f64),
            // The outer circle (a rotation keeps it; a stretch is refused with a map).
            Projection::Exponential { .. } => 0.5 * self.height as f64,
        }
    }

    /// Distance between neighbouring samples in the plane.
    pub fn spacing(&self) -> f64 {
        2.0 * self.radius / self.height as f64
    }
}

/// The offset of sample (i, j) of a `width` × `height` raster from its centre, in spacings,
/// x right and y up, before the view's transform (exact halves).
#[inline]
pub fn image_offset(width: u32, height: u32, i: u32, j: u32) -> [f64; 2] {
    let ox = (2.0 * i as f64 + 1.0 - width as f64) * 0.5;
    let oy = (2.0 * j as f64 + 1.0 - height as f64) * 0.5;
    [ox, -oy]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pixel_centres_follow_the_convention() {
        let g = SampleGrid {
            center: [0.0, 0.0],
            radius: 2.0,
            width: 4,
            height: 2,
            transform: Transform::IDENTITY,
            projection: Projection::Flat,
        };
        assert_eq!(g.point(0, 0), [-3.0, 1.0]);
        assert_eq!(g.point(3, 1), [3.0, -1.0]);
        assert_eq!(g.spacing(), 2.0);
    }
}
