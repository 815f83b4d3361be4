//! The formula families: one row each, declared once, with the name users write, Kalles
//! Fraktaler's type number, the powers it comes in, and the four steps of [`super::map`]
//! that make its map.
//!
//! Each row is exactly Kalles Fraktaler 2.15's definition (its `formula.xml`, reference
//! lines), rewritten as a composition: for instance KF's Burning Ship power 3,
//! `Xrn = (Xr2 - 3 Xi2) |Xr| + Cr; Xin = (3 Xr2 - Xi2) |Xi| + Ci`, is (|x| + i|y|)³ + c, a
//! fold of both parts before the power. Kalles Fraktaler's Mandelbar of power 3 negates the
//! real part of z³ where its other powers conjugate: the table keeps that. Its "quasi"
//! families fold a factor of the imaginary part, `Xin = Ci - |3 Xr2 - Xi2| Xi`: since
//! Im w = y (3x² - y²) there, that is -sgn(y) |Im w|, a fold of Im w that gives it back the
//! sign of y (`IM_BY_Y`; of x or xy in others). The Mothbrot and SimonBrot rows are
//! products of two maps instead ([`super::product`]), with their factors in the row.
//! `tests/integration/formula_kf.rs` checks every row against KF's expanded formulas.

use super::map::{FOLD_BOTH, FOLD_IM, FOLD_NONE, FOLD_RE, IM_BY_X, IM_BY_Y, SIGN_IM, SIGN_NONE, SIGN_RE};

/// A formula family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Kind {
    /// z^p + c (type 0).
    Mandelbrot,
    /// (|x| + i|y|)^p + c (type 1).
    BurningShip,
    /// |Re z^p| + i|Im z^p| + c (type 2).
    Buffalo,
    /// |Re z^p| + i Im z^p + c (type 3).
    Celtic,
    /// conj(z)^p + c; for p = 3, -Re z³ + i Im z³ + c (type 4, the tricorn at p = 2).
    Mandelbar,
    /// |Re z²| - i Im z² + c (type 5).
    MandelbarCeltic,
    /// conj((|x| + iy)²) + c (type 6).
    PerpendicularMandelbrot,
    /// conj((x + i|y|)²) + c (type 7).
    PerpendicularBurningShip,
    /// |Re w| - i Im w + c, w = (|x| + iy)² (type 8).
    PerpendicularCeltic,
    /// |Re w| - i Im w + c, w = (x + i|y|)² (type 9).
    PerpendicularBuffalo,
    /// Re w - i|Im w| + c, w = (|x| + iy)³ (type 10).
    CubicQuasiBurningShip,
    /// (|x| + iy)³ + c (type 11).
    CubicPartialBsReal,
    /// (x + i|y|)³ + c (type 12).
    CubicPartialBsImag,
    /// Re z³ + i|Im z³| + c (type 13).
    CubicFlyingSquirrel,
    /// Re w - i sgn(y)|Im w| + c, w = (|x| + iy)³ (type 14).
    CubicQuasiPerpendicular,
    /// (x + i|y|)⁴ + c (type 15).
    BurningShip4PartialImag,
    /// (|x| + iy)⁴ + c (type 16).
    BurningShip4PartialReal,
    /// conj((|x| + iy)⁴) + c (type 17).
    BurningShip4PartialRealMbar,
    /// |Re w| + i Im w + c, w = (x + i|y|)⁴ (type 18).
    CelticBurningShip4PartialImag,
    /// |Re w| + i Im w + c, w = (|x| + iy)⁴ (type 19).
    CelticBurningShip4PartialReal,
    /// |Re w| - i Im w + c, w = (|x| + iy)⁴ (type 20).
    CelticBurningShip4PartialRealMbar,
    /// Re z⁴ + i|Im z⁴| + c (type 21).
    Buffalo4PartialImag,
    /// |Re z⁴| - i Im z⁴ + c (type 22).
    Celtic4Mbar,
    /// Re z⁴ - i sgn(xy)|Im z⁴| + c (type 23).
    FalseQuasiPerpendicular4,
    /// Re z⁴ + i sgn(xy)|Im z⁴| + c (type 24).
    FalseQuasiHeart4,
    /// |Re z⁴| - i sgn(xy)|Im z⁴| + c (type 25).
    CelticFalseQuasiPerpendicular4,
    /// |Re z⁴| + i sgn(xy)|Im z⁴| + c (type 26).
    CelticFalseQuasiHeart4,
    /// (|x| + iy)⁵ + c (type 27).
    BurningShip5Partial,
    /// conj((|x| + iy)⁵) + c (type 28).
    BurningShip5PartialMbar,
    /// |Re z⁵| - i Im z⁵ + c (type 29).
    Celtic5Mbar,
    /// Re w - i|Im w| + c, w = (|x| + iy)⁵ (type 30).
    QuasiBurningShip5,
    /// Re w - i sgn(y)|Im w| + c, w = (|x| + iy)⁵ (type 31).
    QuasiPerpendicular5,
    /// Re w + i sgn(y)|Im w| + c, w = (|x| + iy)⁵ (type 32).
    QuasiHeart5,
    /// z² (|x| + i|y|)² + c, Mothbrot 2×2 under its other name (type 33).
    SimonBrot4,
    /// Re z⁴ + i sgn(x)|Im z⁴| + c (type 34).
    ImagQuasiPerpendicular4,
    /// Re z⁴ - i sgn(y)|Im z⁴| + c (type 35).
    RealQuasiPerpendicular4,
    /// Re z⁴ + i sgn(y)|Im z⁴| + c (type 36).
    RealQuasiHeart4,
    /// |Re z⁴| + i sgn(x)|Im z⁴| + c (type 37).
    CelticImagQuasiPerpendicular4,
    /// |Re z⁴| - i sgn(y)|Im z⁴| + c (type 38).
    CelticRealQuasiPerpendicular4,
    /// |Re z⁴| + i sgn(y)|Im z⁴| + c (type 39).
    CelticRealQuasiHeart4,
    /// z³ (|x| + i|y|)³ + c, Mothbrot 3×3 under its other name (type 40).
    SimonBrot6,
    /// W² - W + c, W = |x| + i|y| (type 41).
    HpdzBuffalo,
    /// a z² + z³ + c (type 42).
    RedshiftRider1,
    /// a z² - z³ + c (type 43).
    RedshiftRider2,
    /// 2 z² - z³ + c (type 44).
    RedshiftRider3,
    /// a z² + z⁴ + c (type 45).
    RedshiftRider4,
    /// a z² - z⁴ + c (type 46).
    RedshiftRider5,
    /// a z² + z⁵ + c (type 47).
    RedshiftRider6,
    /// a z² - z⁵ + c (type 48).
    RedshiftRider7,
    /// a z² + z⁶ + c (type 49).
    RedshiftRider8,
    /// a z² - z⁶ + c (type 50).
    RedshiftRider9,
    /// u (|Re u| + i|Im u|) + c, u = z² (type 51).
    SimonBrot2,
    /// z^1 (|x| + i|y|)^1 + c (type 54).
    Mothbrot1x1,
    /// z^1 (|x| + i|y|)^2 + c (type 55).
    Mothbrot1x2,
    /// z^2 (|x| + i|y|)^1 + c (type 56).
    Mothbrot2x1,
    /// z^1 (|x| + i|y|)^3 + c (type 57).
    Mothbrot1x3,
    /// z^2 (|x| + i|y|)^2 + c (type 58).
    Mothbrot2x2,
    /// z^3 (|x| + i|y|)^1 + c (type 59).
    Mothbrot3x1,
    /// z^1 (|x| + i|y|)^4 + c (type 60).
    Mothbrot1x4,
    /// z^2 (|x| + i|y|)^3 + c (type 61).
    Mothbrot2x3,
    /// z^3 (|x| + i|y|)^2 + c (type 62).
    Mothbrot3x2,
    /// z^4 (|x| + i|y|)^1 + c (type 63).
    Mothbrot4x1,
    /// z^1 (|x| + i|y|)^5 + c (type 64).
    Mothbrot1x5,
    /// z^2 (|x| + i|y|)^4 + c (type 65).
    Mothbrot2x4,
    /// z^3 (|x| + i|y|)^3 + c (type 66).
    Mothbrot3x3,
    /// z^4 (|x| + i|y|)^2 + c (type 67).
    Mothbrot4x2,
    /// z^5 (|x| + i|y|)^1 + c (type 68).
    Mothbrot5x1,
}

/// What one family is: the facts every part of the tool reads from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct KindInfo {
    /// The family.
    pub kind: Kind,
    /// The name in scene files and on the command line.
    pub name: &'static str,
    /// Kalles Fraktaler's name for it.
    pub kf_name: &'static str,
    /// Kalles Fraktaler's `FractalType`.
    pub kf_type: u32,
    /// The smallest power.
    pub min_power: u32,
    /// The largest power.
    pub max_power: u32,
    /// The fold before the power.
    pub fold_in: u8,
    /// The fold after the power.
    pub fold_out: u8,
    /// The negation at the end, for every power but 3.
    pub sign: u8,
    /// The negation at the end for power 3.
    pub sign3: u8,
    /// For a product family ([`super::product`]): (PRE, A, B) of u^A (|Re u| + i|Im u|)^B,
    /// u = z^PRE; its fold and sign fields are then [`PRODUCT`], which no composition has.
    pub factors: Option<(u32, u32, u32)>,
    /// For a family of two terms ([`super::sum`]), its shape; its fold and sign fields are
    /// then [`PRODUCT`].
    pub sum: Option<SumShape>,
    /// Where the family's coefficient a comes from.
    pub coef: Coefficient,
}

/// A family of two terms ([`super::sum`]): a W² + W^q, or a W² - W^q where `neg`, with W = z
/// folded by `fold_in`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SumShape {
    /// The fold of z before both terms.
    pub fold_in: u8,
    /// The second term's power (1 to 6).
    pub q: u32,
    /// Whether the second term is subtracted.
    pub neg: bool,
}

/// Where a family's coefficient a comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Coefficient {
    /// The family has none.
    None,
    /// The user's (`a` in scenes, `--a` on the command line, Kalles Fraktaler's
    /// `FactorAR`, `FactorAI`), 1 when none is given, as in Kalles Fraktaler.
    User,
    /// A constant of the family (Kalles Fraktaler writes some families with a number
    /// where their relatives have a).
    Fixed(i32),
}

impl Coefficient {
    /// The value a phase of the family starts with.
    pub fn default(self) -> [f64; 2] {
        match self {
            Coefficient::Fixed(v) => [v as f64, 0.0],
            _ => [1.0, 0.0],
        }
    }
}

/// What the fold and sign fields of a product's or a sum's row hold: no composition's steps,
/// so code that reads a row as a composition cannot take a product for one.
pub const PRODUCT: u8 = 0x80;

const fn row(
    kind: Kind,
    name: &'static str,
    kf_name: &'static str,
    kf_type: u32,
    powers: (u32, u32),
    fold_in: u8,
    fold_out: u8,
    sign: u8,
) -> KindInfo {
    KindInfo {
        kind,
        name,
        kf_name,
        kf_type,
        min_power: powers.0,
        max_power: powers.1,
        fold_in,
        fold_out,
        sign,
        sign3: sign,
        factors: None,
        sum: None,
        coef: Coefficient::None,
    }
}

/// The row of a product family: u^A (|Re u| + i|Im u|)^B, u = z^PRE, of power PRE (A + B).
const fn prow(
    kind: Kind,
    name: &'static str,
    kf_name: &'static str,
    kf_type: u32,
    (pre, a, b): (u32, u32, u32),
) -> KindInfo {
    let p = pre * (a + b);
    KindInfo {
        factors: Some((pre, a, b)),
        sign3: PRODUCT,
        ..row(kind, name, kf_name, kf_type, (p, p), PRODUCT, PRODUCT, PRODUCT)
    }
}

/// The row of a family of two terms ([`super::sum`]), a W² ± W^q, W = z folded by
/// `fold_in`, of power max(2, q).
const fn srow(
    kind: Kind,
    name: &'static str,
    kf_name: &'static str,
    kf_type: u32,
    (fold_in, q, neg): (u8, u32, bool),
    coef: Coefficient,
) -> KindInfo {
    let p = if q > 2 { q } else { 2 };
    KindInfo {
        sum: Some(SumShape { fold_in, q, neg }),
        coef,
        sign3: PRODUCT,
        ..row(kind, name, kf_name, kf_type, (p, p), PRODUCT, PRODUCT, PRODUCT)
    }
}

use Kind as K;

/// The imaginary part folded after the power and given the sign of x, of y, or of xy.
const BY_X: u8 = FOLD_IM | IM_BY_X;
const BY_Y: u8 = FOLD_IM | IM_BY_Y;
const BY_XY: u8 = FOLD_IM | IM_BY_X | IM_BY_Y;

/// Every family, in Kalles Fraktaler's order.
pub const KINDS: [KindInfo; 67] = [
    row(K::Mandelbrot, "mandelbrot", "Mandelbrot", 0, (2, 10), FOLD_NONE, FOLD_NONE, SIGN_NONE),
    row(K::BurningShip, "burning-ship", "Burning Ship", 1, (2, 5), FOLD_BOTH, FOLD_NONE, SIGN_NONE),
    row(K::Buffalo, "buffalo", "Buffalo", 2, (2, 5), FOLD_NONE, FOLD_BOTH, SIGN_NONE),
    row(K::Celtic, "celtic", "Celtic", 3, (2, 5), FOLD_NONE, FOLD_RE, SIGN_NONE),
    KindInfo {
        sign3: SIGN_RE,
        ..row(K::Mandelbar, "mandelbar", "Mandelbar", 4, (2, 5), FOLD_NONE, FOLD_NONE, SIGN_IM)
    },
    row(K::MandelbarCeltic, "mandelbar-celtic", "Mandelbar Celtic", 5, (2, 2), FOLD_NONE, FOLD_RE, SIGN_IM),
    row(
        K::PerpendicularMandelbrot,
        "perpendicular-mandelbrot",
        "Perpendicular Mandelbrot",
        6,
        (2, 2),
        FOLD_RE,
        FOLD_NONE,
        SIGN_IM,
    ),
    row(
        K::PerpendicularBurningShip,
        "perpendicular-burning-ship",
        "Perpendicular Burning Ship",
        7,
        (2, 2),
        FOLD_IM,
        FOLD_NONE,
        SIGN_IM,
    ),
    row(K::PerpendicularCeltic, "perpendicular-celtic", "Perpendicular Celtic", 8, (2, 2), FOLD_RE, FOLD_RE, SIGN_IM),
    row(
        K::PerpendicularBuffalo,
        "perpendicular-buffalo",
        "Perpendicular Buffalo",
        9,
        (2, 2),
        FOLD_IM,
        FOLD_RE,
        SIGN_IM,
    ),
    row(
        K::CubicQuasiBurningShip,
        "cubic-quasi-burning-ship",
        "Cubic Quasi Burning Ship",
        10,
        (3, 3),
        FOLD_RE,
        FOLD_IM,
        SIGN_IM,
    ),
    row(
        K::CubicPartialBsReal,
        "cubic-partial-bs-real",
        "Cubic Partial BS Real",
        11,
        (3, 3),
        FOLD_RE,
        FOLD_NONE,
        SIGN_NONE,
    ),
    row(
        K::CubicPartialBsImag,
        "cubic-partial-bs-imag",
        "Cubic Partial BS Imag",
        12,
        (3, 3),
        FOLD_IM,
        FOLD_NONE,
        SIGN_NONE,
    ),
    row(
        K::CubicFlyingSquirrel,
        "cubic-flying-squirrel",
        "Cubic Flying Squirrel (Buffalo Imag)",
        13,
        (3, 3),
        FOLD_NONE,
        FOLD_IM,
        SIGN_NONE,
    ),
    row(
        K::CubicQuasiPerpendicular,
        "cubic-quasi-perpendicular",
        "Cubic Quasi Perpendicular",
        14,
        (3, 3),
        FOLD_RE,
        BY_Y,
        SIGN_IM,
    ),
    row(
        K::BurningShip4PartialImag,
        "4th-burning-ship-partial-imag",
        "4th Burning Ship Partial Imag",
        15,
        (4, 4),
        FOLD_IM,
        FOLD_NONE,
        SIGN_NONE,
    ),
    row(
        K::BurningShip4PartialReal,
        "4th-burning-ship-partial-real",
        "4th Burning Ship Partial Real",
        16,
        (4, 4),
        FOLD_RE,
        FOLD_NONE,
        SIGN_NONE,
    ),
    row(
        K::BurningShip4PartialRealMbar,
        "4th-burning-ship-partial-real-mbar",
        "4th Burning Ship Partial Real Mbar",
        17,
        (4, 4),
        FOLD_RE,
        FOLD_NONE,
        SIGN_IM,
    ),
    row(
        K::CelticBurningShip4PartialImag,
        "4th-celtic-burning-ship-partial-imag",
        "4th Celtic Burning Ship Partial Imag",
        18,
        (4, 4),
        FOLD_IM,
        FOLD_RE,
        SIGN_NONE,
    ),
    row(
        K::CelticBurningShip4PartialReal,
        "4th-celtic-burning-ship-partial-real",
        "4th Celtic Burning Ship Partial Real",
        19,
        (4, 4),
        FOLD_RE,
        FOLD_RE,
        SIGN_NONE,
    ),
    row(
        K::CelticBurningShip4PartialRealMbar,
        "4th-celtic-burning-ship-partial-real-mbar",
        "4th Celtic Burning Ship Partial Real Mbar",
        20,
        (4, 4),
        FOLD_RE,
        FOLD_RE,
        SIGN_IM,
    ),
    row(
        K::Buffalo4PartialImag,
        "4th-buffalo-partial-imag",
        "4th Buffalo Partial Imag",
        21,
        (4, 4),
        FOLD_NONE,
        FOLD_IM,
        SIGN_NONE,
    ),
    row(K::Celtic4Mbar, "4th-celtic-mbar", "4th Celtic Mbar", 22, (4, 4), FOLD_NONE, FOLD_RE, SIGN_IM),
    row(
        K::FalseQuasiPerpendicular4,
        "4th-false-quasi-perpendicular",
        "4th False Quasi Perpendicular",
        23,
        (4, 4),
        FOLD_NONE,
        BY_XY,
        SIGN_IM,
    ),
    row(K::FalseQuasiHeart4, "4th-false-quasi-heart", "4th False Quasi Heart", 24, (4, 4), FOLD_NONE, BY_XY, SIGN_NONE),
    row(
        K::CelticFalseQuasiPerpendicular4,
        "4th-celtic-false-quasi-perpendicular",
        "4th Celtic False Quasi Perpendicular",
        25,
        (4, 4),
        FOLD_NONE,
        FOLD_RE | BY_XY,
        SIGN_IM,
    ),
    row(
        K::CelticFalseQuasiHeart4,
        "4th-celtic-false-quasi-heart",
        "4th Celtic False Quasi Heart",
        26,
        (4, 4),
        FOLD_NONE,
        FOLD_RE | BY_XY,
        SIGN_NONE,
    ),
    row(
        K::BurningShip5Partial,
        "5th-burning-ship-partial",
        "5th Burning Ship Partial",
        27,
        (5, 5),
        FOLD_RE,
        FOLD_NONE,
        SIGN_NONE,
    ),
    row(
        K::BurningShip5PartialMbar,
        "5th-burning-ship-partial-mbar",
        "5th Burning Ship Partial Mbar",
        28,
        (5, 5),
        FOLD_RE,
        FOLD_NONE,
        SIGN_IM,
    ),
    row(K::Celtic5Mbar, "5th-celtic-mbar", "5th Celtic Mbar", 29, (5, 5), FOLD_NONE, FOLD_RE, SIGN_IM),
    row(
        K::QuasiBurningShip5,
        "5th-quasi-burning-ship",
        "5th Quasi Burning Ship (BS/Buffalo Hybrid)",
        30,
        (5, 5),
        FOLD_RE,
        FOLD_IM,
        SIGN_IM,
    ),
    row(
        K::QuasiPerpendicular5,
        "5th-quasi-perpendicular",
        "5th Quasi Perpendicular",
        31,
        (5, 5),
        FOLD_RE,
        BY_Y,
        SIGN_IM,
    ),
    row(K::QuasiHeart5, "5th-quasi-heart", "5th Quasi Heart", 32, (5, 5), FOLD_RE, BY_Y, SIGN_NONE),
    prow(K::SimonBrot4, "simonbrot-4th", "SimonBrot 4th", 33, (1, 2, 2)),
    row(
        K::ImagQuasiPerpendicular4,
        "4th-imag-quasi-perpendicular",
        "4th Imag Quasi Perpendicular / Heart",
        34,
        (4, 4),
        FOLD_NONE,
        BY_X,
        SIGN_NONE,
    ),
    row(
        K::RealQuasiPerpendicular4,
        "4th-real-quasi-perpendicular",
        "4th Real Quasi Perpendicular",
        35,
        (4, 4),
        FOLD_NONE,
        BY_Y,
        SIGN_IM,
    ),
    row(K::RealQuasiHeart4, "4th-real-quasi-heart", "4th Real Quasi Heart", 36, (4, 4), FOLD_NONE, BY_Y, SIGN_NONE),
    row(
        K::CelticImagQuasiPerpendicular4,
        "4th-celtic-imag-quasi-perpendicular",
        "4th Celtic Imag Quasi Perpendicular / Heart",
        37,
        (4, 4),
        FOLD_NONE,
        FOLD_RE | BY_X,
        SIGN_NONE,
    ),
    row(
        K::CelticRealQuasiPerpendicular4,
        "4th-celtic-real-quasi-perpendicular",
        "4th Celtic Real Quasi Perpendicular",
        38,
        (4, 4),
        FOLD_NONE,
        FOLD_RE | BY_Y,
        SIGN_IM,
    ),
    row(
        K::CelticRealQuasiHeart4,
        "4th-celtic-real-quasi-heart",
        "4th Celtic Real Quasi Heart",
        39,
        (4, 4),
        FOLD_NONE,
        FOLD_RE | BY_Y,
        SIGN_NONE,
    ),
    prow(K::SimonBrot6, "simonbrot-6th", "SimonBrot 6th", 40, (1, 3, 3)),
    srow(K::HpdzBuffalo, "hpdz-buffalo", "HPDZ Buffalo", 41, (FOLD_BOTH, 1, true), Coefficient::Fixed(1)),
    srow(
        K::RedshiftRider1,
        "redshift-rider-1",
        "TheRedshiftRider 1: a * z^2 + z^3 + c",
        42,
        (FOLD_NONE, 3, false),
        Coefficient::User,
    ),
    srow(
        K::RedshiftRider2,
        "redshift-rider-2",
        "TheRedshiftRider 2: a * z^2 - z^3 + c",
        43,
        (FOLD_NONE, 3, true),
        Coefficient::User,
    ),
    srow(
        K::RedshiftRider3,
        "redshift-rider-3",
        "TheRedshiftRider 3: 2 * z^2 - z^3 + c",
        44,
        (FOLD_NONE, 3, true),
        Coefficient::Fixed(2),
    ),
    srow(
        K::RedshiftRider4,
        "redshift-rider-4",
        "TheRedshiftRider 4: a * z^2 + z^4 + c",
        45,
        (FOLD_NONE, 4, false),
        Coefficient::User,
    ),
    srow(
        K::RedshiftRider5,
        "redshift-rider-5",
        "TheRedshiftRider 5: a * z^2 - z^4 + c",
        46,
        (FOLD_NONE, 4, true),
        Coefficient::User,
    ),
    srow(
        K::RedshiftRider6,
        "redshift-rider-6",
        "TheRedshiftRider 6: a * z^2 + z^5 + c",
        47,
        (FOLD_NONE, 5, false),
        Coefficient::User,
    ),
    srow(
        K::RedshiftRider7,
        "redshift-rider-7",
        "TheRedshiftRider 7: a * z^2 - z^5 + c",
        48,
        (FOLD_NONE, 5, true),
        Coefficient::User,
    ),
    srow(
        K::RedshiftRider8,
        "redshift-rider-8",
        "TheRedshiftRider 8: a * z^2 + z^6 + c",
        49,
        (FOLD_NONE, 6, false),
        Coefficient::User,
    ),
    srow(
        K::RedshiftRider9,
        "redshift-rider-9",
        "TheRedshiftRider 9: a * z^2 - z^6 + c",
        50,
        (FOLD_NONE, 6, true),
        Coefficient::User,
    ),
    prow(K::SimonBrot2, "simonbrot2-4th", "SimonBrot2 4th", 51, (2, 1, 1)),
    prow(K::Mothbrot1x1, "mothbrot-1x1", "Mothbrot 2nd 1x1", 54, (1, 1, 1)),
    prow(K::Mothbrot1x2, "mothbrot-1x2", "Mothbrot 3rd 1x2", 55, (1, 1, 2)),
    prow(K::Mothbrot2x1, "mothbrot-2x1", "Mothbrot 3rd 2x1", 56, (1, 2, 1)),
    prow(K::Mothbrot1x3, "mothbrot-1x3", "Mothbrot 4th 1x3", 57, (1, 1, 3)),
    prow(K::Mothbrot2x2, "mothbrot-2x2", "Mothbrot 4th 2x2 (aka SimonBrot 4th)", 58, (1, 2, 2)),
    prow(K::Mothbrot3x1, "mothbrot-3x1", "Mothbrot 4th 3x1", 59, (1, 3, 1)),
    prow(K::Mothbrot1x4, "mothbrot-1x4", "Mothbrot 5th 1x4", 60, (1, 1, 4)),
    prow(K::Mothbrot2x3, "mothbrot-2x3", "Mothbrot 5th 2x3", 61, (1, 2, 3)),
    prow(K::Mothbrot3x2, "mothbrot-3x2", "Mothbrot 5th 3x2", 62, (1, 3, 2)),
    prow(K::Mothbrot4x1, "mothbrot-4x1", "Mothbrot 5th 4x1", 63, (1, 4, 1)),
    prow(K::Mothbrot1x5, "mothbrot-1x5", "Mothbrot 6th 1x5", 64, (1, 1, 5)),
    prow(K::Mothbrot2x4, "mothbrot-2x4", "Mothbrot 6th 2x4 (Simon's Mothbrot)", 65, (1, 2, 4)),
    prow(K::Mothbrot3x3, "mothbrot-3x3", "Mothbrot 6th 3x3 (aka SimonBrot 6th)", 66, (1, 3, 3)),
    prow(K::Mothbrot4x2, "mothbrot-4x2", "Mothbrot 6th 4x2", 67, (1, 4, 2)),
    prow(K::Mothbrot5x1, "mothbrot-5x1", "Mothbrot 6th 5x1", 68, (1, 5, 1)),
];

// Each family's row is at its index in `Kind`, so that `Kind::info` is one load rather than a
// search of the table: a hybrid's loops look their phase's shape up at every step
// (`formula::Cycle`). Measured on a hybrid of late families, the search cost nothing
// visible; the load is the simpler contract, and this block keeps it true.
const _: () = {
    let mut i = 0;
    while i < KINDS.len() {
        assert!(KINDS[i].kind as usize == i, "KINDS must list the families in the order of `Kind`");
        i += 1;
    }
};

impl Kind {
    /// The family's row.
    #[inline(always)]
    pub fn info(self) -> &'static KindInfo {
        &KINDS[self as usize]
    }

    /// The name users write.
    pub fn name(self) -> &'static str {
        self.info().name
    }

    /// The family called `name`.
    pub fn from_name(name: &str) -> Option<Kind> {
        KINDS.iter().find(|k| k.name == name).map(|k| k.kind)
    }

    /// The family of Kalles Fraktaler's `FractalType` `t`.
    pub fn from_kf_type(t: u32) -> Option<Kind> {
        KINDS.iter().find(|k| k.kf_type == t).map(|k| k.kind)
    }

    /// Whether the family comes in power `p`.
    pub fn has_power(self, p: u32) -> bool {
        let i = self.info();
        (i.min_power..=i.max_power).contains(&p)
    }

    /// The family's default power (its smallest).
    pub fn default_power(self) -> u32 {
        self.info().min_power
    }

    /// The four steps of the map at power `p`: (fold in, power, fold out, sign); for a
    /// product or a sum, ([`PRODUCT`], p, [`PRODUCT`], [`PRODUCT`]), which no composition is.
    #[inline(always)]
    pub fn shape(self, p: u32) -> (u8, u32, u8, u8) {
        let i = self.info();
        (i.fold_in, p, i.fold_out, if p == 3 { i.sign3 } else { i.sign })
    }

    /// True when the user gives the family its coefficient a ([`Coefficient::User`]).
    pub fn takes_a(self) -> bool {
        self.info().coef == Coefficient::User
    }

    /// The shape of a family of two terms ([`KindInfo::sum`]), None otherwise.
    #[inline(always)]
    pub fn sum(self) -> Option<SumShape> {
        self.info().sum
    }

    /// (PRE, A, B) for a product family ([`KindInfo::factors`]), None for a composition.
    #[inline(always)]
    pub fn factors(self) -> Option<(u32, u32, u32)> {
        self.info().factors
    }

    /// The map at power `p` in words, derived from its four steps (what `deepfield formulas`
    /// prints): `|Re w| - i Im w + c, w = (|x| + iy)^2`.
    pub fn definition(self, p: u32) -> String {
        if let Some(SumShape { fold_in, q, neg }) = self.sum() {
            let a = match self.info().coef {
                Coefficient::Fixed(1) => String::new(),
                Coefficient::Fixed(v) => format!("{v} "),
                _ => "a ".into(),
            };
            let op = if neg { "-" } else { "+" };
            let second = if q == 1 { "W".to_string() } else { format!("W^{q}") };
            return match fold_in {
                FOLD_NONE => format!("{a}z^2 {op} {} + c", second.replace('W', "z")),
                _ => format!("{a}W^2 {op} {second} + c, W = |x| + i|y|"),
            };
        }
        if let Some((pre, a, b)) = self.factors() {
            let power = |w: &str, n: u32| if n == 1 { w.to_string() } else { format!("{w}^{n}") };
            return if pre == 1 {
                format!("{} {} + c", power("z", a), power("(|x| + i|y|)", b))
            } else {
                format!("{} {} + c, u = z^{pre}", power("u", a), power("(|Re u| + i|Im u|)", b))
            };
        }
        let (fold_in, _, fold_out, sign) = self.shape(p);
        let base = match fold_in {
            FOLD_RE => "(|x| + iy)",
            FOLD_IM => "(x + i|y|)",
            FOLD_BOTH => "(|x| + i|y|)",
            _ => "z",
        };
        let w = format!("{base}^{p}");
        let re = if fold_out & FOLD_RE != 0 { "|Re w|" } else { "Re w" };
        let im = match (fold_out & FOLD_IM != 0, fold_out & IM_BY_X != 0, fold_out & IM_BY_Y != 0) {
            (false, ..) => "Im w",
            (true, false, false) => "|Im w|",
            (true, true, false) => "sgn(x) |Im w|",
            (true, false, true) => "sgn(y) |Im w|",
            (true, true, true) => "sgn(xy) |Im w|",
        };
        let (re, op) = match sign {
            SIGN_RE => (format!("-{re}"), "+"),
            SIGN_IM => (re.to_string(), "-"),
            _ => (re.to_string(), "+"),
        };
        if fold_out == FOLD_NONE && sign == SIGN_NONE {
            format!("{w} + c")
        } else if fold_out == FOLD_NONE && sign == SIGN_IM {
            format!("conj({w}) + c")
        } else {
            format!("{re} {op} i {im} + c, w = {w}")
        }
    }

    /// Every name, for messages.
    pub fn names() -> String {
        KINDS.iter().map(|k| k.name).collect::<Vec<_>>().join(", ")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_and_kf_types_are_unique() {
        for (i, a) in KINDS.iter().enumerate() {
            for b in &KINDS[i + 1..] {
                assert_ne!(a.name, b.name);
                assert_ne!(a.kf_type, b.kf_type);
                assert_ne!(a.kind, b.kind);
            }
            assert_eq!(Kind::from_name(a.name), Some(a.kind));
            assert_eq!(Kind::from_kf_type(a.kf_type), Some(a.kind));
        }
        assert_eq!(Kind::from_kf_type(52), None, "the general quadratics are refused");
        assert_eq!(Kind::from_kf_type(41), Some(Kind::HpdzBuffalo));
        assert_eq!(Kind::from_kf_type(44), Some(Kind::RedshiftRider3));
        assert!(Kind::RedshiftRider1.takes_a() && !Kind::RedshiftRider3.takes_a() && !Kind::Mandelbrot.takes_a());
        assert_eq!(Kind::from_kf_type(33), Some(Kind::SimonBrot4));
    }

    #[test]
    fn definitions_in_words() {
        assert_eq!(Kind::Mandelbrot.definition(3), "z^3 + c");
        assert_eq!(Kind::BurningShip.definition(2), "(|x| + i|y|)^2 + c");
        assert_eq!(Kind::Mandelbar.definition(2), "conj(z^2) + c");
        assert_eq!(Kind::Mandelbar.definition(3), "-Re w + i Im w + c, w = z^3");
        assert_eq!(Kind::PerpendicularCeltic.definition(2), "|Re w| - i Im w + c, w = (|x| + iy)^2");
        assert_eq!(Kind::CubicQuasiPerpendicular.definition(3), "Re w - i sgn(y) |Im w| + c, w = (|x| + iy)^3");
        assert_eq!(Kind::CelticFalseQuasiHeart4.definition(4), "|Re w| + i sgn(xy) |Im w| + c, w = z^4");
        assert_eq!(Kind::Mothbrot2x3.definition(5), "z^2 (|x| + i|y|)^3 + c");
        assert_eq!(Kind::Mothbrot1x1.definition(2), "z (|x| + i|y|) + c");
        assert_eq!(Kind::SimonBrot2.definition(4), "u (|Re u| + i|Im u|) + c, u = z^2");
        assert_eq!(Kind::RedshiftRider2.definition(3), "a z^2 - z^3 + c");
        assert_eq!(Kind::RedshiftRider3.definition(3), "2 z^2 - z^3 + c");
        assert_eq!(Kind::HpdzBuffalo.definition(2), "W^2 - W + c, W = |x| + i|y|");
    }
}
