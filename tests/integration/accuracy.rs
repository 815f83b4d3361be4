//! The f64 kernels against direct arbitrary-precision iteration, on random pixels.
//!
//! Every sampled pixel is iterated twice: by the engine (the real render path: scene, SIMD
//! kernel, quantities) and by `reference` (astro-float, exact pixel coordinates). Pixels are
//! then judged by their conditioning. A pixel whose distance to the set is d pixels has an
//! orbit that amplifies any perturbation of its coordinates or of one rounding by about
//! 1/d: no f64 computation can pin its values down better than ~1e-16/d, so for d < 1e-6 px
//! the bound is scaled by the condition (1e-12 / d) instead of being flat. Orbits passing
//! within 1e-9 of the escape circle (N ill-conditioned) are excluded.

use std::sync::atomic::AtomicBool;

use deepfield::field::{self, ChannelSet};
use deepfield::formula::end::INTERIOR;

use super::reference;
use super::util::{Lcg, median, scene};

struct View {
    center: [&'static str; 2],
    radius: &'static str,
    julia: Option<[&'static str; 2]>,
    max_iter: u32,
    size: (u32, u32),
    samples: u32,
    bits: usize,
}

/// One compared pixel.
#[derive(Debug, Clone, Copy)]
pub struct Sample {
    /// True distance estimate in pixels (None: the reference says interior).
    pub d: Option<f64>,
    /// N agrees with the reference.
    pub n_ok: bool,
    /// |NF - NF_true| (when both escaped at the same n).
    pub nf_err: Option<f64>,
    /// |DE - DE_true| / |DE_true| for the vector (DEX, DEY): length and direction (same condition).
    pub de_err: Option<f64>,
}

fn measure(v: &View) -> Vec<Sample> {
    let formula = match v.julia {
        Some([re, im]) => format!("[formula]\nkind = \"julia\"\nc = [\"{re}\", \"{im}\"]\n"),
        None => String::new(),
    };
    let text = format!(
        "version = 1\n{formula}[view]\ncenter = [\"{}\", \"{}\"]\nradius = \"{}\"\nwidth = {}\nheight = {}\n[iteration]\nmax = {}\n",
        v.center[0], v.center[1], v.radius, v.size.0, v.size.1, v.max_iter
    );
    let s = scene(&text);
    let params = deepfield::render::field_params(&s, ChannelSet::default_exr());
    let spacing = params.grid.spacing();
    let ln_r = params.orbit.escape_radius.ln();
    let julia_c = v.julia.map(|c| [reference::parse(c[0], v.bits), reference::parse(c[1], v.bits)]);
    let mut rng = Lcg(0x5eed ^ v.max_iter as u64);
    let cancel = AtomicBool::new(false);
    let mut out = Vec::new();
    for _ in 0..v.samples {
        let (i, j) = (rng.below(v.size.0), rng.below(v.size.1));
        let strip = field::compute_strip(&params, j..j + 1, &cancel).unwrap().planes;
        let p = reference::pixel(v.center, v.radius, v.size.0, v.size.1, i, j, v.bits);
        let t = reference::orbit(&p, julia_c.as_ref(), v.max_iter, params.orbit.escape_radius, v.bits);
        if t.near_circle {
            continue;
        }
        out.push(judge(&t, &strip, i as usize, spacing, ln_r));
    }
    out
}

/// Compares sample `k` of `planes` with the reference's orbit. `spacing` converts the
/// reference's dz into pixels (1 when the reference already scaled it).
pub fn judge(t: &reference::Truth, planes: &field::Planes, k: usize, spacing: f64, ln_r: f64) -> Sample {
    let n = planes.n[k];
    let engine_n = (n != INTERIOR).then_some(n);
    let d = t.n.map(|_| {
        let abs_z = t.z[0].hypot(t.z[1]);
        abs_z * abs_z.ln() / t.dz[0].hypot(t.dz[1]) / spacing
    });
    let mut sample = Sample { d, n_ok: engine_n == t.n, nf_err: None, de_err: None };
    if sample.n_ok && n != INTERIOR {
        let lnz = 0.5 * (t.z[0] * t.z[0] + t.z[1] * t.z[1]).ln();
        let nf_true = (1.0 - (lnz / ln_r).log2()).clamp(0.0, 1.0);
        sample.nf_err = Some((planes.nf[k] as f64 - nf_true).abs());
        let d_true = d.expect("escaped");
        // The true vector: length d along conj(dz / z), i.e. along conj(dz) * z.
        let (wx, wy) = (t.dz[0] * t.z[0] + t.dz[1] * t.z[1], t.dz[0] * t.z[1] - t.dz[1] * t.z[0]);
        let w = wx.hypot(wy);
        let (tx, ty) = (d_true * wx / w, d_true * wy / w);
        let err = (planes.dex[k] as f64 - tx).hypot(planes.dey[k] as f64 - ty);
        sample.de_err = Some(err / d_true);
    }
    sample
}

pub fn summary(name: &str, s: &[Sample]) {
    let nf: Vec<f64> = s.iter().filter_map(|x| x.nf_err).collect();
    let de: Vec<f64> = s.iter().filter_map(|x| x.de_err).collect();
    let bad = s.iter().filter(|x| !x.n_ok).count();
    eprintln!(
        "{name}: {} pixels, N mismatch {:.3}%, NF median {:.2e} max {:.2e}, DE median {:.2e} max {:.2e}",
        s.len(),
        100.0 * bad as f64 / s.len() as f64,
        median(nf.clone()),
        nf.iter().cloned().fold(0.0, f64::max),
        median(de.clone()),
        de.iter().cloned().fold(0.0, f64::max)
    );
}

/// The error an f64 computation may have at a pixel d pixels from the set.
pub fn allowed(flat: f64, d: Option<f64>) -> f64 {
    match d {
        Some(d) if d < 1e-6 => flat.max(1e-12 / d),
        _ => flat,
    }
}

fn check_shallow(name: &str, v: View) {
    let s = measure(&v);
    summary(name, &s);
    assert!(s.len() as u32 >= v.samples * 9 / 10, "too few comparable pixels");
    for x in &s {
        assert!(x.n_ok, "{name}: N differs from the reference: {x:?}");
        if let (Some(e), Some(d)) = (x.nf_err, x.d) {
            assert!(e <= allowed(1e-6, Some(d)), "{name}: NF error {e} at d = {d} px");
        }
        if let (Some(e), Some(d)) = (x.de_err, x.d) {
            assert!(e <= allowed(1e-6, Some(d)), "{name}: distance error {e} at d = {d} px");
        }
    }
    let nf_median = median(s.iter().filter_map(|x| x.nf_err).collect());
    let de_median = median(s.iter().filter_map(|x| x.de_err).collect());
    assert!(nf_median <= 1e-6 && de_median <= 1e-6, "{name}: medians {nf_median} {de_median}");
}

#[test]
fn full_mandelbrot_set_matches_reference() {
    let v = View {
        center: ["-0.75", "0"],
        radius: "1.25",
        julia: None,
        max_iter: 1000,
        size: (640, 480),
        samples: 400,
        bits: 256,
    };
    check_shallow("full set", v);
}

#[test]
fn julia_sets_match_reference() {
    let v = View {
        center: ["0", "0"],
        radius: "1.2",
        julia: Some(["-0.8", "0.156"]),
        max_iter: 2000,
        size: (480, 480),
        samples: 300,
        bits: 256,
    };
    check_shallow("julia -0.8+0.156i", v);
    let v = View {
        center: ["0.1", "-0.2"],
        radius: "1.5",
        julia: Some(["0", "1"]),
        max_iter: 1000,
        size: (400, 300),
        samples: 300,
        bits: 256,
    };
    check_shallow("julia dendrite", v);
}

/// Seahorse valley at zoom 1e10, centred on the famous spiral (a dense, hard view).
/// Here f64 is the limit: a pixel's coordinates are rounded to 1/15000 of a pixel and
/// the orbits amplify that. Pixels well clear of the set (d >= 0.01 px, where no pixel
/// value should depend on 1e-4 px) must meet the plain-f64 figures; all pixels
/// together must keep the median distance error within them.
#[test]
fn seahorse_valley_at_zoom_1e10_is_within_f64_limits() {
    let v = View {
        center: ["-0.743643887037158704752191506114774", "0.131825904205311970493132056385139"],
        radius: "2e-10",
        julia: None,
        max_iter: 20000,
        size: (640, 480),
        samples: 1000,
        bits: 384,
    };
    let s = measure(&v);
    summary("zoom 1e10, all", &s);
    let clear: Vec<Sample> = s.iter().copied().filter(|x| x.d.is_none_or(|d| d >= 0.01)).collect();
    summary("zoom 1e10, d >= 0.01 px", &clear);
    assert!(clear.len() >= 500, "too few well-conditioned pixels: {}", clear.len());
    let mismatch = clear.iter().filter(|x| !x.n_ok).count() as f64 / clear.len() as f64;
    assert!(mismatch <= 0.0003, "N mismatch fraction {mismatch}");
    let nf_max = clear.iter().filter_map(|x| x.nf_err).fold(0.0, f64::max);
    assert!(nf_max <= 0.02, "NF error {nf_max}");
    let de_median = median(s.iter().filter_map(|x| x.de_err).collect());
    assert!(de_median <= 1e-5, "median distance error {de_median}");
}

/// A picture turned a quarter turn counter-clockwise is the unturned picture with pixel
/// (i, j) moved to (H - 1 - j, i) (a square image), and its distance vectors turn with it:
/// (x, y) becomes (-y, x). Not bit for bit: cos 90° is 6e-17 in f64, so the points differ
/// in the last bits.
#[test]
fn a_quarter_turn_turns_the_picture_and_its_distance_vectors() {
    let text = |rotate: &str| {
        format!(
            "version = 1\n[view]\ncenter = [\"-0.7436\", \"0.1318\"]\nradius = \"0.004\"\nwidth = 96\nheight = 96\n{rotate}\n[iteration]\nmax = 2000\n[render]\nengine = \"f64\"\n"
        )
    };
    let cancel = AtomicBool::new(false);
    let planes = |t: &str| {
        let params = deepfield::render::field_params(&scene(t), ChannelSet::default_exr());
        field::compute_strip(&params, 0..96, &cancel).unwrap().planes
    };
    let plain = planes(&text(""));
    let turned = planes(&text("rotate = 90.0"));
    let (mut same, mut escaped) = (0, 0);
    for j in 0..96usize {
        for i in 0..96usize {
            let a = j * 96 + i;
            let b = i * 96 + (95 - j);
            if turned.n[a] != plain.n[b] {
                continue;
            }
            same += 1;
            if plain.n[b] == INTERIOR {
                continue;
            }
            escaped += 1;
            let (x, y) = (plain.dex[b] as f64, plain.dey[b] as f64);
            let (u, v) = (turned.dex[a] as f64, turned.dey[a] as f64);
            let err = (u + y).hypot(v - x) / x.hypot(y);
            assert!(err < 1e-4, "pixel ({i}, {j}): ({u}, {v}) is not ({x}, {y}) turned: {err}");
        }
    }
    assert!(same >= 96 * 96 * 995 / 1000, "N agrees at only {same} of {} pixels", 96 * 96);
    assert!(escaped > 1000, "the view has escaping pixels ({escaped})");
}
