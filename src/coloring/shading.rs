//! Pure per-sample functions of the distance estimate: the soft distance colouring of Inigo Quilez's Mandelbrot distance shader,
//! distance transfers, antialiased boundary coverage and slope lighting.
//!
//! Distances arrive in image pixels. The DE vector (DEX, DEY) points along the gradient of
//! the potential, away from the set: read as the normal of a height field it lights the
//! image as a relief, the "slope" or "3D lighting" colouring of Ultra Fractal and Kalles
//! Fraktaler (after the normal-map colouring described by Arnaud Chéritat).

use crate::num::fastmath;
use crate::simd_level::SimdLevel;

/// How a distance layer maps distance (image pixels) to palette position or grey level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DistanceStyle {
    /// Inigo Quilez's soft colouring: clamp((k d)^0.2, 0, 1).
    Soft {
        /// Scale k per pixel.
        k: f64,
    },
    /// d * density.
    Linear {
        /// Palette cycles per pixel.
        density: f64,
    },
    /// ln(1 + d) * density.
    Log {
        /// Palette cycles per unit of ln(1 + d).
        density: f64,
    },
}

impl DistanceStyle {
    /// The value for distance `d` (pixels, >= 0).
    #[inline(always)]
    pub fn value(self, d: f64) -> f64 {
        let mut v = [d];
        self.values(SimdLevel::Scalar, &mut v);
        v[0]
    }

    /// [`DistanceStyle::value`] of every distance of a run, in place, under `simd`'s
    /// instruction set ([`SimdLevel::map`]): the same bits at every width.
    pub fn values(self, simd: SimdLevel, v: &mut [f64]) {
        match self {
            DistanceStyle::Soft { k } => simd.map(v, |d| soft(k, d)),
            DistanceStyle::Linear { density } => simd.map(v, |d| d * density),
            DistanceStyle::Log { density } => simd.map(v, |d| fastmath::ln_1p(d) * density),
        }
    }
}

/// The soft style's clamp((k d)^0.2, 0, 1), in f32 (ample for a value in [0, 1]; at and
/// above 1 the value is 1).
#[inline(always)]
fn soft(k: f64, d: f64) -> f64 {
    let x = (k * d) as f32;
    f64::from(if x >= 1.0 { 1.0 } else { fastmath::fifth_root(x) }).clamp(0.0, 1.0)
}

/// Coverage in [0, 1] of a boundary line `width` pixels wide at distance `d` from the set
/// (antialiased over one pixel).
#[inline]
pub fn boundary_cover(d: f64, width: f64) -> f32 {
    (width * 0.5 + 0.5 - d).clamp(0.0, 1.0) as f32
}

/// A light for slope shading.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Light {
    /// Unit vector towards the light in the image plane (x right, y up).
    pub dir: [f64; 2],
    /// Height of the light above the plane (0: grazing; larger: flatter, brighter).
    pub height: f64,
    /// How much the shading darkens: 0 none, 1 full.
    pub strength: f64,
}

impl Light {
    /// A light from the angle in degrees (counter-clockwise from the +x axis).
    pub fn new(angle_degrees: f64, height: f64, strength: f64) -> Self {
        let a = angle_degrees.to_radians();
        Self { dir: [a.cos(), a.sin()], height, strength }
    }

    /// Brightness in [0, 1] at a sample with DE vector (dx, dy): Lambert-like
    /// (n . l + h) / (1 + h), clamped, then mixed towards 1 by 1 - strength.
    #[inline]
    pub fn shade(&self, dx: f32, dy: f32) -> f32 {
        let (dx, dy) = (dx as f64, dy as f64);
        let len = (dx * dx + dy * dy).sqrt();
        let cos = if len > 0.0 && len.is_finite() { (dx * self.dir[0] + dy * self.dir[1]) / len } else { 0.0 };
        let b = ((cos + self.height) / (1.0 + self.height)).clamp(0.0, 1.0);
        (1.0 - self.strength * (1.0 - b)) as f32
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::simd_level::testing::{every_level_matches, uniform};

    #[test]
    fn soft_distance_is_quilez_s_fifth_root() {
        let s = DistanceStyle::Soft { k: 8.0 };
        assert_eq!(s.value(0.0), 0.0);
        assert!((s.value(1.0) - 8f64.powf(0.2).min(1.0)).abs() < 1e-7);
        assert!((s.value(1.0 / 32.0) - 0.25f64.powf(0.2)).abs() < 1e-7);
        assert_eq!(DistanceStyle::Log { density: 2.0 }.value(0.0), 0.0);
    }

    #[test]
    fn every_instruction_set_gives_the_values_of_one_sample_at_a_time() {
        // Distances from 1e-12 to 1e6 pixels, and the edges.
        let mut d: Vec<f64> = uniform(7, 1000).into_iter().map(|u| 10f64.powf(u * 18.0 - 12.0)).collect();
        d.extend([0.0, 1.0, 1.0 / 32.0, f64::INFINITY, f64::NAN, 1e-320]);
        for style in
            [DistanceStyle::Soft { k: 8.0 }, DistanceStyle::Soft { k: 0.01 }, DistanceStyle::Log { density: 0.3 }]
        {
            every_level_matches(&d, |x| style.value(x), |l, v| style.values(l, v), &format!("{style:?}"));
        }
    }

    #[test]
    fn boundary_is_antialiased() {
        assert_eq!(boundary_cover(0.0, 1.0), 1.0);
        assert_eq!(boundary_cover(0.5, 1.0), 0.5);
        assert_eq!(boundary_cover(2.0, 1.0), 0.0);
        assert_eq!(boundary_cover(1.5, 3.0), 0.5);
    }

    #[test]
    fn light_facing_and_away() {
        let l = Light::new(0.0, 0.0, 1.0);
        assert_eq!(l.shade(3.0, 0.0), 1.0);
        assert_eq!(l.shade(-3.0, 0.0), 0.0);
        assert!((l.shade(0.0, 2.0)).abs() < 1e-7);
        let soft = Light::new(90.0, 1.0, 0.5);
        // Perpendicular: (0 + 1) / 2 = 0.5 brightness, half strength: 0.75.
        assert!((soft.shade(1.0, 0.0) - 0.75).abs() < 1e-6);
        assert_eq!(l.shade(0.0, 0.0), 0.0);
    }
}
