//! Ground truth by direct arbitrary-precision iteration (astro-float), independent of the
//! engine's code: its own step, its own derivative, exact pixel coordinates from the
//! decimal centre.

use astro_float::{BigFloat, Consts, Radix, RoundingMode, Sign};

const RM: RoundingMode = RoundingMode::ToEven;

/// Converts a big float to the nearest f64 (to within one ulp; plenty for comparisons).
pub fn to_f64(x: &BigFloat) -> f64 {
    if x.is_zero() {
        return 0.0;
    }
    let (words, _bits, sign, exp, _) = x.as_raw_parts().expect("finite");
    let top = *words.last().expect("mantissa") as f64;
    let next = if words.len() > 1 { words[words.len() - 2] as f64 / 2f64.powi(64) } else { 0.0 };
    // Two steps so that exponents near the ends of the f64 range do not overflow early.
    let v = (top + next) * 2f64.powi(-64) * 2f64.powi(exp);
    if sign == Sign::Neg { -v } else { v }
}

/// Exact decimal text to a big float.
pub fn parse(text: &str, p: usize) -> BigFloat {
    let mut cc = Consts::new().expect("constants");
    BigFloat::parse(text, Radix::Dec, p, RM, &mut cc)
}

/// The exact point of pixel (i, j) of a view (the coordinate convention of docs/design.md).
pub fn pixel(center: [&str; 2], radius: &str, width: u32, height: u32, i: u32, j: u32, p: usize) -> [BigFloat; 2] {
    let r = parse(radius, p);
    let h = BigFloat::from_f64(height as f64, p);
    let ox = BigFloat::from_f64(2.0 * i as f64 + 1.0 - width as f64, p).mul(&r, p, RM).div(&h, p, RM);
    let oy = BigFloat::from_f64(2.0 * j as f64 + 1.0 - height as f64, p).mul(&r, p, RM).div(&h, p, RM);
    [parse(center[0], p).add(&ox, p, RM), parse(center[1], p).sub(&oy, p, RM)]
}

/// What the reference found for one orbit.
#[derive(Debug, Clone)]
pub struct Truth {
    /// First n with |z_n| > R, or None.
    pub n: Option<u32>,
    /// z_n.
    pub z: [f64; 2],
    /// dz_n.
    pub dz: [f64; 2],
    /// Some |z_k| was within 1e-9 relative of R: N is ill-conditioned there.
    pub near_circle: bool,
}

/// Iterates z -> z^2 + c directly. `julia`: Some(c) iterates from z0 = point with dz0 = 1;
/// None is the Mandelbrot set (z0 = 0, dz0 = 0, dz' = 2 z dz + 1).
pub fn orbit(point: &[BigFloat; 2], julia: Option<&[BigFloat; 2]>, max_iter: u32, radius: f64, p: usize) -> Truth {
    orbit_scaled(point, julia, max_iter, radius, p, None)
}

/// Like [`orbit`], with the returned dz multiplied by `dz_scale` before rounding to f64
/// (deep views: dz itself is far outside the f64 range, dz times the pixel spacing is not).
pub fn orbit_scaled(
    point: &[BigFloat; 2],
    julia: Option<&[BigFloat; 2]>,
    max_iter: u32,
    radius: f64,
    p: usize,
    dz_scale: Option<&BigFloat>,
) -> Truth {
    let zero = BigFloat::from_f64(0.0, p);
    let one = BigFloat::from_f64(1.0, p);
    let two = BigFloat::from_f64(2.0, p);
    let (mut x, mut y, cx, cy, mut dx, mut dy, dadd) = match julia {
        Some(c) => {
            (point[0].clone(), point[1].clone(), c[0].clone(), c[1].clone(), one.clone(), zero.clone(), zero.clone())
        }
        None => {
            (zero.clone(), zero.clone(), point[0].clone(), point[1].clone(), zero.clone(), zero.clone(), one.clone())
        }
    };
    let r2 = radius * radius;
    let mut near = false;
    for n in 0..=max_iter {
        let xx = x.mul(&x, p, RM);
        let yy = y.mul(&y, p, RM);
        let m2 = to_f64(&xx.add(&yy, p, RM));
        if ((m2 / r2).sqrt() - 1.0).abs() < 1e-9 {
            near = true;
        }
        if m2 > r2 {
            return Truth {
                n: Some(n),
                z: [to_f64(&x), to_f64(&y)],
                dz: match dz_scale {
                    Some(k) => [to_f64(&dx.mul(k, p, RM)), to_f64(&dy.mul(k, p, RM))],
                    None => [to_f64(&dx), to_f64(&dy)],
                },
                near_circle: near,
            };
        }
        if n == max_iter {
            break;
        }
        // dz <- 2 z dz + dadd
        let ndx = x.mul(&dx, p, RM).sub(&y.mul(&dy, p, RM), p, RM).mul(&two, p, RM).add(&dadd, p, RM);
        let ndy = x.mul(&dy, p, RM).add(&y.mul(&dx, p, RM), p, RM).mul(&two, p, RM);
        let nx = xx.sub(&yy, p, RM).add(&cx, p, RM);
        let ny = x.mul(&y, p, RM).mul(&two, p, RM).add(&cy, p, RM);
        (x, y, dx, dy) = (nx, ny, ndx, ndy);
    }
    Truth { n: None, z: [0.0; 2], dz: [0.0; 2], near_circle: near }
}

#[test]
fn conversion_to_f64_is_faithful() {
    for v in [1.0, -0.75, 3.0e-20, 123456.789, -2.0f64.powi(-300)] {
        let b = BigFloat::from_f64(v, 128);
        assert_eq!(to_f64(&b), v);
    }
    let third = parse("0.333333333333333333333333333333", 256);
    assert!((to_f64(&third) - 1.0 / 3.0).abs() < 1e-16);
}
