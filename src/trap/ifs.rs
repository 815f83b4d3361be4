//! The minimal IFS density field (p ← abs(p)/dot(p,p) + offset, weighted accumulation) on
//! the CPU: its parameters and the density at a plane point, as a per-sample layer
//! quantity like a trap's. The GPU version (`gpu::ifs`, `ifs.wgsl`) runs the same f32
//! operations in the same order; it builds on this module, not the other way round.
//!
//! The field folds a 3D point again and again, p -> |p| / (p . p) + offset (the "kali"
//! fold), and measures how much successive squared radii differ: steps that barely change
//! |p|^2 contribute exp(-strength |mag - prev|^2.3), weighted by exp(-i / decay). The
//! density is max(0, 5 accum / total weight - 0.7): bright filaments where the fold
//! settles, dark elsewhere. A plane point (x, y) is the 3D point (x scale, y scale, z), so
//! `z` picks a slice of the 3D field and `scale` how much of it the view shows.

/// Smallest p . p divided by (the seed divided by zero at p = 0).
pub const MIN_MAG: f32 = 1e-20;
/// |mag - prev| is clamped into [MIN_STEP, MAX_STEP] before pow(.., 2.3): pow(0, y) and
/// infinities are undefined in WGSL, and exp(-strength MAX_STEP^2.3) is already zero.
pub const MIN_STEP: f32 = 1e-30;
/// See [`MIN_STEP`].
pub const MAX_STEP: f32 = 1e4;

/// Parameters of the IFS field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IfsParams {
    /// Added after each fold (the GLSL idiom's tunable vec3(-0.5, -0.4, -1.5)).
    pub offset: [f32; 3],
    /// The slice of the 3D field shown.
    pub z: f32,
    /// Folds.
    pub iterations: u32,
    /// Sharpness of the exp(-strength |d|^2.3) term.
    pub strength: f32,
    /// Weight of fold i: exp(-i / decay).
    pub decay: f32,
    /// Plane units to field units.
    pub scale: f32,
}

impl Default for IfsParams {
    fn default() -> Self {
        Self { offset: [-0.5, -0.4, -1.5], z: 0.0, iterations: 32, strength: 7.0, decay: 7.0, scale: 1.0 }
    }
}

/// The density at plane point (x, y), in f32, with the shader's operations in its order.
pub fn density(params: &IfsParams, x: f32, y: f32) -> f32 {
    let mut p = [x * params.scale, y * params.scale, params.z];
    let (mut accum, mut prev, mut total) = (0.0f32, 0.0f32, 0.0f32);
    for i in 0..params.iterations {
        let mag = p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        let m = mag.max(MIN_MAG);
        for k in 0..3 {
            p[k] = p[k].abs() / m + params.offset[k];
        }
        let w = (-(i as f32) / params.decay).exp();
        let step = (mag - prev).abs().clamp(MIN_STEP, MAX_STEP);
        accum += w * (-params.strength * step.powf(2.3)).exp();
        total += w;
        prev = mag;
    }
    if total <= 0.0 {
        return 0.0;
    }
    (5.0 * accum / total - 0.7).max(0.0)
}
