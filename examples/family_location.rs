//! Deep locations for any formula family, by "Newton zoom": the centre (in full precision),
//! zoom and an iteration limit for a view deeper than asked, near a miniship/minibrot.
//!
//! `cargo run --release --example family_location -- FORMULA DEPTH [--power P] [--seed S]
//! [--stages K] [--max-escape E]`
//!
//! e.g. `-- burning-ship 100`, `-- mandelbar 50`, `-- mandelbrot 50 --power 3`.
//!
//! `--max-escape` (default 20000) caps the descents' iteration limit. `--stages 1` is what
//! found the shipped scenes; more stages (the default is 3) do not work yet: the descent
//! from a mini's surroundings starts at a limit of 200, below those escape counts, and
//! loses the boundary every time (it needs a starting limit near the mini's).
//!
//! Method. Each stage starts from a view (centre, radius): a boundary descent
//! ([`deepfield::compare::boundary::descend`], sampling only) follows the set's boundary
//! down to a depth half-way (in log scale) between that view and the stage's goal, and
//! there the lowest-period periodic point in the view is found: the orbit of the view's
//! centre is iterated in big floats with the real 2×2 Jacobian J_n = dz_n/dc of the map
//! (folds and all), and the first n whose Newton step J_n⁻¹ z_n is shorter than the view's
//! radius (the image of the view may hold a zero of z_n) is tried with Newton's method on
//! z_n(c) = 0; the first that settles inside the view is the nucleus of a mini of that
//! period. A mini found this way is about as much deeper than the view as the view is
//! deeper than where it started ("depth doubling"), so the next stage starts from the
//! mini's surroundings (a view 30 of its sizes wide) and goes for a higher period, until the
//! goal (DEPTH and 3 decades, so that the mini is a small part of the last view; taken at
//! 0.9 decades) is passed.
//! The mini's size is estimated from its cycle as 1/sqrt(|det L| |det D|), L the product
//! of the map's Jacobians along the cycle (z_1 .. z_(p-1)) and D = dz_p/dc, which for
//! z² + c is the usual 1/(|β| |λ|²).
//!
//! The last view is centred on the last nucleus at zoom 2·10^⌈DEPTH⌉ (the image height
//! spans 4/zoom, as in deepfield's scenes). A coarse grid of escape counts over an
//! 800×600 frame (16×12 samples in big floats, limit 8 periods within 50000..200000) prints
//! the counts' spread and the share that does not escape within 4× the largest count seen
//! (at least 20 periods), a limit to give the scene.
#![allow(clippy::print_stdout)] // printing the location is the point

use deepfield::compare::boundary::{descend, escape_time, periodic_point, shifted};
use deepfield::compare::views::Rng;
use deepfield::formula::{Cycle, Formula, Stepper};
use deepfield::num::FloatExp;
use deepfield::num::bigcomplex::BigC;

/// |z|² beyond which an orbit has escaped.
const ESCAPE2: f64 = 16.0;

/// log10 of 1 / `radius`.
fn depth(radius: FloatExp) -> f64 {
    -radius.log2() * std::f64::consts::LOG10_2
}

/// A 2×2 real matrix as `m · 2^e`, renormalised so `m` stays within f64's range.
#[derive(Clone, Copy)]
struct Scaled {
    m: [[f64; 2]; 2],
    e: i32,
}

impl Scaled {
    const ZERO: Scaled = Scaled { m: [[0.0; 2]; 2], e: 0 };

    /// a · self + I (the Jacobian's step J ← Df J + I), or a · self without the identity.
    fn step(self, a: [[f64; 2]; 2], plus_one: bool) -> Scaled {
        let j = self.m;
        let one = if plus_one { 2f64.powi(-self.e) } else { 0.0 };
        let mut m = [
            [a[0][0] * j[0][0] + a[0][1] * j[1][0] + one, a[0][0] * j[0][1] + a[0][1] * j[1][1]],
            [a[1][0] * j[0][0] + a[1][1] * j[1][0], a[1][0] * j[0][1] + a[1][1] * j[1][1] + one],
        ];
        let mut e = self.e;
        let big = m.iter().flatten().fold(0.0f64, |b, v| b.max(v.abs()));
        if big > 2f64.powi(200) || (big < 2f64.powi(-200) && big > 0.0) {
            let k = big.log2().round() as i32;
            m = m.map(|r| r.map(|v| v * 2f64.powi(-k)));
            e += k;
        }
        Scaled { m, e }
    }

    /// self⁻¹ v, or None where singular.
    fn solve(self, v: [FloatExp; 2]) -> Option<[FloatExp; 2]> {
        let j = self.m;
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let k = 1.0 / det;
        let x = (v[0].mul_f64(j[1][1]) - v[1].mul_f64(j[0][1])).mul_f64(k).ldexp(-self.e);
        let y = (v[1].mul_f64(j[0][0]) - v[0].mul_f64(j[1][0])).mul_f64(k).ldexp(-self.e);
        Some([x, y])
    }

    /// log2 |det self|.
    fn log2_det(self) -> f64 {
        let j = self.m;
        (j[0][0] * j[1][1] - j[0][1] * j[1][0]).abs().log2() + 2.0 * self.e as f64
    }
}

fn f64s(z: &BigC) -> [f64; 2] {
    z.to_fe().map(FloatExp::to_f64)
}

fn norm(v: [FloatExp; 2]) -> FloatExp {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

/// Newton's method for a zero of z_p(c) from `from`, given up when it leaves 4 `radius`
/// of it or does not settle in 80 steps.
fn newton(s: Cycle, from: &BigC, radius: FloatExp, period: u32) -> Option<BigC> {
    let mut c = from.clone();
    let small = radius.mul_f64(1e-12);
    for _ in 0..80 {
        let mut z = BigC::zero(c.bits);
        let mut j = Scaled::ZERO;
        for n in 0..period {
            j = j.step(s.jacobian(n, f64s(&z)), true);
            z = s.apply_big(n, &z).add(&c);
        }
        let d = j.solve(z.to_fe())?;
        c = shifted(&c, [-d[0], -d[1]]);
        if norm(c.sub(from).to_fe()) > radius.mul_f64(4.0) {
            return None;
        }
        if norm(d) < small {
            return Some(c);
        }
    }
    None
}

/// The nucleus of the lowest period within `radius` of `center`, with its period.
/// Newton's method is tried at the first 6 such periods at most.
fn lowest_period(s: Cycle, center: &BigC, radius: FloatExp, limit: u32) -> Option<(BigC, u32)> {
    let mut z = BigC::zero(center.bits);
    let mut j = Scaled::ZERO;
    let mut tries = 0;
    for n in 0..limit {
        j = j.step(s.jacobian(n, f64s(&z)), true);
        z = s.apply_big(n, &z).add(center);
        let fe = z.to_fe();
        if (fe[0] * fe[0] + fe[1] * fe[1]).to_f64() > ESCAPE2 {
            return None;
        }
        let Some(d) = j.solve(fe) else { continue };
        if norm(d) > radius {
            continue;
        }
        tries += 1;
        if tries > 6 {
            return None;
        }
        if let Some(c) = newton(s, center, radius, n + 1)
            && norm(c.sub(center).to_fe()) <= radius.mul_f64(1.5)
        {
            return Some((c, n + 1));
        }
    }
    None
}

/// The size of the mini whose nucleus is `c` (period `p`): 1/sqrt(|det L| |det D|).
fn mini_size(s: Cycle, c: &BigC, p: u32) -> FloatExp {
    let mut z = BigC::zero(c.bits);
    let mut d = Scaled::ZERO;
    let mut log2_l = 0.0;
    for n in 0..p {
        let a = s.jacobian(n, f64s(&z));
        if n > 0 {
            log2_l += (a[0][0] * a[1][1] - a[0][1] * a[1][0]).abs().log2();
        }
        d = d.step(a, true);
        z = s.apply_big(n, &z).add(c);
    }
    FloatExp::from(1.0).ldexp(-((log2_l + d.log2_det()) / 2.0).round() as i32)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let usage = "usage: family_location FORMULA DEPTH [--power P] [--seed S] [--stages K] [--max-escape E]";
    let (Some(name), Some(target)) = (args.first(), args.get(1).and_then(|d| d.parse::<f64>().ok())) else {
        eprintln!("{usage}");
        std::process::exit(2);
    };
    let opt = |flag: &str| args.iter().position(|a| a == flag).and_then(|i| args.get(i + 1));
    let power = opt("--power").map(|p| p.parse::<u32>().expect("--power: an integer"));
    let seed = opt("--seed").map_or(1, |s| s.parse::<u64>().expect("--seed: an integer"));
    let stages = opt("--stages").map_or(3, |s| s.parse::<u32>().expect("--stages: an integer"));
    let max_escape = opt("--max-escape").map_or(20_000, |s| s.parse::<u32>().expect("--max-escape: an integer"));
    let formula = Formula::parse(name, power).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2);
    });
    let s = Cycle(formula);
    let mut rng = Rng::new(seed);
    // The last view has zoom 2·10^⌈DEPTH⌉ (half-height 10^-⌈DEPTH⌉); the mini is aimed 3
    // decades deeper, and taken when it is at least 0.9 deeper (its radius at most 1/8 of
    // the view's half-height).
    let goal = target.ceil() + 3.0;
    let (mut center, mut radius) = (BigC::zero(64), FloatExp::from(2.5));
    let mut stage = 1;
    let (nucleus, period, size) = loop {
        let d0 = depth(radius);
        let stage_goal = if stage >= stages { goal } else { d0 + (goal - d0) / (stages - stage + 1) as f64 };
        let d1 = (d0 + stage_goal) / 2.0;
        // A descent may lose the boundary (a random step into a cell that the next grid
        // finds all inside or all outside), end beside a component where escapes are slow
        // (a parabolic boundary, no mini nearby), or end where Newton's method does not
        // settle: up to 40 tries, each with new random steps.
        let first = stage == 1;
        let found = (0..40).find_map(|_| {
            // The first stage starts from a jittered view of the whole set (an 8×8 grid
            // over [-2.5, 2.5]² can miss a small set such as the tricorn's entirely).
            let (c, r) = if first {
                let c = BigC::from_f64(rng.uniform(-0.5, 0.5), rng.uniform(-0.5, 0.5), 64);
                (c, FloatExp::from(rng.uniform(0.8, 2.0)))
            } else {
                (center.clone(), radius)
            };
            let found = descend(&mut rng, formula, None, c, r, d1, max_escape)?;
            eprintln!("  boundary at 1e{:.1}, escapes up to {}", depth(found.radius), found.max_n);
            let bits = deepfield::num::bigfloat::precision_for(-(2.0 * d1 - d0 + 20.0));
            let at = found.center.with_bits(bits);
            let (c, p) = lowest_period(s, &at, found.radius, 4 * found.max_n + 1000)
                .or_else(|| periodic_point(formula, &at, found.radius, 4 * found.max_n + 1000))?;
            Some((found, c, p))
        });
        let Some((found, c, p)) = found else {
            eprintln!("stage {stage}: no mini found on the way to 1e{d1:.1} in 40 tries; try another --seed");
            std::process::exit(1);
        };
        let size = mini_size(s, &c, p);
        println!(
            "stage {stage}: boundary at 1e{:.1} (escapes up to {}), period {p}, mini size 1e-{:.1}",
            depth(found.radius),
            found.max_n,
            depth(size)
        );
        if depth(size) >= target.ceil() + 0.9 {
            break (c, p, size);
        }
        (center, radius) = (c, size.mul_f64(30.0));
        stage += 1;
    };
    let zoom = target.ceil();
    // The frame: height 4/zoom, 800×600, sampled on a 32×24 grid.
    let half_h = FloatExp::exp10(-zoom);
    let [re, im] = nucleus.to_decimals(0);
    println!("formula {formula}, period {period}, mini size 1e-{:.1}", depth(size));
    println!("center = [\"{}\", \"{}\"]", re.text(), im.text());
    println!("zoom = \"2e{zoom}\"");
    let limit = (8 * period).clamp(50_000, 200_000);
    let (gw, gh) = (16usize, 12usize);
    let mut counts = Vec::new();
    for i in 0..gh {
        for k in 0..gw {
            let x = half_h.mul_f64((4.0 / 3.0) * (2.0 * (k as f64 + 0.5) / gw as f64 - 1.0));
            let y = half_h.mul_f64(2.0 * (i as f64 + 0.5) / gh as f64 - 1.0);
            counts.push(escape_time(formula, None, &shifted(&nucleus, [x, y]), limit, false));
        }
    }
    let mut esc: Vec<u32> = counts.iter().flatten().copied().collect();
    esc.sort_unstable();
    let max = esc.last().copied().unwrap_or(0);
    let suggested = (4 * max).max(20 * period);
    let inside = counts.iter().filter(|n| n.is_none_or(|n| n > suggested)).count();
    if let (Some(lo), Some(hi)) = (esc.first(), esc.last()) {
        println!(
            "escape counts on a {gw}x{gh} grid: {lo} .. {hi} (median {}), {} of {} not escaped within {limit}",
            esc[esc.len() / 2],
            counts.len() - esc.len(),
            counts.len()
        );
    }
    println!("iteration limit {suggested}: {inside} of {} grid samples interior", counts.len());
}
