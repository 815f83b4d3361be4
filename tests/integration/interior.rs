//! Interior detection in the perturbation engines against direct big-float iteration.
//!
//! Views holding interior are rendered by the real path with detection on, off and by
//! default, on every instruction set this CPU has: N must be the same plane in all of them
//! (detection stops interior samples early and changes nothing else), the statistics must
//! show samples stopped early where detection runs, and sampled pixels must have the N of
//! `reference` (astro-float, exact pixel coordinates, every iteration up to the limit).

use std::sync::Mutex;
use std::sync::atomic::AtomicBool;

use deepfield::field::ChannelSet;
use deepfield::formula::end::INTERIOR;
use deepfield::orbit::interior::Decision;
use deepfield::render::{self, Options, Stats};
use deepfield::simd_level::SimdLevel;
use rayon::prelude::*;

use super::reference;
use super::util::{Lcg, scene};

/// The nucleus of a period-1429 minibrot (size 1.6e-102) found by `deepfield find
/// scenes/locations/all-seeing-eye.toml --zoom 1e70`; the shipped scenes/minibrot-e102.toml.
const EYE_MINIBROT: [&str; 2] = [
    "-0.83031842675693053553109980802050591726924580592100415017586803599827560339120465373468510811787516730515186454892834980632246054605795",
    "0.23612476396680780363307856325882633547132442124365456398110558858530832926040168389957117374824216611986058042279006600832794659929318",
];

/// A view to render: scene text without `[render]` (the test adds it).
struct View {
    center: [&'static str; 2],
    radius: &'static str,
    julia: Option<[&'static str; 2]>,
    max_iter: u32,
    size: (u32, u32),
    engine: &'static str,
}

impl View {
    /// A 48×36 view through the f64 perturbation engine to 5000 iterations.
    fn small(center: [&'static str; 2], radius: &'static str, julia: Option<[&'static str; 2]>) -> View {
        View { center, radius, julia, max_iter: 5000, size: (48, 36), engine: "perturb-f64" }
    }

    fn text(&self, detection: Option<bool>) -> String {
        let formula = match self.julia {
            Some([re, im]) => format!("[formula]\nkind = \"julia\"\nc = [\"{re}\", \"{im}\"]\n"),
            None => String::new(),
        };
        let detection = detection.map_or(String::new(), |d| format!("interior_detection = {d}\n"));
        format!(
            "version = 1\n{formula}[view]\ncenter = [\"{}\", \"{}\"]\nradius = \"{}\"\nwidth = {}\nheight = {}\n[iteration]\nmax = {}\n[render]\nengine = \"{}\"\n{detection}",
            self.center[0], self.center[1], self.radius, self.size.0, self.size.1, self.max_iter, self.engine
        )
    }
}

/// Renders `text` with `simd` through the real render path: the N plane and the statistics.
fn render_n(text: &str, simd: SimdLevel) -> (Vec<u32>, Stats) {
    let s = scene(text);
    let n = Mutex::new(Vec::new());
    let options = Options { simd, exr_channels: ChannelSet::default(), ..Options::default() };
    let plan = render::engine::plan(&s).expect("an engine");
    let stats = render::render(&s, &plan, options, &AtomicBool::new(false), &|_| {}, &|_| Ok(()), |strip, ()| {
        n.lock().unwrap().extend_from_slice(&strip.planes.n);
        Ok(())
    })
    .expect("render");
    (n.into_inner().unwrap(), stats)
}

/// Renders `v` with detection on, off and by default on every instruction set: one N
/// plane for all. Returns it with the samples detection stopped early and, of those, the
/// samples Newton's test found (the same on every instruction set), and what the default
/// decided.
fn render_all_ways(v: &View) -> (Vec<u32>, (u64, u64), Decision) {
    let mut plane: Option<Vec<u32>> = None;
    let (mut stopped, mut default) = (None, None);
    for detection in [Some(true), Some(false), None] {
        let mut counted = None;
        for simd in SimdLevel::usable() {
            let (n, stats) = render_n(&v.text(detection), simd);
            let deep = stats.deep.expect("the perturbation engine ran");
            let what = format!("{}, detection {detection:?}, {simd}", v.radius);
            match &plane {
                None => plane = Some(n),
                Some(p) => {
                    let differing = p.iter().zip(&n).filter(|(a, b)| a != b).count();
                    assert_eq!(differing, 0, "{what}: N differs on {differing} samples");
                }
            }
            let count = (deep.interior_samples, deep.interior_newton_samples);
            assert_eq!(*counted.get_or_insert(count), count, "{what}: samples stopped");
            match detection {
                Some(true) => {
                    assert_eq!(deep.interior_detection, Decision::On, "{what}");
                    stopped = Some(count);
                }
                Some(false) => {
                    assert_eq!(deep.interior_detection, Decision::Off, "{what}");
                    assert_eq!(deep.interior_samples, 0, "{what}");
                }
                None => default = Some(deep.interior_detection),
            }
        }
    }
    (plane.unwrap_or_default(), stopped.unwrap_or_default(), default.expect("rendered"))
}

/// N at `samples` random pixels against direct big-float iteration (orbits passing within
/// 1e-9 of the escape circle excepted), the pixels iterated in parallel; returns how many
/// sampled pixels are interior.
fn against_big_floats(v: &View, n: &[u32], samples: u32) -> u32 {
    let s = scene(&v.text(None));
    let bits = (-s.log10_spacing() * std::f64::consts::LOG2_10) as usize + 160;
    let julia = v.julia.map(|c| [reference::parse(c[0], bits), reference::parse(c[1], bits)]);
    let mut rng = Lcg(0x1e7e ^ v.max_iter as u64);
    let pixels: Vec<(u32, u32)> = (0..samples).map(|_| (rng.below(v.size.0), rng.below(v.size.1))).collect();
    let truths: Vec<reference::Truth> = pixels
        .par_iter()
        .map(|&(i, j)| {
            let p = reference::pixel(v.center, v.radius, v.size.0, v.size.1, i, j, bits);
            reference::orbit(&p, julia.as_ref(), v.max_iter, s.escape_radius, bits)
        })
        .collect();
    let mut interior = 0;
    for (&(i, j), t) in pixels.iter().zip(&truths) {
        if t.near_circle {
            continue;
        }
        let got = n[(j * v.size.0 + i) as usize];
        assert_eq!((got != INTERIOR).then_some(got), t.n, "{}: pixel ({i}, {j})", v.radius);
        interior += t.n.is_none() as u32;
    }
    interior
}

/// A view centred on the period-1429 minibrot at zoom 1e102, about half of it interior, to
/// 10^6 iterations (700 periods): the interior samples detection finds stop early (most by
/// Newton's test, the reference being one period of the nucleus), the others run to the
/// limit, and every sampled pixel has the big-float N (each interior one iterated 10^6
/// times in 500-bit floats). The default turns detection on (the view is centred on a
/// nucleus whose minibrot spans many samples).
#[test]
fn minibrot_centred_view_at_1e102() {
    let v = View {
        center: EYE_MINIBROT,
        radius: "1.2e-102",
        julia: None,
        max_iter: 1_000_000,
        size: (40, 30),
        engine: "auto",
    };
    let (n, (stopped, newton), default) = render_all_ways(&v);
    let interior = n.iter().filter(|&&x| x == INTERIOR).count();
    assert!(interior > 200 && interior < 1000, "{interior} interior samples of 1200");
    assert!(stopped > interior as u64 * 9 / 10, "only {stopped} of {interior} interior samples stopped early");
    assert!(newton > stopped / 2, "only {newton} of {stopped} by Newton's test");
    assert_eq!(default, Decision::AutoOn);
    let sampled = against_big_floats(&v, &n, 16);
    eprintln!(
        "minibrot 1e102: {interior} interior samples, {stopped} stopped early ({newton} by Newton's test); {sampled} of 16 sampled interior"
    );
    assert!(sampled >= 4, "the sample must hold interior pixels ({sampled})");
}

/// Shallow views with interior through the perturbation engine, against big floats: the
/// Mandelbrot set about the period-2 bulb and seahorse valley (cardioid, bulbs, a
/// minibrot), and the whole Douady rabbit (a Julia set whose parameter is inside the
/// period-3 bulb), where samples inside must be found and outside never.
#[test]
fn shallow_views_with_interior() {
    let mandelbrot = View::small(["-0.9", "0.15"], "0.35", None);
    let rabbit = View::small(["0", "0"], "1.3", Some(["-0.12", "0.75"]));
    for v in [mandelbrot, rabbit] {
        let (n, (stopped, newton), _) = render_all_ways(&v);
        assert_eq!(newton, 0, "{}: Newton's test needs a nucleus's reference", v.radius);
        let interior = n.iter().filter(|&&x| x == INTERIOR).count() as u64;
        assert!(stopped > interior * 9 / 10, "{}: {stopped} of {interior} interior samples stopped early", v.radius);
        let sampled = against_big_floats(&v, &n, 80);
        eprintln!(
            "{}: {interior} interior samples, {stopped} stopped early; {sampled} of 80 sampled interior",
            v.radius
        );
        assert!(sampled >= 6, "{}: the sample must hold interior pixels ({sampled})", v.radius);
    }
}

/// A Julia set whose parameter is outside the Mandelbrot set has no interior, and samples
/// near a preimage of 0 contract on their way out: detection stays off even when turned on.
#[test]
fn julia_set_without_interior_is_not_checked() {
    let v = View::small(["0", "0"], "1.5", Some(["0.28", "0.008"]));
    let (_, stats) = render_n(&v.text(Some(true)), SimdLevel::detect());
    let deep = stats.deep.expect("perturbation");
    assert_eq!(deep.interior_detection, Decision::JuliaNoInterior);
    assert_eq!(deep.interior_samples, 0);
}
