//! Misiurewicz points found in deep views, checked by their own orbits in astro-float
//! (independent of the finder's malachite arithmetic): z_(k+p) = z_k, entered from the
//! other side (z_(k+p-1) = -z_(k-1), so the preperiod is exactly k and the point is no
//! nucleus), no shorter period, and the point inside the view searched.

use astro_float::{BigFloat, RoundingMode};
use deepfield::locate::search;
use deepfield::num::Decimal;

use super::reference;

const RM: RoundingMode = RoundingMode::ToEven;

/// z and dz/dc along the orbit of c, at `p` bits.
fn orbit(c: &[BigFloat; 2], n: usize, p: usize) -> Vec<([BigFloat; 2], [BigFloat; 2])> {
    let zero = || BigFloat::from_f64(0.0, p);
    let mut out = vec![([zero(), zero()], [zero(), zero()])];
    for _ in 0..n {
        let ([x, y], [dx, dy]) = out.last().expect("started").clone();
        // dz' = 2 z dz + 1, z' = z^2 + c.
        let ndx = x.mul(&dx, p, RM).sub(&y.mul(&dy, p, RM), p, RM).mul(&BigFloat::from_f64(2.0, p), p, RM);
        let ndx = ndx.add(&BigFloat::from_f64(1.0, p), p, RM);
        let ndy = x.mul(&dy, p, RM).add(&y.mul(&dx, p, RM), p, RM).mul(&BigFloat::from_f64(2.0, p), p, RM);
        let nx = x.mul(&x, p, RM).sub(&y.mul(&y, p, RM), p, RM).add(&c[0], p, RM);
        let ny = x.mul(&y, p, RM).mul(&BigFloat::from_f64(2.0, p), p, RM).add(&c[1], p, RM);
        out.push(([nx, ny], [ndx, ndy]));
    }
    out
}

/// log2 |a + sign b| for complex a, b.
fn log2_norm(a: &[BigFloat; 2], b: &[BigFloat; 2], sign: f64, p: usize) -> f64 {
    let s = BigFloat::from_f64(sign, p);
    let re = a[0].add(&b[0].mul(&s, p, RM), p, RM);
    let im = a[1].add(&b[1].mul(&s, p, RM), p, RM);
    let e = |v: &BigFloat| if v.is_zero() { f64::NEG_INFINITY } else { v.exponent().unwrap_or(0) as f64 };
    // Within a bit: enough for the margins below.
    e(&re).max(e(&im))
}

fn find_and_check(name: &str, center: [&str; 2], log10_zoom: f64) {
    let log10_radius = 2f64.log10() - log10_zoom;
    let decimals = [Decimal::parse(center[0]).expect("re"), Decimal::parse(center[1]).expect("im")];
    let (c, radius) = search::disc(&decimals, log10_radius);
    let m = search::misiurewicz_in_view(&c, radius, 8000, 2600).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (k, p) = (m.preperiod as usize, m.period as usize);
    eprintln!("{name}: preperiod {k}, period {p}, {} bits", m.point.bits);
    assert!(k >= 2, "{name}: preperiod {k}");
    let bits = m.point.bits as usize * 2;
    let [re, im] = m.point.to_decimals(0);
    let point = [reference::parse(re.text(), bits), reference::parse(im.text(), bits)];
    let o = orbit(&point, k + p, bits);
    let log2_radius = log10_radius * std::f64::consts::LOG2_10;
    // The printed point is a root of z_(k+p) = z_k and of z_(k+p-1) = -z_(k-1) to far below
    // the view's scale: first-order distances |f| / |f'| under 2^-40 radii.
    for (what, a, b, sign) in [("z_(k+p) = z_k", k + p, k, -1.0), ("z_(k+p-1) = -z_(k-1)", k + p - 1, k - 1, 1.0)] {
        let distance = log2_norm(&o[a].0, &o[b].0, sign, bits) - log2_norm(&o[a].1, &o[b].1, sign, bits);
        assert!(distance < log2_radius - 40.0, "{name}: {what} holds only to 2^{distance} (radius 2^{log2_radius})");
    }
    // Not a lower preperiod (z_(k-1) is no point of the cycle) and no shorter period.
    // (sign 0: log2 |z_k| itself.)
    let scale = log2_norm(&o[k].0, &o[k].0, 0.0, bits).max(0.0);
    assert!(log2_norm(&o[k + p - 1].0, &o[k - 1].0, -1.0, bits) > scale - 20.0, "{name}: preperiod below {k}");
    for q in (1..p).filter(|q| p % q == 0) {
        assert!(log2_norm(&o[k + q].0, &o[k].0, -1.0, bits) > scale - 20.0, "{name}: period {q} divides {p}");
    }
    // Inside the disc searched.
    let d = [0, 1].map(|i| reference::to_f64(&point[i].sub(&reference::parse(center[i], bits), bits, RM)));
    assert!(d[0].hypot(d[1]).log2() <= log2_radius + 1e-9 || d == [0.0, 0.0], "{name}: outside the view");
}

/// At bench-e1086's centre (Kalles Fraktaler's benchmark location) seen at 1e20 and 1e30,
/// where the search once returned a nucleus as "preperiod 1" and then nothing; at deep-e318's
/// centre at 1e40 and floral-fantasy's at 1e30.
#[test]
fn misiurewicz_points_of_deep_views_are_what_their_orbits_say() {
    let centre = |file: &str| {
        let text = std::fs::read_to_string(format!("{}/scenes/{file}", env!("CARGO_MANIFEST_DIR"))).expect("scene");
        super::util::scene(&text).center.map(|d| d.text().to_string())
    };
    let e1086 = centre("bench-e1086.toml");
    let e318 = centre("deep-e318.toml");
    let floral = centre("floral-fantasy.toml");
    find_and_check("bench-e1086 at 1e20", [e1086[0].as_str(), e1086[1].as_str()], 20.0);
    find_and_check("bench-e1086 at 1e30", [e1086[0].as_str(), e1086[1].as_str()], 30.0);
    find_and_check("deep-e318 at 1e40", [e318[0].as_str(), e318[1].as_str()], 40.0);
    find_and_check("floral-fantasy at 1e30", [floral[0].as_str(), floral[1].as_str()], 30.0);
}
