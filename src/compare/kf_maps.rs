//! Kalles Fraktaler's formulas as it writes them: the independent oracle for every family of
//! [`crate::formula::kind::KINDS`].
//!
//! The engines build each family's map by composition (`formula::map`: fold, power, fold,
//! negate). Here each (family, power) is instead written term by term as Kalles Fraktaler
//! 2.15's `formula.xml` states it in its `<reference t="R">` lines (Burning Ship power 3:
//! `Xrn = (Xr2 - 3 Xi2) |Xr| + Cr`, `Xin = (3 Xr2 - Xi2) |Xi| + Ci`), with the same grouping,
//! the same `abs` placements and `Ci - ...` where KF subtracts; its complex-only lines
//! (Mandelbrot powers 4 to 10, `Xn = X^p + C`) by the binomial expansion. Nothing here
//! calls `formula::map`, so `tests/integration/formula_kf.rs` comparing the two checks the
//! composition table against KF, and the ground truth of `deepfield compare` iterates this.
//!
//! One expansion serves two arithmetics ([`Num`]): plain big floats ([`kf_step`]) and big
//! floats carrying two tangents ([`Dual`], forward-mode differentiation), which give the real
//! 2×2 Jacobian of the expansion exactly as written ([`kf_jacobian`]) and let the truth carry
//! d z_n / d(parameter) through every step ([`kf_step_dual`]). A fold's derivative is taken as
//! +1 where its argument is exactly zero (as `formula::map` does); such a point is a kink,
//! where no derivative exists, and the results say when one was met.

use malachite_float::Float;

use crate::formula::{Kind, Phase};

/// The arithmetic an expansion is written in: each operation rounded to `bits`.
pub trait Num: Clone {
    /// The value (the primal part).
    fn value(&self) -> &Float;
    /// self + o.
    fn add(&self, o: &Self, bits: u64) -> Self;
    /// self - o.
    fn sub(&self, o: &Self, bits: u64) -> Self;
    /// self o.
    fn mul(&self, o: &Self, bits: u64) -> Self;
    /// k self, for KF's integer coefficients.
    fn times(&self, k: u32, bits: u64) -> Self;
    /// -self (exact).
    fn neg(&self) -> Self;
    /// The constant `v` (no derivative).
    fn lift(v: Float) -> Self;
}

impl Num for Float {
    fn value(&self) -> &Float {
        self
    }
    fn add(&self, o: &Self, bits: u64) -> Self {
        self.add_prec_ref_ref(o, bits).0
    }
    fn sub(&self, o: &Self, bits: u64) -> Self {
        self.sub_prec_ref_ref(o, bits).0
    }
    fn mul(&self, o: &Self, bits: u64) -> Self {
        self.mul_prec_ref_ref(o, bits).0
    }
    fn times(&self, k: u32, bits: u64) -> Self {
        self.mul_prec_ref_val(Float::from(k), bits).0
    }
    fn neg(&self) -> Self {
        -self.clone()
    }
    fn lift(v: Float) -> Self {
        v
    }
}

/// A big float with its derivatives along two directions (forward-mode differentiation).
#[derive(Debug, Clone, PartialEq)]
pub struct Dual {
    /// The value.
    pub v: Float,
    /// d v / d s_k for the two parameters s_0, s_1.
    pub d: [Float; 2],
}

impl Dual {
    /// A constant (both derivatives zero).
    pub fn constant(v: Float) -> Dual {
        Dual { v, d: [Float::from(0u32), Float::from(0u32)] }
    }

    /// The parameter s_k itself: value `v`, derivative 1 along k and 0 along the other.
    pub fn variable(v: Float, k: usize) -> Dual {
        let mut d = [Float::from(0u32), Float::from(0u32)];
        d[k] = Float::from(1u32);
        Dual { v, d }
    }
}

impl Num for Dual {
    fn value(&self) -> &Float {
        &self.v
    }
    fn add(&self, o: &Self, bits: u64) -> Self {
        let d = |k: usize| self.d[k].add_prec_ref_ref(&o.d[k], bits).0;
        Dual { v: self.v.add_prec_ref_ref(&o.v, bits).0, d: [d(0), d(1)] }
    }
    fn sub(&self, o: &Self, bits: u64) -> Self {
        let d = |k: usize| self.d[k].sub_prec_ref_ref(&o.d[k], bits).0;
        Dual { v: self.v.sub_prec_ref_ref(&o.v, bits).0, d: [d(0), d(1)] }
    }
    fn mul(&self, o: &Self, bits: u64) -> Self {
        // (a b)' = a b' + a' b.
        let d = |k: usize| {
            let x = self.v.mul_prec_ref_ref(&o.d[k], bits).0;
            x.add_prec(self.d[k].mul_prec_ref_ref(&o.v, bits).0, bits).0
        };
        Dual { v: self.v.mul_prec_ref_ref(&o.v, bits).0, d: [d(0), d(1)] }
    }
    fn times(&self, k: u32, bits: u64) -> Self {
        let t = |x: &Float| x.mul_prec_ref_val(Float::from(k), bits).0;
        Dual { v: t(&self.v), d: [t(&self.d[0]), t(&self.d[1])] }
    }
    fn neg(&self) -> Self {
        Dual { v: -self.v.clone(), d: [-self.d[0].clone(), -self.d[1].clone()] }
    }
    fn lift(v: Float) -> Self {
        Dual::constant(v)
    }
}

/// The state of one evaluation: the precision, and whether an `abs` met a zero argument.
struct Ev {
    bits: u64,
    kink: bool,
}

impl Ev {
    /// KF's `abs`: |x|, derivative sign(x) (+1 at 0, which is a kink).
    fn abs<T: Num>(&mut self, x: T) -> T {
        if x.value().is_zero() {
            self.kink = true;
        }
        if *x.value() < 0u32 { x.neg() } else { x }
    }
}

/// Every (kind, power) this module writes: exactly the rows of `KINDS`.
pub fn defined(phase: Phase) -> bool {
    use Kind as K;
    let p = phase.power;
    match phase.kind {
        K::Mandelbrot => (2..=10).contains(&p),
        K::BurningShip | K::Buffalo | K::Celtic | K::Mandelbar => (2..=5).contains(&p),
        K::MandelbarCeltic
        | K::PerpendicularMandelbrot
        | K::PerpendicularBurningShip
        | K::PerpendicularCeltic
        | K::PerpendicularBuffalo => p == 2,
        K::CubicQuasiBurningShip
        | K::CubicPartialBsReal
        | K::CubicPartialBsImag
        | K::CubicFlyingSquirrel
        | K::CubicQuasiPerpendicular => p == 3,
        K::BurningShip4PartialImag
        | K::BurningShip4PartialReal
        | K::BurningShip4PartialRealMbar
        | K::CelticBurningShip4PartialImag
        | K::CelticBurningShip4PartialReal
        | K::CelticBurningShip4PartialRealMbar
        | K::Buffalo4PartialImag
        | K::Celtic4Mbar
        | K::FalseQuasiPerpendicular4
        | K::FalseQuasiHeart4
        | K::CelticFalseQuasiPerpendicular4
        | K::CelticFalseQuasiHeart4
        | K::ImagQuasiPerpendicular4
        | K::RealQuasiPerpendicular4
        | K::RealQuasiHeart4
        | K::CelticImagQuasiPerpendicular4
        | K::CelticRealQuasiPerpendicular4
        | K::CelticRealQuasiHeart4 => p == 4,
        K::BurningShip5Partial
        | K::BurningShip5PartialMbar
        | K::Celtic5Mbar
        | K::QuasiBurningShip5
        | K::QuasiPerpendicular5
        | K::QuasiHeart5 => p == 5,
        K::SimonBrot4 | K::SimonBrot2 => p == 4,
        K::SimonBrot6 => p == 6,
        K::Mothbrot1x1 => p == 2,
        K::Mothbrot1x2 | K::Mothbrot2x1 => p == 3,
        K::Mothbrot1x3 | K::Mothbrot2x2 | K::Mothbrot3x1 => p == 4,
        K::Mothbrot1x4 | K::Mothbrot2x3 | K::Mothbrot3x2 | K::Mothbrot4x1 => p == 5,
        K::Mothbrot1x5 | K::Mothbrot2x4 | K::Mothbrot3x3 | K::Mothbrot4x2 | K::Mothbrot5x1 => p == 6,
        K::RedshiftRider1 | K::RedshiftRider2 | K::RedshiftRider3 => p == 3,
        K::RedshiftRider4 | K::RedshiftRider5 => p == 4,
        K::RedshiftRider6 | K::RedshiftRider7 => p == 5,
        K::RedshiftRider8 | K::RedshiftRider9 => p == 6,
        K::HpdzBuffalo => p == 2,
    }
}

/// Kalles Fraktaler's TheRedshiftRider formulas (types 42 to 50) as their complex reference
/// lines are, `Xn = A * (X^2) + (X^q) + C` (or `- (X^q)`; type 44 `2 * (X^2) - (X^3)`): A
/// times X², as complex numbers, then X^q by the binomial expansion, then C. `a` is None for
/// type 44's literal 2.
fn redshift<T: Num>([x, y]: [&T; 2], a: Option<[f64; 2]>, q: u32, minus: bool, [cr, ci]: [&T; 2], bits: u64) -> [T; 2] {
    let [sr, si] = binomial_power(x, y, 2, bits);
    let [ar2, ai2] = match a {
        None => [sr.times(2, bits), si.times(2, bits)],
        Some([ar, ai]) => {
            let big = |v: f64| T::lift(Float::from_primitive_float_prec(v, 64).0);
            let (ar, ai) = (big(ar), big(ai));
            [ar.mul(&sr, bits).sub(&ai.mul(&si, bits), bits), ar.mul(&si, bits).add(&ai.mul(&sr, bits), bits)]
        }
    };
    let [qr, qi] = binomial_power(x, y, q, bits);
    let (re, im) =
        if minus { (ar2.sub(&qr, bits), ai2.sub(&qi, bits)) } else { (ar2.add(&qr, bits), ai2.add(&qi, bits)) };
    [re.add(cr, bits), im.add(ci, bits)]
}

/// Kalles Fraktaler's Mothbrot a×b (types 54 to 68, and SimonBrot 6th, 40, which is 3×3) as
/// its generated lines are: every product of a term of z^a's binomial expansion and one of
/// (|x| + i|y|)^b's, summed into the real or imaginary part by its power of i. Here the two
/// expansions are summed first and multiplied as complex numbers, which is the same sum
/// regrouped.
fn mothbrot<T: Num>(ev: &mut Ev, [x, y]: [&T; 2], (a, b): (u32, u32), [cr, ci]: [&T; 2]) -> [T; 2] {
    let bits = ev.bits;
    let [zr, zi] = binomial_power(x, y, a, bits);
    let (ax, ay) = (ev.abs(x.clone()), ev.abs(y.clone()));
    let [gr, gi] = binomial_power(&ax, &ay, b, bits);
    let re = zr.mul(&gr, bits).sub(&zi.mul(&gi, bits), bits);
    let im = zr.mul(&gi, bits).add(&zi.mul(&gr, bits), bits);
    [re.add(cr, bits), im.add(ci, bits)]
}

/// The binomial coefficient C(n, k), n <= 10.
fn choose(n: u32, k: u32) -> u32 {
    (0..k).fold(1, |c, i| c * (n - i) / (i + 1))
}

/// z^p by the binomial expansion, KF's `X ^ p` for the Mandelbrot family's complex-only
/// lines: Re = sum over even k of (-1)^(k/2) C(p, k) x^(p-k) y^k, Im over odd k likewise.
fn binomial_power<T: Num>(x: &T, y: &T, p: u32, bits: u64) -> [T; 2] {
    let mut xs = vec![x.clone()];
    let mut ys = vec![y.clone()];
    for k in 1..p as usize {
        xs.push(xs[k - 1].mul(x, bits));
        ys.push(ys[k - 1].mul(y, bits));
    }
    // x^j is xs[j - 1]; the k = 0 and k = p terms have one factor.
    let term = |k: u32| -> T {
        let c = choose(p, k);
        let t = match k {
            0 => xs[p as usize - 1].clone(),
            k if k == p => ys[p as usize - 1].clone(),
            k => xs[(p - k) as usize - 1].mul(&ys[k as usize - 1], bits),
        };
        if c == 1 { t } else { t.times(c, bits) }
    };
    let mut parts: [Option<T>; 2] = [None, None];
    for k in 0..=p {
        let part = &mut parts[(k % 2) as usize];
        let t = term(k);
        // i^k: +, +i, -, -i, ...
        let negative = (k / 2) % 2 == 1;
        *part = Some(match part.take() {
            None if negative => t.neg(),
            None => t,
            Some(s) if negative => s.sub(&t, bits),
            Some(s) => s.add(&t, bits),
        });
    }
    let [re, im] = parts;
    [re.unwrap_or_else(|| x.times(0, bits)), im.unwrap_or_else(|| x.times(0, bits))]
}

/// One step of `phase` as KF's reference line writes it, c added (or subtracted from, as KF
/// writes `Ci - ...`); None for a (kind, power) KF does not define.
fn expand<T: Num>(ev: &mut Ev, phase: Phase, [x, y]: [&T; 2], [cr, ci]: [&T; 2]) -> Option<[T; 2]> {
    use Kind as K;
    let b = ev.bits;
    let xr2 = x.mul(x, b);
    let xi2 = y.mul(y, b);
    let m = |a: &T, c: &T| a.mul(c, b);
    let add = |a: &T, c: &T| a.add(c, b);
    let sub = |a: &T, c: &T| a.sub(c, b);
    let k = |n: u32, a: &T| a.times(n, b);
    // Power 2: Xr2 - Xi2, and KF's products of Xr and Xi.
    let d2 = || sub(&xr2, &xi2);
    // Power 3: Xr2 - 3 Xi2 and 3 Xr2 - Xi2.
    let a3 = || sub(&xr2, &k(3, &xi2));
    let b3 = || sub(&k(3, &xr2), &xi2);
    // Power 4: Xr2 Xr2 + Xi2 Xi2 - 6 Xr2 Xi2, and 4 f g (Xr2 - Xi2) for factors f, g.
    let r4 = || sub(&add(&m(&xr2, &xr2), &m(&xi2, &xi2)), &m(&k(6, &xr2), &xi2));
    let i4 = |f: &T, g: &T| m(&m(&k(4, f), g), &d2());
    // Power 5: Xr2 Xr2 - 10 Xr2 Xi2 + 5 Xi2 Xi2 and 5 Xr2 Xr2 - 10 Xr2 Xi2 + Xi2 Xi2.
    let q5 = || add(&sub(&m(&xr2, &xr2), &m(&k(10, &xr2), &xi2)), &m(&k(5, &xi2), &xi2));
    let s5 = || add(&sub(&m(&k(5, &xr2), &xr2), &m(&k(10, &xr2), &xi2)), &m(&xi2, &xi2));
    // `+ C` and `C - ...`.
    let plus = |a: T, c: &T| a.add(c, b);
    let from = |c: &T, a: T| c.sub(&a, b);
    let p = phase.power;
    Some(match (phase.kind, p) {
        // Type 0. Xrn = Xr2 - Xi2 + Cr; Xin = sqr(Xr + Xi) - Xr2 - Xi2 + Ci.
        (K::Mandelbrot, 2) => {
            let s = add(x, y);
            [plus(d2(), cr), plus(sub(&sub(&m(&s, &s), &xr2), &xi2), ci)]
        }
        (K::Mandelbrot, 3) => [plus(m(x, &a3()), cr), plus(m(&b3(), y), ci)],
        (K::Mandelbrot, 4..=10) => {
            let [re, im] = binomial_power(x, y, p, b);
            [plus(re, cr), plus(im, ci)]
        }
        // Type 1.
        (K::BurningShip, 2) => [plus(d2(), cr), plus(ev.abs(m(&k(2, x), y)), ci)],
        (K::BurningShip, 3) => [plus(m(&a3(), &ev.abs(x.clone())), cr), plus(m(&b3(), &ev.abs(y.clone())), ci)],
        (K::BurningShip, 4) => [plus(r4(), cr), plus(m(&k(4, &ev.abs(m(x, y))), &d2()), ci)],
        (K::BurningShip, 5) => [plus(m(&ev.abs(x.clone()), &q5()), cr), plus(m(&ev.abs(y.clone()), &s5()), ci)],
        // Type 2.
        (K::Buffalo, 2) => [plus(ev.abs(d2()), cr), plus(k(2, &ev.abs(m(x, y))), ci)],
        (K::Buffalo, 3) => [plus(ev.abs(m(&a3(), x)), cr), plus(ev.abs(m(&b3(), y)), ci)],
        (K::Buffalo, 4) => [plus(ev.abs(r4()), cr), plus(ev.abs(i4(x, y)), ci)],
        (K::Buffalo, 5) => [plus(ev.abs(m(x, &q5())), cr), plus(ev.abs(m(y, &s5())), ci)],
        // Type 3.
        (K::Celtic, 2) => [plus(ev.abs(d2()), cr), plus(k(2, &m(x, y)), ci)],
        (K::Celtic, 3) => [plus(ev.abs(m(&a3(), x)), cr), plus(m(&b3(), y), ci)],
        (K::Celtic, 4) => [plus(ev.abs(r4()), cr), plus(i4(x, y), ci)],
        (K::Celtic, 5) => [plus(ev.abs(m(x, &q5())), cr), plus(m(y, &s5()), ci)],
        // Type 4: power 3 negates the real part, the others the imaginary part.
        (K::Mandelbar, 2) => [plus(d2(), cr), from(ci, k(2, &m(x, y)))],
        (K::Mandelbar, 3) => [from(cr, m(&a3(), x)), plus(m(&b3(), y), ci)],
        (K::Mandelbar, 4) => [plus(r4(), cr), from(ci, i4(x, y))],
        (K::Mandelbar, 5) => [plus(m(x, &q5()), cr), from(ci, m(y, &s5()))],
        // Types 5 to 9.
        (K::MandelbarCeltic, 2) => [plus(ev.abs(d2()), cr), from(ci, k(2, &m(x, y)))],
        (K::PerpendicularMandelbrot, 2) => [plus(d2(), cr), from(ci, k(2, &m(&ev.abs(x.clone()), y)))],
        (K::PerpendicularBurningShip, 2) => [plus(d2(), cr), from(ci, k(2, &m(x, &ev.abs(y.clone()))))],
        (K::PerpendicularCeltic, 2) => [plus(ev.abs(d2()), cr), from(ci, k(2, &m(&ev.abs(x.clone()), y)))],
        (K::PerpendicularBuffalo, 2) => [plus(ev.abs(d2()), cr), from(ci, k(2, &m(x, &ev.abs(y.clone()))))],
        // Types 10 to 13.
        (K::CubicQuasiBurningShip, 3) => [plus(m(&a3(), &ev.abs(x.clone())), cr), from(ci, ev.abs(m(&b3(), y)))],
        (K::CubicPartialBsReal, 3) => [plus(m(&a3(), &ev.abs(x.clone())), cr), plus(m(&b3(), y), ci)],
        (K::CubicPartialBsImag, 3) => [plus(m(&a3(), x), cr), plus(m(&b3(), &ev.abs(y.clone())), ci)],
        (K::CubicFlyingSquirrel, 3) => [plus(m(&a3(), x), cr), plus(ev.abs(m(&b3(), y)), ci)],
        // Types 15 to 22.
        (K::BurningShip4PartialImag, 4) => [plus(r4(), cr), plus(i4(x, &ev.abs(y.clone())), ci)],
        (K::BurningShip4PartialReal, 4) => [plus(r4(), cr), plus(i4(&ev.abs(x.clone()), y), ci)],
        (K::BurningShip4PartialRealMbar, 4) => [plus(r4(), cr), from(ci, i4(&ev.abs(x.clone()), y))],
        (K::CelticBurningShip4PartialImag, 4) => [plus(ev.abs(r4()), cr), plus(i4(x, &ev.abs(y.clone())), ci)],
        (K::CelticBurningShip4PartialReal, 4) => [plus(ev.abs(r4()), cr), plus(i4(&ev.abs(x.clone()), y), ci)],
        (K::CelticBurningShip4PartialRealMbar, 4) => [plus(ev.abs(r4()), cr), from(ci, i4(&ev.abs(x.clone()), y))],
        (K::Buffalo4PartialImag, 4) => [plus(r4(), cr), plus(ev.abs(i4(x, y)), ci)],
        (K::Celtic4Mbar, 4) => [plus(ev.abs(r4()), cr), from(ci, i4(x, y))],
        // Types 27 to 30.
        (K::BurningShip5Partial, 5) => [plus(m(&ev.abs(x.clone()), &q5()), cr), plus(m(y, &s5()), ci)],
        (K::BurningShip5PartialMbar, 5) => [plus(m(&ev.abs(x.clone()), &q5()), cr), from(ci, m(y, &s5()))],
        (K::Celtic5Mbar, 5) => [plus(ev.abs(m(x, &q5())), cr), from(ci, m(y, &s5()))],
        (K::QuasiBurningShip5, 5) => [plus(m(&ev.abs(x.clone()), &q5()), cr), from(ci, ev.abs(m(y, &s5())))],
        // Type 14. Xrn = (Xr2 - Xi2 * 3) * abs(Xr) + Cr; Xin = Ci - abs(Xr2 * 3 - Xi2) * Xi.
        (K::CubicQuasiPerpendicular, 3) => {
            [plus(m(&sub(&xr2, &k(3, &xi2)), &ev.abs(x.clone())), cr), from(ci, m(&ev.abs(sub(&k(3, &xr2), &xi2)), y))]
        }
        // Types 23 to 26: 4 * Xr * Xi * abs(Xr2 - Xi2), subtracted from Ci, added, or times -4.
        (K::FalseQuasiPerpendicular4, 4) => [plus(r4(), cr), from(ci, m(&m(&k(4, x), y), &ev.abs(d2())))],
        (K::FalseQuasiHeart4, 4) => [plus(r4(), cr), plus(m(&m(&k(4, x), y), &ev.abs(d2())), ci)],
        (K::CelticFalseQuasiPerpendicular4, 4) => {
            [plus(ev.abs(r4()), cr), plus(m(&m(&k(4, x).neg(), y), &ev.abs(d2())), ci)]
        }
        (K::CelticFalseQuasiHeart4, 4) => [plus(ev.abs(r4()), cr), plus(m(&m(&k(4, x), y), &ev.abs(d2())), ci)],
        // Types 31 and 32. Xrn = abs(Xr) * (Xr2 Xr2 - 10 Xr2 Xi2 + 5 Xi2 Xi2) + Cr;
        // Xin = Ci - Xi * abs(5 Xr2 Xr2 - 10 Xr2 Xi2 + Xi2 Xi2), or that term + Ci.
        (K::QuasiPerpendicular5, 5) => [plus(m(&ev.abs(x.clone()), &q5()), cr), from(ci, m(y, &ev.abs(s5())))],
        (K::QuasiHeart5, 5) => [plus(m(&ev.abs(x.clone()), &q5()), cr), plus(m(y, &ev.abs(s5())), ci)],
        // Types 34 to 39: 4 * Xr * abs(Xi * Xr2 - Xi * Xi2) or 4 * Xi * abs(Xr * Xr2 - Xr * Xi2),
        // with Xrn = Xr2 Xr2 + Xi2 Xi2 - 6 Xr2 Xi2 + Cr or its abs (Celtic).
        (K::ImagQuasiPerpendicular4, 4) => {
            [plus(r4(), cr), plus(m(&k(4, x), &ev.abs(sub(&m(y, &xr2), &m(y, &xi2)))), ci)]
        }
        (K::RealQuasiPerpendicular4, 4) => {
            [plus(r4(), cr), from(ci, m(&k(4, y), &ev.abs(sub(&m(x, &xr2), &m(x, &xi2)))))]
        }
        (K::RealQuasiHeart4, 4) => [plus(r4(), cr), plus(m(&k(4, y), &ev.abs(sub(&m(x, &xr2), &m(x, &xi2)))), ci)],
        (K::CelticImagQuasiPerpendicular4, 4) => {
            [plus(ev.abs(r4()), cr), plus(m(&k(4, x), &ev.abs(sub(&m(y, &xr2), &m(y, &xi2)))), ci)]
        }
        (K::CelticRealQuasiPerpendicular4, 4) => {
            [plus(ev.abs(r4()), cr), from(ci, m(&k(4, y), &ev.abs(sub(&m(x, &xr2), &m(x, &xi2)))))]
        }
        (K::CelticRealQuasiHeart4, 4) => {
            [plus(ev.abs(r4()), cr), plus(m(&k(4, y), &ev.abs(sub(&m(x, &xr2), &m(x, &xi2)))), ci)]
        }
        // Type 33. Xrn = Xi2 abs(Xi2) - 4 Xi abs(Xr Xi) Xr - Xr2 abs(Xi2) - Xi2 abs(Xr2)
        // + Xr2 abs(Xr2) + Cr; Xin = Ci - 2 Xr Xi abs(Xi2) - 2 Xi2 abs(Xr Xi)
        // + 2 Xr2 abs(Xr Xi) + 2 Xr Xi abs(Xr2).
        (K::SimonBrot4, 4) => {
            let (a_r2, a_i2, a_ri) = (ev.abs(xr2.clone()), ev.abs(xi2.clone()), ev.abs(m(x, y)));
            let re = add(
                &sub(&sub(&sub(&m(&xi2, &a_i2), &m(&m(&k(4, y), &a_ri), x)), &m(&xr2, &a_i2)), &m(&xi2, &a_r2)),
                &m(&xr2, &a_r2),
            );
            let im = add(
                &add(&sub(&sub(ci, &m(&m(&k(2, x), y), &a_i2)), &m(&k(2, &xi2), &a_ri)), &m(&k(2, &xr2), &a_ri)),
                &m(&m(&k(2, x), y), &a_r2),
            );
            [plus(re, cr), im]
        }
        // Type 51. Xrn = (Xr2 - Xi2) abs(Xr2 - Xi2) - 2 Xr Xi abs(2 Xr Xi) + Cr;
        // Xin = (Xr2 - Xi2) abs(2 Xr Xi) + 2 Xr Xi abs(Xr2 - Xi2) + Ci.
        (K::SimonBrot2, 4) => {
            let two_xy = m(&k(2, x), y);
            let (a_d, a_t) = (ev.abs(d2()), ev.abs(two_xy.clone()));
            [plus(sub(&m(&d2(), &a_d), &m(&two_xy, &a_t)), cr), plus(add(&m(&d2(), &a_t), &m(&two_xy, &a_d)), ci)]
        }
        // Types 54 to 68, Mothbrot a×b of power a + b, and type 40, SimonBrot 6th = 3×3.
        (K::SimonBrot6, 6) => mothbrot(ev, [x, y], (3, 3), [cr, ci]),
        (K::Mothbrot1x1, 2) => mothbrot(ev, [x, y], (1, 1), [cr, ci]),
        (K::Mothbrot1x2, 3) => mothbrot(ev, [x, y], (1, 2), [cr, ci]),
        (K::Mothbrot2x1, 3) => mothbrot(ev, [x, y], (2, 1), [cr, ci]),
        (K::Mothbrot1x3, 4) => mothbrot(ev, [x, y], (1, 3), [cr, ci]),
        (K::Mothbrot2x2, 4) => mothbrot(ev, [x, y], (2, 2), [cr, ci]),
        (K::Mothbrot3x1, 4) => mothbrot(ev, [x, y], (3, 1), [cr, ci]),
        (K::Mothbrot1x4, 5) => mothbrot(ev, [x, y], (1, 4), [cr, ci]),
        (K::Mothbrot2x3, 5) => mothbrot(ev, [x, y], (2, 3), [cr, ci]),
        (K::Mothbrot3x2, 5) => mothbrot(ev, [x, y], (3, 2), [cr, ci]),
        (K::Mothbrot4x1, 5) => mothbrot(ev, [x, y], (4, 1), [cr, ci]),
        (K::Mothbrot1x5, 6) => mothbrot(ev, [x, y], (1, 5), [cr, ci]),
        (K::Mothbrot2x4, 6) => mothbrot(ev, [x, y], (2, 4), [cr, ci]),
        (K::Mothbrot3x3, 6) => mothbrot(ev, [x, y], (3, 3), [cr, ci]),
        (K::Mothbrot4x2, 6) => mothbrot(ev, [x, y], (4, 2), [cr, ci]),
        (K::Mothbrot5x1, 6) => mothbrot(ev, [x, y], (5, 1), [cr, ci]),
        // Type 41. Xrn = (Xr2 - Xi2) - abs(Xr) + Cr; Xin = abs(Xr * Xi) * 2 - abs(Xi) + Ci.
        (K::HpdzBuffalo, 2) => {
            let re = sub(&d2(), &ev.abs(x.clone()));
            let im = sub(&k(2, &ev.abs(m(x, y))), &ev.abs(y.clone()));
            [plus(re, cr), plus(im, ci)]
        }
        // Types 42 to 50.
        (K::RedshiftRider1, 3) => redshift([x, y], Some(phase.a.get()), 3, false, [cr, ci], b),
        (K::RedshiftRider2, 3) => redshift([x, y], Some(phase.a.get()), 3, true, [cr, ci], b),
        (K::RedshiftRider3, 3) => redshift([x, y], None, 3, true, [cr, ci], b),
        (K::RedshiftRider4, 4) => redshift([x, y], Some(phase.a.get()), 4, false, [cr, ci], b),
        (K::RedshiftRider5, 4) => redshift([x, y], Some(phase.a.get()), 4, true, [cr, ci], b),
        (K::RedshiftRider6, 5) => redshift([x, y], Some(phase.a.get()), 5, false, [cr, ci], b),
        (K::RedshiftRider7, 5) => redshift([x, y], Some(phase.a.get()), 5, true, [cr, ci], b),
        (K::RedshiftRider8, 6) => redshift([x, y], Some(phase.a.get()), 6, false, [cr, ci], b),
        (K::RedshiftRider9, 6) => redshift([x, y], Some(phase.a.get()), 6, true, [cr, ci], b),
        _ => return None,
    })
}

/// One step z -> f(z) + c of `phase` in big floats at `bits`, as Kalles Fraktaler writes it;
/// None for a (kind, power) it does not define (none of `KINDS`' rows).
pub fn kf_step(phase: Phase, z: [&Float; 2], c: [&Float; 2], bits: u64) -> Option<[Float; 2]> {
    expand(&mut Ev { bits, kink: false }, phase, z, c)
}

/// A step in dual numbers: the new z with its derivatives, and whether some `abs` met a
/// zero argument (a kink, where the derivative taken is a one-sided one).
#[derive(Debug, Clone)]
pub struct DualStep {
    /// f(z) + c with derivatives.
    pub z: [Dual; 2],
    /// Some fold's argument was exactly zero.
    pub kink: bool,
}

/// [`kf_step`] in dual numbers: the step and its derivatives along the duals' two
/// directions (the truth's d z_n / d c, or d z_n / d z_0 for Julia sets).
pub fn kf_step_dual(phase: Phase, z: &[Dual; 2], c: &[Dual; 2], bits: u64) -> Option<DualStep> {
    let mut ev = Ev { bits, kink: false };
    let z = expand(&mut ev, phase, [&z[0], &z[1]], [&c[0], &c[1]])?;
    Some(DualStep { z, kink: ev.kink })
}

/// The real Jacobian of KF's expansion at z, rows first
/// (`[[d re/dx, d re/dy], [d im/dx, d im/dy]]`), and whether z is at a kink.
#[derive(Debug, Clone)]
pub struct KfJacobian {
    /// The matrix.
    pub m: [[Float; 2]; 2],
    /// Some fold's argument was exactly zero: the map has no derivative there and `m` is
    /// one of its one-sided ones.
    pub kink: bool,
}

/// The Jacobian of `phase`'s step at z (c does not enter it), differentiated term by term.
pub fn kf_jacobian(phase: Phase, z: [&Float; 2], bits: u64) -> Option<KfJacobian> {
    let z = [Dual::variable(z[0].clone(), 0), Dual::variable(z[1].clone(), 1)];
    let c = [Dual::constant(Float::from(0u32)), Dual::constant(Float::from(0u32))];
    let s = kf_step_dual(phase, &z, &c, bits)?;
    let [re, im] = s.z;
    Some(KfJacobian { m: [re.d, im.d], kink: s.kink })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::kind::KINDS;

    fn f(x: f64) -> Float {
        Float::from_primitive_float_prec(x, 64).0
    }

    fn to_f64(x: &Float) -> f64 {
        crate::num::bigfloat::to_floatexp(x).to_f64()
    }

    #[test]
    fn every_row_of_kinds_is_defined_and_nothing_else() {
        for k in KINDS {
            for p in 2..=10 {
                let phase = Phase::new(k.kind, p);
                let inside = (k.min_power..=k.max_power).contains(&p);
                assert_eq!(defined(phase), inside, "{phase}");
                let one = f(0.5);
                assert_eq!(kf_step(phase, [&one, &one], [&one, &one], 100).is_some(), inside, "{phase}");
            }
        }
    }

    /// z² + c as `truth::orbit` steps it: x² - y² + cx, 2 x y + cy. At 300 bits every
    /// operation on these f64 inputs is exact, so the two must be equal.
    #[test]
    fn mandelbrot_power_2_is_the_truths_step() {
        let bits = 300;
        for (z, c) in [([0.3, -0.7], [-0.75, 0.1]), ([-1.25, 0.0], [0.0, 2.0]), ([0.0, -3.5], [1e-3, -1e-5])] {
            let (x, y, cx, cy) = (f(z[0]), f(z[1]), f(c[0]), f(c[1]));
            let got = kf_step(Phase::QUADRATIC, [&x, &y], [&cx, &cy], bits).unwrap();
            let xx = x.square_prec_ref(bits).0;
            let yy = y.square_prec_ref(bits).0;
            let re = xx.sub_prec(yy, bits).0.add_prec_ref_ref(&cx, bits).0;
            let im = (x.mul_prec_ref_ref(&y, bits).0 << 1u32).add_prec_ref_ref(&cy, bits).0;
            assert_eq!(got, [re, im], "{z:?} {c:?}");
        }
    }

    /// KF's Mandelbar of power 3, `Xrn = Cr - (Xr2 - 3 Xi2) Xr`, `Xin = (3 Xr2 - Xi2) Xi + Ci`,
    /// by hand at z = 1 + 2i, c = 0: z³ = -11 - 2i, so the step is 11 - 2i (the real part
    /// negated, where conj(z)³ would give -11 + 2i).
    #[test]
    fn mandelbar_power_3_negates_the_real_part() {
        let phase = Phase::new(Kind::Mandelbar, 3);
        let (one, two, zero) = (f(1.0), f(2.0), f(0.0));
        let [re, im] = kf_step(phase, [&one, &two], [&zero, &zero], 64).unwrap();
        assert_eq!((to_f64(&re), to_f64(&im)), (11.0, -2.0));
        // Power 2 conjugates: (1 - 2i)² = -3 - 4i.
        let phase = Phase::new(Kind::Mandelbar, 2);
        let [re, im] = kf_step(phase, [&one, &two], [&zero, &zero], 64).unwrap();
        assert_eq!((to_f64(&re), to_f64(&im)), (-3.0, -4.0));
    }

    /// Burning Ship power 3 by hand at z = -1 - 2i: (|x| + i|y|)³ = (1 + 2i)³ = -11 - 2i.
    #[test]
    fn burning_ship_power_3_folds_both_parts() {
        let phase = Phase::new(Kind::BurningShip, 3);
        let (x, y, c) = (f(-1.0), f(-2.0), f(0.5));
        let [re, im] = kf_step(phase, [&x, &y], [&c, &c], 64).unwrap();
        assert_eq!((to_f64(&re), to_f64(&im)), (-10.5, -1.5));
    }

    /// The binomial expansion of the Mandelbrot family's high powers against repeated
    /// complex multiplication, exactly (every operation is exact at 2000 bits).
    #[test]
    fn binomial_powers_are_powers() {
        let (x, y) = (f(0.625), f(-1.375));
        for p in 2..=10 {
            let [re, im] = binomial_power(&x, &y, p, 2000);
            let (mut a, mut b) = (f(1.0), f(0.0));
            for _ in 0..p {
                let na = a.mul_prec_ref_ref(&x, 2000).0.sub_prec(b.mul_prec_ref_ref(&y, 2000).0, 2000).0;
                b = a.mul_prec_ref_ref(&y, 2000).0.add_prec(b.mul_prec_ref_ref(&x, 2000).0, 2000).0;
                a = na;
            }
            assert_eq!((re, im), (a, b), "power {p}");
        }
    }

    /// The dual numbers' Jacobian against central differences of the step.
    #[test]
    fn jacobian_matches_finite_differences() {
        let bits = 200;
        let h = 1e-20;
        for k in KINDS {
            for p in k.min_power..=k.max_power {
                let phase = Phase::new(k.kind, p);
                let z = [0.37, -0.81];
                let j = kf_jacobian(phase, [&f(z[0]), &f(z[1])], bits).unwrap();
                assert!(!j.kink);
                let zero = f(0.0);
                let at = |dx: f64, dy: f64| {
                    let x = f(z[0]).add_prec(f(dx), bits).0;
                    let y = f(z[1]).add_prec(f(dy), bits).0;
                    kf_step(phase, [&x, &y], [&zero, &zero], bits).unwrap()
                };
                for (col, (dx, dy)) in [(h, 0.0), (0.0, h)].into_iter().enumerate() {
                    let (a, b) = (at(dx, dy), at(-dx, -dy));
                    for row in 0..2 {
                        let fd = to_f64(&a[row].sub_prec_ref_ref(&b[row], bits).0) / (2.0 * h);
                        let want = to_f64(&j.m[row][col]);
                        assert!((fd - want).abs() <= 1e-12 * (1.0 + want.abs()), "{phase} [{row}][{col}] {fd} {want}");
                    }
                }
            }
        }
    }

    #[test]
    fn a_fold_at_zero_is_a_kink() {
        let phase = Phase::new(Kind::BurningShip, 2);
        let j = kf_jacobian(phase, [&f(0.0), &f(0.5)], 100).unwrap();
        assert!(j.kink);
        let j = kf_jacobian(Phase::QUADRATIC, [&f(0.0), &f(0.5)], 100).unwrap();
        assert!(!j.kink);
    }
}
