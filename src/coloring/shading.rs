//! Pure per-sample functions of the distance estimate: the soft distance colouring of Inigo Quilez's Mandelbrot distance shader,
//! distance transfers, antialiased boundary coverage and slope lighting.
//!
//! Distances arrive in image pixels. The DE vector (DEX, DEY) points along the gradient of
//! the potential, away from the set: read as the normal of a height field it lights the
//! image as a relief, the "slope" or "3D lighting" colouring of Ultra Fractal and Kalles
//! Fraktaler (after the normal-map colouring described by Arnaud Chéritat).

use crate::num::fastmath;

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
    #[inline]
    pub fn value(self, d: f64) -> f64 {
        match self {
            // f32 is ample for a value in [0, 1], and libm's f32 pow is ~3x faster than f64's.
            DistanceStyle::Soft { k } => f64::from(((k * d) as f32).powf(0.2)).clamp(0.0, 1.0),
            DistanceStyle::Linear { density } => d * density,
            DistanceStyle::Log { density } => fastmath::ln_1p(d) * density,
        }
    }
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

    #[test]
    fn soft_distance_matches_the_seed() {
        let s = DistanceStyle::Soft { k: 8.0 };
        assert_eq!(s.value(0.0), 0.0);
        assert!((s.value(1.0) - 8f64.powf(0.2).min(1.0)).abs() < 1e-7);
        assert!((s.value(1.0 / 32.0) - 0.25f64.powf(0.2)).abs() < 1e-7);
        assert_eq!(DistanceStyle::Log { density: 2.0 }.value(0.0), 0.0);
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
