//! Pure functions from an orbit's end (z_n, dz_n) to the per-sample quantities defined in docs/design.md.

/// Largest f32 below 1: NF is clamped into [0, 1).
const BELOW_ONE: f32 = 1.0 - f32::EPSILON / 2.0;
/// Distances are capped here so that no channel ever holds infinity (dz_n = 0 at a
/// critical point would otherwise give an infinite estimate).
pub const DISTANCE_CAP: f32 = 1e30;

/// Smooth iteration fraction NF = nu - n = 1 - log2(ln|z_n| / ln R), clamped to [0, 1).
#[inline]
pub fn smooth_fraction(z: [f64; 2], ln_r: f64) -> f32 {
    let ln_abs = 0.5 * (z[0] * z[0] + z[1] * z[1]).ln();
    let f = 1.0 - (ln_abs / ln_r).log2();
    (f as f32).clamp(0.0, BELOW_ONE)
}

/// The smooth fraction of a map of escape rate e^`ln_degree`: 1 - log_p(ln|z| / ln R),
/// clamped to [0, 1). At degree 2 it is [`smooth_fraction`], bit for bit.
#[inline]
pub fn smooth_fraction_of_degree(z: [f64; 2], ln_r: f64, ln_degree: f64) -> f32 {
    if ln_degree == std::f64::consts::LN_2 {
        return smooth_fraction(z, ln_r);
    }
    let ln_abs = 0.5 * (z[0] * z[0] + z[1] * z[1]).ln();
    let f = 1.0 - (ln_abs / ln_r).ln() / ln_degree;
    (f as f32).clamp(0.0, BELOW_ONE)
}

/// Phase of z_n in turns, in [0, 1).
#[inline]
pub fn phase(z: [f64; 2]) -> f32 {
    let t = z[1].atan2(z[0]) / std::f64::consts::TAU;
    let t = if t < 0.0 { t + 1.0 } else { t };
    (t as f32).clamp(0.0, BELOW_ONE)
}

/// Exterior distance estimate |z| ln|z| / |dz|, in units of `spacing`, as the vector of
/// that length along conj(dz / z) (the gradient of the potential, away from the set).
#[inline]
pub fn distance_vector(z: [f64; 2], dz: [f64; 2], spacing: f64) -> [f32; 2] {
    let abs_z = norm(z);
    let abs_dz = norm(dz);
    let d = abs_z * abs_z.ln() / abs_dz / spacing;
    let d = if d.is_finite() { (d as f32).min(DISTANCE_CAP) } else { DISTANCE_CAP };
    // conj(dz / z) has the direction of conj(dz) * z.
    let wx = dz[0] * z[0] + dz[1] * z[1];
    let wy = dz[0] * z[1] - dz[1] * z[0];
    let w = norm([wx, wy]);
    if w.is_finite() && w > 0.0 { [(d as f64 * wx / w) as f32, (d as f64 * wy / w) as f32] } else { [d, 0.0] }
}

/// |v|, by sqrt of the squared sum unless that overflows (then `hypot`).
#[inline]
fn norm(v: [f64; 2]) -> f64 {
    let s = v[0] * v[0] + v[1] * v[1];
    if s.is_finite() { s.sqrt() } else { v[0].hypot(v[1]) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn smooth_fraction_is_continuous_at_the_radius() {
        let ln_r = 1024f64.ln();
        // Just past R: nu - n -> 1 (clamped below one); at R^2: 0.
        assert!(smooth_fraction([1024.0 + 1e-9, 0.0], ln_r) > 0.999_999);
        assert!(smooth_fraction([1024.0 * 1024.0, 0.0], ln_r).abs() < 1e-7);
    }

    #[test]
    fn phase_in_turns() {
        assert_eq!(phase([1.0, 0.0]), 0.0);
        assert!((phase([0.0, 1.0]) - 0.25).abs() < 1e-7);
        assert!((phase([0.0, -1.0]) - 0.75).abs() < 1e-7);
    }

    #[test]
    fn distance_points_away_along_conjugate() {
        // z real, dz = i: conj(dz / z) = -i / |z|, so the vector points down.
        let v = distance_vector([100.0, 0.0], [0.0, 1.0], 1.0);
        let d = 100.0 * 100f64.ln();
        assert!((v[0]).abs() < 1e-3);
        assert!((v[1] as f64 + d).abs() < 1e-3);
    }
}
