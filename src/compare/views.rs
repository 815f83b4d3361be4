//! A seeded generator of deep views nobody tuned the engine to, for the deep-view fuzzer
//! ([`super::fuzz`]).
//!
//! Hand-picked test locations share the habits of whoever picked them; these are drawn at
//! random from the places deep zooms go: the neighbourhoods of minibrots of random period
//! (found by a descent of ball-method periods and Newton's method, [`crate::locate`]),
//! Misiurewicz points of random preperiod and period (self-similar at every depth, so any
//! zoom up to 1e2000 and beyond is cheap to reach exactly), views whose reference point lies
//! just outside a minibrot (the reference escapes before many of the samples), views whose
//! sample spacing straddles the line between f64 and FloatExp deltas (1e-280 .. 1e-320),
//! and Julia sets with c near the boundary of the Mandelbrot set, centred on a point of the
//! Julia set found by inverse iteration. The same seed gives the same views, on every
//! machine: everything is computed in big floats from a fixed pseudo-random sequence.
//!
//! Those kinds are z² + c's (its ball periods, Misiurewicz points and inverse iteration).
//! For any formula, including the non-quadratic families and hybrids, four more kinds come
//! from boundary descents ([`super::boundary`]): the boundary of the Mandelbrot-form set,
//! of a Julia set whose c is itself on that boundary, the neighbourhood of a periodic point
//! found by Newton's method from a descent's end (a minibrot, or a miniship), and the real
//! axis (centred exactly on it or just off it, where the Burning Ship's folds meet).

use std::fmt::Write as _;

use super::boundary;
use crate::formula::Formula;
use crate::locate::{Minibrot, misiurewicz, nucleus, period};
use crate::num::bigcomplex::BigC;
use crate::num::{Decimal, FloatExp};
use crate::scene::Scene;

/// The kinds of view the generator draws.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ViewKind {
    /// The decorations around a minibrot reached by a random descent (a few minibrot
    /// sizes away from its nucleus).
    Descent,
    /// A minibrot of random period, framed at a random scale about its nucleus.
    Minibrot,
    /// A Misiurewicz point of random preperiod and period, at any depth.
    Misiurewicz,
    /// A view whose centre (the reference) lies just outside a minibrot that fills part of
    /// it: the reference escapes before the samples inside and near the minibrot.
    EarlyEscape,
    /// A Misiurewicz view whose sample spacing is between 1e-280 and 1e-320, where the
    /// engine changes from f64 to FloatExp deltas.
    FloatExpLine,
    /// A Julia set with c near the Mandelbrot set's boundary, centred on the Julia set.
    Julia,
    /// Any formula: a boundary descent of its Mandelbrot-form set.
    Boundary,
    /// Any formula: a boundary descent of its Julia set for a c found by a shallow descent.
    JuliaBoundary,
    /// Any formula: the neighbourhood of a periodic point (a minibrot or miniship) that
    /// Newton's method finds from a descent's end.
    Mini,
    /// Any formula: a descent along the real axis of its Mandelbrot form, the view centred
    /// on the axis or just off it.
    RealAxis,
}

impl ViewKind {
    /// Every kind.
    pub const ALL: [ViewKind; 10] = [
        ViewKind::Descent,
        ViewKind::Minibrot,
        ViewKind::Misiurewicz,
        ViewKind::EarlyEscape,
        ViewKind::FloatExpLine,
        ViewKind::Julia,
        ViewKind::Boundary,
        ViewKind::JuliaBoundary,
        ViewKind::Mini,
        ViewKind::RealAxis,
    ];

    /// The kinds found by boundary descents, which work for any formula.
    pub const ANY_FORMULA: [ViewKind; 4] =
        [ViewKind::Boundary, ViewKind::JuliaBoundary, ViewKind::Mini, ViewKind::RealAxis];

    /// True for the kinds that work for any formula (the others are z² + c's).
    pub fn any_formula(self) -> bool {
        Self::ANY_FORMULA.contains(&self)
    }

    /// The kinds that can be drawn for `formula`.
    pub fn for_formula(formula: Formula) -> Vec<ViewKind> {
        Self::ALL.into_iter().filter(|k| formula.is_quadratic() || k.any_formula()).collect()
    }

    /// A short name for file names and reports.
    pub fn name(self) -> &'static str {
        match self {
            ViewKind::Descent => "descent",
            ViewKind::Minibrot => "minibrot",
            ViewKind::Misiurewicz => "misiurewicz",
            ViewKind::EarlyEscape => "early-escape",
            ViewKind::FloatExpLine => "floatexp-line",
            ViewKind::Julia => "julia",
            ViewKind::Boundary => "boundary",
            ViewKind::JuliaBoundary => "julia-boundary",
            ViewKind::Mini => "mini",
            ViewKind::RealAxis => "real-axis",
        }
    }
}

/// What to draw: a kind, a depth and limits.
#[derive(Debug, Clone, Copy)]
pub struct ViewSpec {
    /// The kind of view.
    pub kind: ViewKind,
    /// log10 of the zoom to aim for (the kinds found by descent land near it).
    pub log10_zoom: f64,
    /// The largest iteration limit a view may get.
    pub max_iter: u32,
    /// Image size.
    pub width: u32,
    /// Image size.
    pub height: u32,
    /// The formula iterated.
    pub formula: Formula,
}

/// A generated view: the scene, its text (to write out and reproduce) and how it was made.
#[derive(Debug, Clone)]
pub struct GeneratedView {
    /// A name: kind, seed and draw.
    pub name: String,
    /// The scene file's text.
    pub toml: String,
    /// The validated scene.
    pub scene: Scene,
    /// The formula the view is of (until scenes state one, it travels beside the scene).
    pub formula: Formula,
}

/// A small deterministic pseudo-random sequence (SplitMix64).
#[derive(Debug, Clone)]
pub struct Rng(u64);

impl Rng {
    /// The sequence of `seed`.
    pub fn new(seed: u64) -> Rng {
        Rng(seed ^ 0x5eed_de9f_1e1d_0000)
    }

    /// The next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    /// Uniform in [a, b).
    pub fn uniform(&mut self, a: f64, b: f64) -> f64 {
        a + (b - a) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }

    /// Uniform integer in [a, b].
    pub fn int(&mut self, a: u32, b: u32) -> u32 {
        a + (self.next_u64() % (b - a + 1) as u64) as u32
    }
}

/// Bits that place a point exactly at zoom 10^log10_zoom, with a margin (what a view's
/// reference orbit gets).
fn bits_for(log10_zoom: f64) -> u64 {
    crate::num::bigfloat::precision_for(-log10_zoom)
}

/// A point at distance `dist` from `p` in direction `angle`, at `p`'s precision.
fn offset(p: &BigC, dist: FloatExp, angle: f64) -> BigC {
    let d = |x: FloatExp| {
        let e = x.exponent();
        BigC::from_f64(x.mantissa(), 0.0, p.bits).ldexp(e).re
    };
    let dx = d(dist.mul_f64(angle.cos()));
    let dy = d(dist.mul_f64(angle.sin()));
    p.add(&BigC { re: dx, im: dy, bits: p.bits })
}

/// A Misiurewicz point of random preperiod (2..=10) and period (1..=4) at low precision:
/// Newton's method from random starts until one converges to a point with preperiod >= 1.
fn random_misiurewicz(rng: &mut Rng) -> Option<(BigC, u32, u32)> {
    for _ in 0..200 {
        let (k, p) = (rng.int(2, 10), rng.int(1, 4));
        let start = BigC::from_f64(rng.uniform(-2.0, 0.5), rng.uniform(-1.2, 1.2), 128);
        let Some(c) = misiurewicz::newton(&start, k, p, 60) else { continue };
        if let Some((k, p)) = misiurewicz::orbit_type(&c, 12, 8)
            && k >= 1
        {
            return Some((c, k, p));
        }
    }
    None
}

/// The multiplier of the cycle a Misiurewicz point's orbit lands on: |prod 2 z_j| over one
/// period from z_k (> 1: the cycle repels).
fn cycle_multiplier(c: &BigC, k: u32, p: u32) -> f64 {
    let mut z = BigC::zero(c.bits.min(256));
    let c = c.with_bits(c.bits.min(256));
    let mut log2 = 0.0;
    for n in 1..=k + p {
        z = z.square().add(&c);
        if n > k {
            log2 += (z.abs().ldexp(1)).log2();
        }
    }
    log2.exp2()
}

/// A minibrot reached by a random descent: from a random Misiurewicz point, the ball
/// method's period near a point, Newton's method to its nucleus, then a point a few sizes
/// away and again, until the minibrot is at least as small as 10^-`log10_zoom` (or the
/// periods pass `max_period`, or a step finds no period or no nucleus: then the deepest
/// minibrot reached, so minibrot views come out at depths up to the one asked; in practice
/// descents often stall between 1e40 and 1e60, where the ball method's period and Newton's
/// basin stop agreeing).
fn descend(rng: &mut Rng, log10_zoom: f64, max_period: u32) -> Option<Minibrot> {
    let (start, _, _) = random_misiurewicz(rng)?;
    let mut point = offset(&start, FloatExp::from(rng.uniform(1e-4, 1e-2)), rng.uniform(0.0, std::f64::consts::TAU));
    let mut radius = FloatExp::from(rng.uniform(1e-5, 1e-3));
    let mut found: Option<Minibrot> = None;
    for _ in 0..40 {
        let bits = bits_for(-radius.log2() * std::f64::consts::LOG10_2);
        let here = point.with_bits(bits);
        // A step that finds nothing ends the descent where it is: the deepest minibrot so
        // far still makes a view nobody tuned to, only shallower than asked.
        let Some(p) = period::ball_period(crate::formula::Formula::default(), &here, radius, max_period) else { break };
        let Some(m) = nucleus::minibrot(&here, p) else { break };
        let depth = -m.size.log2() * std::f64::consts::LOG10_2;
        if depth >= log10_zoom - 1.0 {
            return Some(m);
        }
        // Into the minibrot's neighbourhood, clear of the minibrot itself: the embedded
        // copies of its Julia set there hold minibrots of higher period. (A disc that still
        // reaches the minibrot finds it again; then the next try goes further out.)
        let m = match found {
            Some(f) if f.period == m.period && f.size == m.size => f,
            _ => m,
        };
        let bits = bits_for(depth + 10.0);
        let dist = m.size.mul_f64(rng.uniform(3.0, 30.0));
        point = offset(&m.nucleus.with_bits(bits), dist, rng.uniform(0.0, std::f64::consts::TAU));
        radius = dist.mul_f64(rng.uniform(0.01, 0.1));
        found = Some(m);
    }
    found
}

/// A point on the Julia set of `c`, to `bits`: inverse iteration z <- ±sqrt(z - c) with
/// random branches, which converges onto the Julia set (the inverse branches contract
/// towards it), for about twice as many steps as there are bits.
fn julia_point(rng: &mut Rng, c: &BigC, bits: u64) -> BigC {
    let c = c.with_bits(bits);
    let mut z = BigC::from_f64(0.5, 0.25, bits);
    for _ in 0..(2 * bits).max(200) {
        z = z.sub(&c).sqrt();
        if rng.next_u64() & 1 == 1 {
            z = z.neg();
        }
    }
    z
}

/// The scene text of a view.
fn scene_text(center: &BigC, radius: FloatExp, julia: Option<&[Decimal; 2]>, max_iter: u32, spec: &ViewSpec) -> String {
    let [re, im] = center.to_decimals(3);
    let mut t = String::from("version = 1\n");
    let kind =
        if spec.formula.is_quadratic() && julia.is_some() { "julia".to_string() } else { spec.formula.to_string() };
    if !spec.formula.is_quadratic() || julia.is_some() {
        let _ = writeln!(t, "[formula]\nkind = \"{kind}\"");
    }
    if let Some([cr, ci]) = julia {
        let _ = writeln!(t, "c = [\"{cr}\", \"{ci}\"]");
    }
    if let Some([ar, ai]) = spec.formula.a() {
        let _ = writeln!(t, "a = [{ar:?}, {ai:?}]");
    }
    let radius = crate::num::scientific(radius.log2() * std::f64::consts::LOG10_2, 9);
    let _ = writeln!(t, "[view]\ncenter = [\"{re}\", \"{im}\"]\nradius = \"{radius}\"");
    let _ = writeln!(t, "width = {}\nheight = {}\n[iteration]\nmax = {max_iter}", spec.width, spec.height);
    t
}

/// Draws one view of `spec` with draw number `draw` of generator `seed`; None when the
/// random draw found nothing usable (the caller draws again).
pub fn generate(seed: u64, draw: u32, spec: &ViewSpec) -> Option<GeneratedView> {
    if !spec.formula.is_quadratic() && !spec.kind.any_formula() {
        return None;
    }
    let mut rng = Rng::new(seed.wrapping_mul(0x1_0000_0001).wrapping_add(draw as u64));
    let tau = std::f64::consts::TAU;
    let depth = spec.log10_zoom;
    let (center, radius, julia, max_iter) = match spec.kind {
        ViewKind::Boundary | ViewKind::JuliaBoundary | ViewKind::Mini | ViewKind::RealAxis => {
            any_formula_view(&mut rng, spec)?
        }
        ViewKind::Misiurewicz | ViewKind::FloatExpLine => {
            let depth = if spec.kind == ViewKind::FloatExpLine {
                // Spacing 2 radius / height between 1e-320 and 1e-280.
                let spacing = rng.uniform(-320.0, -280.0);
                -(spacing + (spec.height as f64 / 2.0).log10())
            } else {
                depth
            };
            let (rough, k, p) = random_misiurewicz(&mut rng)?;
            let point = misiurewicz::newton(&rough.with_bits(bits_for(depth)), k, p, 60)?;
            let radius = FloatExp::exp10(-depth).mul_f64(2.0 * rng.uniform(0.5, 5.0));
            let center = offset(&point, radius.mul_f64(rng.uniform(0.0, 1.0)), rng.uniform(0.0, tau));
            // Samples escape after about depth / log10(multiplier) periods.
            let per = cycle_multiplier(&point, k, p).max(1.5).log10();
            let need = k as f64 + p as f64 * (depth + 2.0) / per;
            (center, radius, None, (2.0 * need + 1000.0) as u32)
        }
        ViewKind::Minibrot | ViewKind::Descent | ViewKind::EarlyEscape => {
            let m = descend(&mut rng, depth, 50_000)?;
            let s = m.size;
            let bits = bits_for(-s.log2() * std::f64::consts::LOG10_2 + 6.0);
            let nucleus = m.nucleus.with_bits(bits.max(m.nucleus.bits));
            let (dist, radius) = match spec.kind {
                ViewKind::Minibrot => (s.mul_f64(rng.uniform(0.0, 0.5)), s.mul_f64(rng.uniform(1.0, 30.0))),
                ViewKind::Descent => (s.mul_f64(rng.uniform(3.0, 30.0)), s.mul_f64(rng.uniform(1.0, 10.0))),
                _ => (s.mul_f64(rng.uniform(1.3, 3.0)), s.mul_f64(rng.uniform(2.0, 8.0))),
            };
            let center = offset(&nucleus, dist, rng.uniform(0.0, tau));
            let max_iter = (m.period as f64 * rng.uniform(20.0, 200.0)) as u32 + 1000;
            (center, radius, None, max_iter)
        }
        ViewKind::Julia => {
            // c near the boundary: a Misiurewicz point (a dendrite) moved a little, inside or
            // out.
            let (rough, _, _) = random_misiurewicz(&mut rng)?;
            let moved = offset(&rough, FloatExp::exp10(rng.uniform(-6.0, -2.0)), rng.uniform(0.0, tau));
            // c as the scene states it (20 decimals), and exactly that value in big floats.
            let c = moved.to_rationals().map(|r| Decimal::from_rational(&r, 20));
            let big = BigC::from_decimals(&c[0], &c[1], bits_for(depth));
            let z = julia_point(&mut rng, &big, bits_for(depth));
            let radius = FloatExp::exp10(-depth).mul_f64(2.0 * rng.uniform(0.5, 5.0));
            let center = offset(&z, radius.mul_f64(rng.uniform(0.0, 1.0)), rng.uniform(0.0, tau));
            (center, radius, Some(c), (3000.0 + 30.0 * depth) as u32)
        }
    };
    let max_iter = max_iter.clamp(100, spec.max_iter);
    let toml = scene_text(&center, radius, julia.as_ref(), max_iter, spec);
    let name = if spec.formula.is_quadratic() {
        format!("{}-{seed}-{draw}", spec.kind.name())
    } else {
        let formula = spec.formula.to_string().replace(['^', ','], "_");
        format!("{formula}-{}-{seed}-{draw}", spec.kind.name())
    };
    let file = Scene::parse_file(&name, &toml).ok()?;
    let no_bitmaps = |_: &std::path::Path| {
        Err(std::io::Error::new(std::io::ErrorKind::Unsupported, "generated views have no bitmap layers"))
    };
    let scene = Scene::validate(file, &name, &toml, std::path::Path::new("."), no_bitmaps).ok()?;
    Some(GeneratedView { name, toml, scene, formula: spec.formula })
}

/// A view of a kind that works for any formula: (centre, radius, Julia c, iteration limit).
fn any_formula_view(rng: &mut Rng, spec: &ViewSpec) -> Option<(BigC, FloatExp, Option<[Decimal; 2]>, u32)> {
    let (formula, depth, tau) = (spec.formula, spec.log10_zoom, std::f64::consts::TAU);
    // A descent from the whole plane (radius 2.5 about 0), and where the first grid holds
    // no point of the set (the Mandelbar's points near 0 fall between the samples of a grid
    // about 0), again from the view moved by half a grid step, whose grid has a sample on 0.
    let from_whole = |rng: &mut Rng, julia: Option<&BigC>, depth: f64, limit: u32| {
        let r = FloatExp::from(2.5);
        boundary::descend(rng, formula, julia, BigC::zero(64), r, depth, limit).or_else(|| {
            let half = 2.5 / (boundary::GRID - 1) as f64;
            boundary::descend(rng, formula, julia, BigC::from_f64(half, half, 64), r, depth, limit)
        })
    };
    let limit = |max_n: u32| max_n.saturating_mul(3).saturating_add(1000);
    // The descents' own limit, low enough that a view's (above) fits under the spec's: a
    // descent held at the spec's limit ends where the samples escape near it, and the
    // view, at that same limit, then has few or no escaping samples to score NF on.
    let cap = (spec.max_iter.saturating_sub(1000) / 3).max(100);
    Some(match spec.kind {
        ViewKind::Boundary => {
            let f = from_whole(rng, None, depth, cap)?;
            (f.center, f.radius, None, limit(f.max_n))
        }
        ViewKind::JuliaBoundary => {
            // c on the boundary of the Mandelbrot-form set, as the scene states it (20
            // decimals) and exactly that value in big floats; then the Julia set's boundary.
            let c_depth = rng.uniform(1.0, 4.0);
            let at = from_whole(rng, None, c_depth, 20_000)?;
            let julia_at = |rng: &mut Rng, p: &BigC| {
                let c = p.to_rationals().map(|r| Decimal::from_rational(&r, 20));
                let big = BigC::from_decimals(&c[0], &c[1], bits_for(depth));
                from_whole(rng, Some(&big), depth, cap).map(|f| (f, c))
            };
            // The descent ends anywhere in a cell the boundary crosses, so c may lie just
            // outside the set, where the Julia set is dust that a descent can lose (the
            // Mandelbar's, at these depths, every time): then again with c the first sample
            // of the last grid that did not escape.
            let (f, c) = julia_at(rng, &at.center).or_else(|| {
                let inside = boundary::inside_sample(formula, &at.center, at.radius, 20_000)?;
                julia_at(rng, &inside)
            })?;
            (f.center, f.radius, Some(c), limit(f.max_n))
        }
        ViewKind::Mini => {
            let f = from_whole(rng, None, depth, cap)?;
            let near = f.center.with_bits(bits_for(depth + 20.0));
            let (nucleus, period) = boundary::periodic_point(formula, &near, f.radius, limit(f.max_n))?;
            let radius = f.radius.mul_f64(rng.uniform(0.3, 3.0));
            let center = offset(&nucleus, radius.mul_f64(rng.uniform(0.0, 0.5)), rng.uniform(0.0, tau));
            (center, radius, None, limit(f.max_n).max(period.saturating_mul(50)))
        }
        _ => {
            let f = boundary::descend_real(rng, formula, depth, cap)?;
            // Half the views centred exactly on the axis, half just off it.
            let center = if rng.next_u64() & 1 == 0 {
                f.center
            } else {
                let up = f.radius.mul_f64(rng.uniform(1e-3, 0.5) * if rng.next_u64() & 1 == 0 { 1.0 } else { -1.0 });
                boundary::shifted(&f.center, [FloatExp::ZERO, up])
            };
            (center, f.radius, None, limit(f.max_n))
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_same_seed_gives_the_same_views() {
        for kind in [ViewKind::Misiurewicz, ViewKind::Julia, ViewKind::Minibrot] {
            let spec = ViewSpec {
                kind,
                log10_zoom: 30.0,
                max_iter: 100_000,
                width: 16,
                height: 12,
                formula: Formula::default(),
            };
            let a = (0..8).find_map(|d| generate(7, d, &spec)).expect("some draw works");
            let b = (0..8).find_map(|d| generate(7, d, &spec)).expect("some draw works");
            assert_eq!(a.toml, b.toml);
            assert_eq!(a.scene.width, 16);
        }
    }

    #[test]
    fn misiurewicz_views_reach_any_depth() {
        let spec = ViewSpec {
            kind: ViewKind::Misiurewicz,
            log10_zoom: 1500.0,
            max_iter: 1_000_000,
            width: 8,
            height: 6,
            formula: Formula::default(),
        };
        let v = (0..8).find_map(|d| generate(3, d, &spec)).expect("some draw works");
        let l = v.scene.log10_spacing();
        assert!((-1502.0..-1498.0).contains(&l), "spacing 1e{l}");
    }

    #[test]
    fn any_formula_kinds_give_the_same_views_for_the_same_seed() {
        let ship = Formula::parse("burning-ship", None).unwrap();
        for kind in ViewKind::ANY_FORMULA {
            let spec = ViewSpec { kind, log10_zoom: 7.0, max_iter: 20_000, width: 16, height: 12, formula: ship };
            let a = (0..8).find_map(|d| generate(3, d, &spec)).unwrap_or_else(|| panic!("no {kind:?} view"));
            let b = (0..8).find_map(|d| generate(3, d, &spec)).expect("the same draw");
            assert_eq!(a.toml, b.toml);
            assert_eq!(a.formula, ship);
            assert!(a.toml.contains("[formula]\nkind = \"burning-ship\""), "{}", a.toml);
            assert!(a.scene.log10_spacing() < -7.0, "{kind:?}: spacing 1e{}", a.scene.log10_spacing());
        }
        // z² + c's own kinds are not drawn for other formulas.
        let spec = ViewSpec {
            kind: ViewKind::Misiurewicz,
            log10_zoom: 7.0,
            max_iter: 1000,
            width: 8,
            height: 6,
            formula: ship,
        };
        assert!(generate(3, 0, &spec).is_none());
    }

    /// The Mandelbar's Julia sets: every c its descents gave lay just outside the set, whose
    /// Julia set is dust a descent loses; c moved to a sample of the set gives views.
    #[test]
    fn mandelbar_julia_sets_are_drawn() {
        let mandelbar = Formula::parse("mandelbar", None).unwrap();
        let spec = ViewSpec {
            kind: ViewKind::JuliaBoundary,
            log10_zoom: 8.0,
            max_iter: 20_000,
            width: 16,
            height: 12,
            formula: mandelbar,
        };
        for draw in 1..4 {
            let v = generate(3, draw, &spec).unwrap_or_else(|| panic!("draw {draw}: no view"));
            assert!(v.toml.contains("c = ["), "{}", v.toml);
            assert!(v.scene.log10_spacing() < -8.0, "draw {draw}: spacing 1e{}", v.scene.log10_spacing());
        }
    }

    #[test]
    fn real_axis_views_are_centred_on_or_near_the_axis() {
        let ship = Formula::parse("burning-ship", None).unwrap();
        let spec = ViewSpec {
            kind: ViewKind::RealAxis,
            log10_zoom: 6.0,
            max_iter: 20_000,
            width: 16,
            height: 12,
            formula: ship,
        };
        let views: Vec<GeneratedView> = (0..12).filter_map(|d| generate(5, d, &spec)).collect();
        let on_axis = views.iter().filter(|v| v.scene.center[1].is_zero()).count();
        assert!(on_axis > 0 && on_axis < views.len(), "{on_axis} of {} on the axis", views.len());
    }
}
