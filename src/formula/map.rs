//! The maps of every formula family, composed of four steps that Kalles Fraktaler's formula
//! definitions are expansions of: fold the components of z (absolute values of x, y or
//! both), raise to an integer power p, fold the components of the result, and negate one
//! component. Then c is added. A fold of the result's imaginary part may also give it back
//! the sign of x, y or xy of z ([`IM_BY_X`], [`IM_BY_Y`]): Kalles Fraktaler's "quasi"
//! families write such a part y |g(x, y)| where Im w = y g(x, y), which is sgn(y) |Im w|.
//!
//! A family is one choice of those four ([`Ops`], const parameters), so every kernel that
//! is generic over [`Map`] is compiled per family into straight-line code: no opcode is
//! read in the hot loop. From that one definition come the four things the engines need:
//! the step in f64 ([`Map::apply`]), in big floats ([`Map::apply_big`]), the perturbed
//! step on a delta against a reference ([`Map::delta`], exact through the folds by
//! [`diffabs`]), and the real 2×2 Jacobian ([`Map::jacobian`]) for derivatives and
//! bilinear approximation.

use super::phase::Phase;
use crate::num::bigcomplex::BigC;
use crate::num::real::{Real, cadd, cmul};

/// No component folded.
pub const FOLD_NONE: u8 = 0;
/// The real part folded: x -> |x|.
pub const FOLD_RE: u8 = 1;
/// The imaginary part folded: y -> |y|.
pub const FOLD_IM: u8 = 2;
/// Both parts folded.
pub const FOLD_BOTH: u8 = 3;

/// With [`FOLD_IM`] after the power: the folded imaginary part times the sign of x (of z,
/// before any fold), sgn(x) |Im w|.
pub const IM_BY_X: u8 = 4;
/// With [`FOLD_IM`] after the power: the folded imaginary part times the sign of y,
/// sgn(y) |Im w| (with [`IM_BY_X`] too: times the sign of xy).
pub const IM_BY_Y: u8 = 8;

/// No component negated.
pub const SIGN_NONE: u8 = 0;
/// The imaginary part negated (the complex conjugate).
pub const SIGN_IM: u8 = 1;
/// The real part negated.
pub const SIGN_RE: u8 = 2;

/// The largest power a family may have.
pub const MAX_POWER: u32 = 10;

/// A 2×2 real matrix, rows first: `[[d re/dx, d re/dy], [d im/dx, d im/dy]]`.
pub type Mat2 = [[f64; 2]; 2];

/// What the f64 map needs of its numbers: f64 itself, or `[f64; L]`, L samples at once
/// (loops over lanes that the compiler turns into vector instructions). Both run the same
/// IEEE operations in the same order, so every lane gives the bits of the scalar map.
pub trait Num: Copy {
    /// The value `x` in every lane.
    fn splat(x: f64) -> Self;
    /// self + o.
    fn add(self, o: Self) -> Self;
    /// self - o.
    fn sub(self, o: Self) -> Self;
    /// self * o.
    fn mul(self, o: Self) -> Self;
    /// self * a + b, rounded once.
    fn mul_add(self, a: Self, b: Self) -> Self;
    /// |self|.
    fn abs(self) -> Self;
    /// -self.
    fn neg(self) -> Self;
    /// +1 where self >= 0 (or is NaN), -1 where self < 0.
    fn sgn(self) -> Self;
    /// [`diffabs`] of the reference part `self` and the delta `d`, lane by lane.
    fn diffabs(self, d: Self) -> Self;
    /// [`signed_diffabs`] of the reference part `self`, the delta `d` and the signs (±1)
    /// `s` and `s_new`, lane by lane.
    fn signed_diffabs(self, d: Self, s: Self, s_new: Self) -> Self;
    /// `a` where self is zero (of either sign), `b` elsewhere, lane by lane.
    fn if_zero(self, a: Self, b: Self) -> Self;
}

impl Num for f64 {
    #[inline(always)]
    fn splat(x: f64) -> Self {
        x
    }
    #[inline(always)]
    fn add(self, o: Self) -> Self {
        self + o
    }
    #[inline(always)]
    fn sub(self, o: Self) -> Self {
        self - o
    }
    #[inline(always)]
    fn mul(self, o: Self) -> Self {
        self * o
    }
    #[inline(always)]
    fn mul_add(self, a: Self, b: Self) -> Self {
        f64::mul_add(self, a, b)
    }
    #[inline(always)]
    fn abs(self) -> Self {
        f64::abs(self)
    }
    #[inline(always)]
    fn neg(self) -> Self {
        -self
    }
    #[inline(always)]
    fn sgn(self) -> Self {
        if self < 0.0 { -1.0 } else { 1.0 }
    }
    #[inline(always)]
    fn diffabs(self, d: Self) -> Self {
        diffabs(self, d)
    }
    #[inline(always)]
    fn signed_diffabs(self, d: Self, s: Self, s_new: Self) -> Self {
        signed_diffabs(self, d, s, s_new)
    }
    #[inline(always)]
    fn if_zero(self, a: Self, b: Self) -> Self {
        if self == 0.0 { a } else { b }
    }
}

impl<const L: usize> Num for [f64; L] {
    // Plain loops over the lanes (not `array::from_fn`, which the compiler may leave as a
    // call outside the caller's vector target features).
    #[inline(always)]
    fn splat(x: f64) -> Self {
        [x; L]
    }
    #[inline(always)]
    fn add(mut self, o: Self) -> Self {
        for k in 0..L {
            self[k] += o[k];
        }
        self
    }
    #[inline(always)]
    fn sub(mut self, o: Self) -> Self {
        for k in 0..L {
            self[k] -= o[k];
        }
        self
    }
    #[inline(always)]
    fn mul(mut self, o: Self) -> Self {
        for k in 0..L {
            self[k] *= o[k];
        }
        self
    }
    #[inline(always)]
    fn mul_add(mut self, a: Self, b: Self) -> Self {
        for k in 0..L {
            self[k] = f64::mul_add(self[k], a[k], b[k]);
        }
        self
    }
    #[inline(always)]
    fn abs(mut self) -> Self {
        for x in &mut self {
            *x = f64::abs(*x);
        }
        self
    }
    #[inline(always)]
    fn neg(mut self) -> Self {
        for x in &mut self {
            *x = -*x;
        }
        self
    }
    #[inline(always)]
    fn sgn(mut self) -> Self {
        for x in &mut self {
            *x = if *x < 0.0 { -1.0 } else { 1.0 };
        }
        self
    }
    #[inline(always)]
    fn diffabs(self, d: Self) -> Self {
        // The scalar `diffabs`'s four outcomes as selects (the lanes stay branch-free):
        // with x >= 0, d where x + d >= 0 else -(d + 2x); with x < 0, d + 2x where x + d > 0
        // else -d.
        let mut r = d;
        for k in 0..L {
            let (x, d) = (self[k], d[k]);
            let s = x + d;
            let e = d + 2.0 * x;
            let pos = x >= 0.0;
            let kept = if pos { s >= 0.0 } else { s > 0.0 };
            let a = if pos { d } else { e };
            let b = if pos { e } else { d };
            r[k] = if kept { a } else { -b };
        }
        r
    }
    #[inline(always)]
    fn signed_diffabs(self, d: Self, s: Self, s_new: Self) -> Self {
        // `signed_diffabs` as selects: the same operations, both outcomes computed.
        let kept = self.diffabs(d);
        let mut r = d;
        for k in 0..L {
            let (u, d) = (self[k], d[k]);
            let t = u + d;
            let m = (if t < 0.0 { -t } else { t }) + f64::abs(u);
            r[k] = if s[k] == s_new[k] { kept[k] * s[k] } else { m * s_new[k] };
        }
        r
    }
    #[inline(always)]
    fn if_zero(mut self, a: Self, b: Self) -> Self {
        for k in 0..L {
            self[k] = if self[k] == 0.0 { a[k] } else { b[k] };
        }
        self
    }
}

/// One map z -> f(z) of a family (c is added by the caller), in every arithmetic the
/// engines use. A value of the type is the map: zero-sized for the families that are fixed
/// by their type (the kernels then hold nothing but the family's code), the coefficient for
/// those that take one ([`super::sum`]).
pub trait Map: Copy + Send + Sync + 'static {
    /// The power p (the degree that smooth iteration and the escape rate use).
    const POWER: u32;
    /// True when f is complex-analytic (no fold, no negation of one part alone): its
    /// Jacobian is then a complex number.
    const CONFORMAL: bool;
    /// The map of `phase` (whose family and power are this type's).
    fn of(phase: &Phase) -> Self;
    /// f(z) in f64.
    #[inline(always)]
    fn apply(&self, z: [f64; 2]) -> [f64; 2] {
        self.apply_n(z)
    }
    /// f(z) for one sample (f64) or several in lanes, the same operations in each.
    fn apply_n<N: Num>(&self, z: [N; 2]) -> [N; 2];
    /// f(z) in big floats at `z.bits`.
    fn apply_big(&self, z: &BigC) -> BigC;
    /// f(Z + d) - f(Z) for a reference value Z (f64) and a delta d, without cancellation:
    /// the power by the binomial expansion in d, the folds by [`diffabs`].
    fn delta<R: Real>(&self, z: [f64; 2], d: [R; 2]) -> [R; 2];
    /// [`Map::delta`] in f64 for one sample or several in lanes (each lane its own Z):
    /// the same operations in the same order, so each lane has the bits of
    /// `delta::<f64>`.
    fn delta_n<N: Num>(&self, z: [N; 2], d: [N; 2]) -> [N; 2];
    /// The Jacobian of f at z (a fold's derivative taken as +1 at 0).
    #[inline(always)]
    fn jacobian(&self, z: [f64; 2]) -> Mat2 {
        self.jacobian_n(z)
    }
    /// The Jacobian for one sample or several in lanes.
    fn jacobian_n<N: Num>(&self, z: [N; 2]) -> [[N; 2]; 2];
}

/// The family composed of a fold `IN`, the power `P`, a fold `OUT` and a negation `SIGN`.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Ops<const IN: u8, const P: u32, const OUT: u8, const SIGN: u8>;

/// z with the parts that `fold` (a set of [`FOLD_RE`], [`FOLD_IM`]) names replaced by their
/// magnitudes, in big floats.
pub fn fold_big(fold: u8, z: BigC) -> BigC {
    z.fold_parts(fold & FOLD_RE != 0, fold & FOLD_IM != 0)
}

/// |X + d| - |X| without cancellation (Claude Heiland-Allen's `diffabs`): exact in the sense
/// that only the sign of X + d is decided, and the result is d, -d, or d + 2X up to sign.
#[inline(always)]
pub fn diffabs<R: Real>(x: f64, d: R) -> R {
    let s = R::from_f64(x) + d;
    if x >= 0.0 {
        if s >= R::ZERO { d } else { -(d + R::from_f64(2.0 * x)) }
    } else if s > R::ZERO {
        d + R::from_f64(2.0 * x)
    } else {
        -d
    }
}

/// s' |U + d| - s |U| for a part U folded and then given a sign, s = ±1 at the reference
/// and s' = ±1 at the sample ([`IM_BY_X`], [`IM_BY_Y`]), without cancellation: s times
/// [`diffabs`] where the sign stays, else s' (|U + d| + |U|), a sum of magnitudes. (The
/// signs multiply exactly: every outcome is the difference's one rounding, or two.)
#[inline(always)]
pub fn signed_diffabs<R: Real>(u: f64, d: R, s: f64, s_new: f64) -> R {
    if s == s_new {
        diffabs(u, d) * R::from_f64(s)
    } else {
        let t = R::from_f64(u) + d;
        let m = (if t < R::ZERO { -t } else { t }) + R::from_f64(u.abs());
        m * R::from_f64(s_new)
    }
}

/// The sign (±1) a signed fold gives the imaginary part: the product of the signs of the
/// parts of `z` that `out` names ([`IM_BY_X`], [`IM_BY_Y`]); 1 for none.
#[inline(always)]
pub fn side<N: Num>(out: u8, z: [N; 2]) -> N {
    let one = N::splat(1.0);
    let sx = if out & IM_BY_X != 0 { z[0].sgn() } else { one };
    let sy = if out & IM_BY_Y != 0 { z[1].sgn() } else { one };
    sx.mul(sy)
}

/// The factor (±1) of the folded imaginary part's derivative against Im u's: sgn(Im u), times
/// [`side`] for a signed fold. Where the part whose sign a signed fold reads is 0 (x for
/// [`IM_BY_X`]), Im u = x g is 0 too and the folded part x |g| is smooth: the factor is then
/// sgn(g), the sign of ∂Im u/∂x there (`grad`: ∂Im u/∂x, ∂Im u/∂y), times the other sign
/// read (y's, for xy); likewise for y. Elsewhere a zero Im u is a kink, whose derivative is
/// taken with the fold's as +1.
#[inline(always)]
fn signed_slope<N: Num>(out: u8, z: [N; 2], im_u: N, grad: [N; 2]) -> N {
    let one = N::splat(1.0);
    let mut f = im_u.sgn();
    if out & (IM_BY_X | IM_BY_Y) == 0 {
        return f;
    }
    f = f.mul(side(out, z));
    if out & IM_BY_X != 0 {
        let other = if out & IM_BY_Y != 0 { z[1].sgn() } else { one };
        f = z[0].if_zero(grad[0].sgn().mul(other), f);
    }
    if out & IM_BY_Y != 0 {
        let other = if out & IM_BY_X != 0 { z[0].sgn() } else { one };
        f = z[1].if_zero(grad[1].sgn().mul(other), f);
    }
    f
}

/// The fold after the power of `out` on u = W^p, with the sign [`side`] of z (the map's
/// input) on a signed imaginary part.
#[inline(always)]
fn fold_out<N: Num>(out: u8, z: [N; 2], u: [N; 2]) -> [N; 2] {
    let v = fold(out, u);
    if out & (IM_BY_X | IM_BY_Y) == 0 { v } else { [v[0], v[1].mul(side(out, z))] }
}

/// C(n, k) for n, k <= [`MAX_POWER`], computed when the crate is compiled (each is exact in
/// f64: a product of integers divided by the next integer, which divides it).
const BINOMIALS: [[f64; MAX_POWER as usize + 1]; MAX_POWER as usize + 1] = {
    let mut t = [[0.0; MAX_POWER as usize + 1]; MAX_POWER as usize + 1];
    let mut n = 0;
    while n <= MAX_POWER as usize {
        let mut c = 1.0;
        let mut k = 0;
        while k <= n {
            t[n][k] = c;
            c = c * (n - k) as f64 / (k + 1) as f64;
            k += 1;
        }
        n += 1;
    }
    t
};

/// The binomial coefficient C(n, k) for k <= n <= [`MAX_POWER`], as an f64 (exact): a load
/// from a table, so that a loop over k that the compiler leaves rolled does not compute it
/// with divisions at every step.
#[inline(always)]
pub fn binomial(n: u32, k: u32) -> f64 {
    BINOMIALS[n as usize][k as usize]
}

/// Folds the parts `fold` names.
#[inline(always)]
pub(super) fn fold<N: Num>(fold: u8, z: [N; 2]) -> [N; 2] {
    let x = if fold & FOLD_RE != 0 { z[0].abs() } else { z[0] };
    let y = if fold & FOLD_IM != 0 { z[1].abs() } else { z[1] };
    [x, y]
}

/// The delta of the parts `fold` names folded, against the unfolded value `z`: |Z + d| - |Z|
/// by [`diffabs`] for those, d itself for the others.
#[inline(always)]
pub(super) fn fold_delta<R: Real>(fold: u8, z: [f64; 2], d: [R; 2]) -> [R; 2] {
    [
        if fold & FOLD_RE != 0 { diffabs(z[0], d[0]) } else { d[0] },
        if fold & FOLD_IM != 0 { diffabs(z[1], d[1]) } else { d[1] },
    ]
}

/// [`fold_delta`] in [`Num`]s, lane by lane.
#[inline(always)]
pub(super) fn fold_delta_n<N: Num>(fold: u8, z: [N; 2], d: [N; 2]) -> [N; 2] {
    [
        if fold & FOLD_RE != 0 { z[0].diffabs(d[0]) } else { d[0] },
        if fold & FOLD_IM != 0 { z[1].diffabs(d[1]) } else { d[1] },
    ]
}

/// Negates the part `sign` names.
#[inline(always)]
fn signed<N: Num>(sign: u8, z: [N; 2]) -> [N; 2] {
    match sign {
        SIGN_IM => [z[0], z[1].neg()],
        SIGN_RE => [z[0].neg(), z[1]],
        _ => z,
    }
}

/// a b for complex numbers in [`Num`]s.
#[inline(always)]
pub(super) fn nmul<N: Num>(a: [N; 2], b: [N; 2]) -> [N; 2] {
    [a[0].mul(b[0]).sub(a[1].mul(b[1])), a[0].mul(b[1]).add(a[1].mul(b[0]))]
}

/// w^p (squaring as z² + c's kernels do; higher powers by repeated products).
#[inline(always)]
pub(super) fn power<const P: u32, N: Num>(w: [N; 2]) -> [N; 2] {
    let [x, y] = w;
    let square = [x.mul_add(x, y.mul(y).neg()), x.add(x).mul(y)];
    let mut u = square;
    for _ in 2..P {
        u = nmul(u, w);
    }
    if P == 1 { w } else { u }
}

/// (W + d)^p - W^p by Horner's rule in d over the binomial expansion: t = 1, then for k
/// from p - 1 down to 1, t = t d + C(p, k) W^(p-k), and the result t d. The powers of W come
/// in rising order as k falls, so each is one product of the one before (W^j = W^(j-1) W
/// from W^0 = 1), made where it is used. (With a table of powers filled first and the
/// coefficients computed by divisions, the lanes ran at half speed at p = 10, where the
/// loops are past what the compiler unrolls: docs/performance.md, "Power 10's single
/// steps".)
#[inline(always)]
pub(super) fn power_delta<const P: u32, R: Real>(w: [f64; 2], d: [R; 2]) -> [R; 2] {
    let mut a = [1.0, 0.0];
    let mut t = [R::from_f64(1.0), R::ZERO];
    for k in (1..P).rev() {
        let c = binomial(P, k);
        a = cmul(a, w);
        t = cadd(cmul(t, d), [R::from_f64(c * a[0]), R::from_f64(c * a[1])]);
    }
    cmul(t, d)
}

/// [`power_delta`] in [`Num`]s, operation for operation (the products of `cmul` are
/// [`nmul`]'s, and `[1, 0]` is multiplied out as it is there).
#[inline(always)]
pub(super) fn power_delta_n<const P: u32, N: Num>(w: [N; 2], d: [N; 2]) -> [N; 2] {
    let one = [N::splat(1.0), N::splat(0.0)];
    let mut a = one;
    let mut t = one;
    for k in (1..P).rev() {
        let c = N::splat(binomial(P, k));
        a = nmul(a, w);
        let td = nmul(t, d);
        t = [td[0].add(c.mul(a[0])), td[1].add(c.mul(a[1]))];
    }
    nmul(t, d)
}

impl<const IN: u8, const P: u32, const OUT: u8, const SIGN: u8> Map for Ops<IN, P, OUT, SIGN> {
    const POWER: u32 = P;
    const CONFORMAL: bool = IN == FOLD_NONE && OUT == FOLD_NONE && SIGN == SIGN_NONE;

    #[inline(always)]
    fn of(_: &Phase) -> Self {
        Ops
    }

    #[inline(always)]
    fn apply_n<N: Num>(&self, z: [N; 2]) -> [N; 2] {
        signed(SIGN, fold_out(OUT, z, power::<P, N>(fold(IN, z))))
    }

    fn apply_big(&self, z: &BigC) -> BigC {
        let mut u = fold_big(OUT, fold_big(IN, z.clone()).pow(P));
        // sgn(x), sgn(y) as `Num::sgn` takes them: -1 below zero only.
        let flip = (OUT & IM_BY_X != 0 && z.re < 0u32) != (OUT & IM_BY_Y != 0 && z.im < 0u32);
        if flip {
            u.im = -u.im;
        }
        match SIGN {
            SIGN_IM => BigC { re: u.re, im: -u.im, bits: u.bits },
            SIGN_RE => BigC { re: -u.re, im: u.im, bits: u.bits },
            _ => u,
        }
    }

    #[inline(always)]
    fn delta<R: Real>(&self, z: [f64; 2], d: [R; 2]) -> [R; 2] {
        let dw = fold_delta(IN, z, d);
        let w = fold(IN, z);
        let du = power_delta::<P, R>(w, dw);
        let du = if OUT == FOLD_NONE {
            du
        } else {
            let u = power::<P, f64>(w);
            let im = if OUT & (IM_BY_X | IM_BY_Y) != 0 {
                // The sample's signs: those of Z + d (a rounded sum keeps the exact sum's sign).
                let neg = |x: f64, d: R| if R::from_f64(x) + d < R::ZERO { -1.0 } else { 1.0 };
                let sx = if OUT & IM_BY_X != 0 { neg(z[0], d[0]) } else { 1.0 };
                let sy = if OUT & IM_BY_Y != 0 { neg(z[1], d[1]) } else { 1.0 };
                signed_diffabs(u[1], du[1], side(OUT, z), sx * sy)
            } else if OUT & FOLD_IM != 0 {
                diffabs(u[1], du[1])
            } else {
                du[1]
            };
            [if OUT & FOLD_RE != 0 { diffabs(u[0], du[0]) } else { du[0] }, im]
        };
        match SIGN {
            SIGN_IM => [du[0], -du[1]],
            SIGN_RE => [-du[0], du[1]],
            _ => du,
        }
    }

    #[inline(always)]
    fn delta_n<N: Num>(&self, z: [N; 2], d: [N; 2]) -> [N; 2] {
        let dw = fold_delta_n(IN, z, d);
        let w = fold(IN, z);
        let du = power_delta_n::<P, N>(w, dw);
        let du = if OUT == FOLD_NONE {
            du
        } else {
            let u = power::<P, N>(w);
            let im = if OUT & (IM_BY_X | IM_BY_Y) != 0 {
                let moved = [z[0].add(d[0]), z[1].add(d[1])];
                u[1].signed_diffabs(du[1], side(OUT, z), side(OUT, moved))
            } else if OUT & FOLD_IM != 0 {
                u[1].diffabs(du[1])
            } else {
                du[1]
            };
            [if OUT & FOLD_RE != 0 { u[0].diffabs(du[0]) } else { du[0] }, im]
        };
        match SIGN {
            SIGN_IM => [du[0], du[1].neg()],
            SIGN_RE => [du[0].neg(), du[1]],
            _ => du,
        }
    }

    #[inline(always)]
    fn jacobian_n<N: Num>(&self, z: [N; 2]) -> [[N; 2]; 2] {
        let one = N::splat(1.0);
        let w = fold(IN, z);
        // p w^(p-1), the complex derivative of the power.
        let mut a = [one, N::splat(0.0)];
        for _ in 1..P {
            a = nmul(a, w);
        }
        let k = N::splat(P as f64);
        let a = [a[0].mul(k), a[1].mul(k)];
        let si = if IN & FOLD_RE != 0 { z[0].sgn() } else { one };
        let sj = if IN & FOLD_IM != 0 { z[1].sgn() } else { one };
        let (so, sp) = if OUT == FOLD_NONE {
            (one, one)
        } else {
            let u = power::<P, N>(w);
            let sp = if OUT & FOLD_IM != 0 { signed_slope(OUT, z, u[1], [a[1].mul(si), a[0].mul(sj)]) } else { one };
            (if OUT & FOLD_RE != 0 { u[0].sgn() } else { one }, sp)
        };
        let (r, m) = match SIGN {
            SIGN_IM => (so, sp.neg()),
            SIGN_RE => (so.neg(), sp),
            _ => (so, sp),
        };
        [[r.mul(a[0]).mul(si), r.mul(a[1]).mul(sj).neg()], [m.mul(a[1]).mul(si), m.mul(a[0]).mul(sj)]]
    }
}

/// m v.
#[inline(always)]
pub fn mat_vec(m: Mat2, v: [f64; 2]) -> [f64; 2] {
    [m[0][0].mul_add(v[0], m[0][1] * v[1]), m[1][0].mul_add(v[0], m[1][1] * v[1])]
}

/// a b.
#[inline(always)]
pub fn mat_mul(a: Mat2, b: Mat2) -> Mat2 {
    [
        [a[0][0] * b[0][0] + a[0][1] * b[1][0], a[0][0] * b[0][1] + a[0][1] * b[1][1]],
        [a[1][0] * b[0][0] + a[1][1] * b[1][0], a[1][0] * b[0][1] + a[1][1] * b[1][1]],
    ]
}

/// The derivative a distance estimate uses, from the Jacobian J of z_n in the sample's
/// parameter: the complex number dz with conj(dz) z = Jᵀ z (the gradient of ln|z_n|,
/// times |z_n|²). Where J is conformal (J = dz as a matrix) this is dz itself; elsewhere
/// |dz| = |Jᵀ ẑ|, the derivative along the direction in which |z_n| grows fastest, so the
/// estimate |z| ln|z| / |dz| is the distance to the level set of the potential.
#[inline]
pub fn gradient_dz(z: [f64; 2], j: Mat2) -> [f64; 2] {
    // g = Jᵀ z as a complex number; dz = conj(g / z).
    let g = [j[0][0] * z[0] + j[1][0] * z[1], j[0][1] * z[0] + j[1][1] * z[1]];
    let n = z[0] * z[0] + z[1] * z[1];
    let q = [(g[0] * z[0] + g[1] * z[1]) / n, (g[1] * z[0] - g[0] * z[1]) / n];
    [q[0], -q[1]]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::formula::checks;

    type Ship3 = Ops<FOLD_BOTH, 3, FOLD_NONE, SIGN_NONE>;
    type Buffalo2 = Ops<FOLD_NONE, 2, FOLD_BOTH, SIGN_NONE>;
    type Perp = Ops<FOLD_RE, 2, FOLD_RE, SIGN_IM>;
    type Multi5 = Ops<FOLD_NONE, 5, FOLD_NONE, SIGN_NONE>;
    /// Kalles Fraktaler's types 14, 26 and 34: imaginary parts signed by y, xy and x.
    type QuasiPerp3 = Ops<FOLD_RE, 3, { FOLD_IM | IM_BY_Y }, SIGN_IM>;
    type CelticFalseHeart4 = Ops<FOLD_NONE, 4, { FOLD_RE | FOLD_IM | IM_BY_X | IM_BY_Y }, SIGN_NONE>;
    type ImagQuasi4 = Ops<FOLD_NONE, 4, { FOLD_IM | IM_BY_X }, SIGN_NONE>;

    const POINTS: [[f64; 2]; 6] = [[0.3, -0.7], [-1.1, 0.2], [0.05, 0.9], [-0.4, -0.35], [1.3, 1e-3], [-2e-3, 0.6]];

    const DELTAS: [[f64; 2]; 4] = [[1e-3, -2e-3], [-0.5, 0.1], [2e-9, 7e-9], [-0.31, 0.8]];

    fn check_delta<M: Map + Default>() {
        checks::check_delta(&M::default(), &POINTS, &DELTAS, 4e-14);
    }

    fn check_jacobian<M: Map + Default>() {
        checks::check_jacobian(&M::default(), &POINTS);
    }

    fn check_big<M: Map + Default>() {
        for z in POINTS {
            let f = M::default().apply(z);
            let b = M::default().apply_big(&BigC::from_f64(z[0], z[1], 200));
            let b = checks::parse(&b);
            assert!((f[0] - b[0]).abs() < 1e-14 && (f[1] - b[1]).abs() < 1e-14, "{z:?}");
        }
    }

    #[test]
    fn delta_is_the_difference_of_two_steps() {
        check_delta::<Ship3>();
        check_delta::<Buffalo2>();
        check_delta::<Perp>();
        check_delta::<Multi5>();
        check_delta::<QuasiPerp3>();
        check_delta::<CelticFalseHeart4>();
        check_delta::<ImagQuasi4>();
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        check_jacobian::<Ship3>();
        check_jacobian::<Buffalo2>();
        check_jacobian::<Perp>();
        check_jacobian::<Multi5>();
        check_jacobian::<QuasiPerp3>();
        check_jacobian::<CelticFalseHeart4>();
        check_jacobian::<ImagQuasi4>();
    }

    #[test]
    fn f64_and_big_float_steps_agree() {
        check_big::<Ship3>();
        check_big::<Buffalo2>();
        check_big::<Perp>();
        check_big::<Multi5>();
        check_big::<QuasiPerp3>();
        check_big::<CelticFalseHeart4>();
        check_big::<ImagQuasi4>();
    }

    #[test]
    fn diffabs_never_cancels() {
        // |X + d| - |X| where both are large and nearly equal: the direct difference loses
        // everything, diffabs keeps d exactly.
        assert_eq!(diffabs(1e10, 1e-9f64), 1e-9);
        assert_eq!(diffabs(-1e10, 1e-9f64), -1e-9);
        assert_eq!(diffabs(1e-3, -3e-3f64), 1e-3);
        assert_eq!(diffabs(-1e-3, 3e-3f64), 1e-3);
    }

    #[test]
    fn gradient_dz_is_dz_where_the_map_is_conformal() {
        let dz = [0.7, -1.3];
        let j = [[dz[0], -dz[1]], [dz[1], dz[0]]];
        let g = gradient_dz([0.4, 2.5], j);
        assert!((g[0] - dz[0]).abs() < 1e-15 && (g[1] - dz[1]).abs() < 1e-15, "{g:?}");
    }

    /// `delta_n` in lanes gives each lane the bits of the scalar `delta::<f64>`, for every
    /// family at every power, at values on and near the fold lines (signs of zero, deltas
    /// that cross a fold) and at random ones.
    #[test]
    fn lane_deltas_have_the_scalar_deltas_bits() {
        use crate::formula::Phase;
        use crate::formula::kind::KINDS;
        let mut seed = 0x2545_f491_4f6c_dd1du64;
        let mut rand = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let special = [0.0, -0.0, 1e-300, -1e-300, 0.5, -0.5, 1.75, -2.0];
        let mut cases: Vec<([f64; 2], [f64; 2])> = vec![];
        for &a in &special {
            for &b in &special {
                cases.push(([a, b], [-a * 0.5, b * 3.0]));
                cases.push(([a, -b], [a * -2.0, 1e-5]));
            }
        }
        for _ in 0..400 {
            let scale = 10f64.powi((rand() * 8.0) as i32);
            cases.push(([rand() * 2.0, rand() * 2.0], [rand() * scale, rand() * scale]));
        }
        const L: usize = 8;
        for k in KINDS {
            for p in k.min_power..=k.max_power {
                let phase = Phase::new(k.kind, p);
                crate::with_map!(phase, m: M => {
                    for chunk in cases.chunks(L) {
                        let mut z = [[0.0; L]; 2];
                        let mut d = [[0.0; L]; 2];
                        for (j, (zc, dc)) in chunk.iter().enumerate() {
                            (z[0][j], z[1][j], d[0][j], d[1][j]) = (zc[0], zc[1], dc[0], dc[1]);
                        }
                        let got = m.delta_n(z, d);
                        for (j, (zc, dc)) in chunk.iter().enumerate() {
                            let want = m.delta::<f64>(*zc, *dc);
                            let lane = [got[0][j], got[1][j]];
                            assert_eq!(lane.map(f64::to_bits), want.map(f64::to_bits), "{phase} {zc:?} {dc:?}");
                        }
                    }
                }, unreachable!("{phase}"));
            }
        }
    }

    /// The signed fold is Kalles Fraktaler's product of a part and the folded factor: type 14's
    /// Im is -y |3x² - y²|, type 34's 4x |y (x² - y²)|, type 26's 4xy |x² - y²|.
    #[test]
    fn signed_folds_are_kf_products() {
        for z in POINTS.into_iter().chain([[0.0, 0.5], [-0.7, 0.0], [0.4, -0.4]]) {
            let [x, y] = z;
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-14 * (1.0 + b.abs());
            assert!(close(QuasiPerp3::default().apply(z)[1], -(y * (3.0 * x * x - y * y).abs())), "{z:?}");
            assert!(close(ImagQuasi4::default().apply(z)[1], 4.0 * x * (y * (x * x - y * y)).abs()), "{z:?}");
            assert!(close(CelticFalseHeart4::default().apply(z)[1], 4.0 * x * y * (x * x - y * y).abs()), "{z:?}");
        }
    }

    #[test]
    fn binomials() {
        assert_eq!(binomial(10, 5), 252.0);
        assert_eq!(binomial(4, 0), 1.0);
        assert_eq!(binomial(7, 7), 1.0);
        // Pascal's rule over the whole table.
        for n in 1..=MAX_POWER {
            for k in 1..n {
                assert_eq!(binomial(n, k), binomial(n - 1, k - 1) + binomial(n - 1, k), "C({n}, {k})");
            }
        }
    }
}
