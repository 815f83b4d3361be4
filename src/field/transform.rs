//! The view's rotation and stretch: the linear map from a sample's offset in the image to its
//! offset in the plane.
//!
//! A view is a centre, a spacing and this map. Kalles Fraktaler 2.15 (and Fraktaler-3)
//! describe it by three numbers, and so do scenes (`[view] rotate`, `stretch_angle`,
//! `stretch_amount`), so that a `.kfr` converts digit for digit:
//!
//! M = Rot(−rotate) · Rot(stretch_angle) · diag(2^stretch_amount, 2^−stretch_amount) ·
//! Rot(−stretch_angle),
//!
//! applied to offsets with x to the right and y up (angles in degrees). The picture turns
//! counter-clockwise by `rotate`, and the plane is covered 2^stretch_amount times faster
//! along `stretch_angle` than across it (det M = 1: the pixel area is the spacing²
//! whatever the stretch). This is KF's `polar_composition` of (rotate, stretch factor,
//! stretch angle), written for deepfield's y-up offsets.
//!
//! The identity is kept exact (cos 0 = 1, sin 0 = 0) and every user checks
//! [`Transform::is_identity`] first, so views without a rotation or stretch compute the same
//! bits as before the map existed.

/// A rotation and stretch of the view (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Transform {
    /// Row-major 2×2 matrix: plane offset = m · image offset.
    m: [[f64; 2]; 2],
}

impl Default for Transform {
    fn default() -> Self {
        Self::IDENTITY
    }
}

/// The largest |stretch_amount| accepted: a factor of 2^20 either way.
pub const MAX_STRETCH_AMOUNT: f64 = 20.0;

impl Transform {
    /// No rotation, no stretch.
    pub const IDENTITY: Transform = Transform { m: [[1.0, 0.0], [0.0, 1.0]] };

    /// The map of `rotate` and `stretch_angle` (degrees) and `stretch_amount` (log2 of the
    /// stretch factor).
    pub fn new(rotate: f64, stretch_angle: f64, stretch_amount: f64) -> Self {
        if rotate == 0.0 && stretch_amount == 0.0 {
            return Self::IDENTITY;
        }
        let rot = |deg: f64| {
            let (s, c) = deg.to_radians().sin_cos();
            [[c, -s], [s, c]]
        };
        let k = stretch_amount.exp2();
        let stretch = [[k, 0.0], [0.0, 1.0 / k]];
        let m = mul(mul(mul(rot(-rotate), rot(stretch_angle)), stretch), rot(-stretch_angle));
        Transform { m }
    }

    /// True for the identity (nothing to apply).
    #[inline]
    pub fn is_identity(&self) -> bool {
        *self == Self::IDENTITY
    }

    /// The plane offset of image offset `v` (x right, y up).
    #[inline]
    pub fn apply(&self, v: [f64; 2]) -> [f64; 2] {
        if self.is_identity() {
            return v;
        }
        let m = &self.m;
        [m[0][0] * v[0] + m[0][1] * v[1], m[1][0] * v[0] + m[1][1] * v[1]]
    }

    /// The image offset of plane offset `p` (the inverse map; det M = 1).
    #[inline]
    pub fn invert(&self, p: [f64; 2]) -> [f64; 2] {
        if self.is_identity() {
            return p;
        }
        let m = &self.m;
        let det = m[0][0] * m[1][1] - m[0][1] * m[1][0];
        [(m[1][1] * p[0] - m[0][1] * p[1]) / det, (-m[1][0] * p[0] + m[0][0] * p[1]) / det]
    }

    /// A gradient `g` taken in the plane, seen in the image (Mᵀ g), keeping its length: the
    /// distance estimate's direction in image terms (its length stays the plane distance in
    /// spacings).
    #[inline]
    pub fn gradient_to_image(&self, g: [f64; 2]) -> [f64; 2] {
        if self.is_identity() {
            return g;
        }
        let m = &self.m;
        let t = [m[0][0] * g[0] + m[1][0] * g[1], m[0][1] * g[0] + m[1][1] * g[1]];
        let (len, tl) = (g[0].hypot(g[1]), t[0].hypot(t[1]));
        if tl > 0.0 && tl.is_finite() { [t[0] * len / tl, t[1] * len / tl] } else { g }
    }

    /// The largest |M v| over the corners v = (±w/2, ±h/2) of a `w` × `h` image, in
    /// spacings: how far from the centre any sample lies in the plane.
    pub fn max_offset(&self, w: f64, h: f64) -> f64 {
        if self.is_identity() {
            return w.hypot(h) * 0.5;
        }
        [[w, h], [w, -h]]
            .iter()
            .map(|c| {
                let p = self.apply([c[0] * 0.5, c[1] * 0.5]);
                p[0].hypot(p[1])
            })
            .fold(0.0, f64::max)
    }
}

/// 2×2 matrix product.
fn mul(a: [[f64; 2]; 2], b: [[f64; 2]; 2]) -> [[f64; 2]; 2] {
    std::array::from_fn(|i| std::array::from_fn(|j| a[i][0] * b[0][j] + a[i][1] * b[1][j]))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: [f64; 2], b: [f64; 2]) -> bool {
        (a[0] - b[0]).abs() < 1e-12 && (a[1] - b[1]).abs() < 1e-12
    }

    #[test]
    fn zero_angles_are_the_exact_identity() {
        assert!(Transform::new(0.0, 37.0, 0.0).is_identity());
        assert_eq!(Transform::new(0.0, 0.0, 0.0).apply([0.3, -7.5]), [0.3, -7.5]);
    }

    #[test]
    fn rotation_turns_the_picture_counter_clockwise() {
        // Turning the picture by 90° counter-clockwise: the image's x axis (to the right)
        // shows the plane's -y direction, so a feature on the plane's +x axis appears up.
        let t = Transform::new(90.0, 0.0, 0.0);
        assert!(close(t.apply([1.0, 0.0]), [0.0, -1.0]), "{:?}", t.apply([1.0, 0.0]));
        assert!(close(t.invert([1.0, 0.0]), [0.0, 1.0]));
    }

    #[test]
    fn stretch_scales_along_its_angle_and_keeps_area() {
        let t = Transform::new(0.0, 90.0, 1.0);
        // Along 90° (image y) the plane is covered twice as fast; across, half as fast.
        assert!(close(t.apply([0.0, 1.0]), [0.0, 2.0]));
        assert!(close(t.apply([1.0, 0.0]), [0.5, 0.0]));
        for v in [[0.3, -1.2], [5.0, 2.0]] {
            assert!(close(t.invert(t.apply(v)), v));
        }
        // Corner (2, 1) lands at (1, 2).
        assert!((t.max_offset(4.0, 2.0) - 1f64.hypot(2.0)).abs() < 1e-12);
    }

    #[test]
    fn gradients_follow_the_picture() {
        // A gradient pointing along the plane's +x shows, in a picture turned 90°
        // counter-clockwise, pointing up.
        let g = Transform::new(90.0, 0.0, 0.0).gradient_to_image([2.0, 0.0]);
        assert!((g[0]).abs() < 1e-6 && (g[1] - 2.0).abs() < 1e-6, "{g:?}");
    }
}
