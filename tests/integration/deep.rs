//! The perturbation engines against direct arbitrary-precision iteration, at the extremes.
//!
//! Each view is rendered by the real path (scene, engine choice, reference orbit, BLA,
//! perturbation loop, quantities) and random pixels are iterated directly by `reference`
//! (astro-float, a different big-float implementation than the engine's malachite), from
//! exact pixel coordinates. Targets: N identical (orbits passing within 1e-9 of
//! the escape circle excepted), NF within 1e-4, distance estimate within 1e-3 relative at
//! the median; pixels nearer the set than 1e-6 px get the conditioning allowance of
//! `accuracy::allowed` (no arithmetic pins them down better than 1e-16 / d).

use std::sync::atomic::AtomicBool;

use astro_float::BigFloat;
use deepfield::compare::fuzz;
use deepfield::field::{self, ChannelSet};
use deepfield::num::bigfloat;
use deepfield::num::{Decimal, FloatExp};
use deepfield::render::{self, Options};
use malachite_float::Float;
use malachite_q::Rational;

use super::accuracy::{Sample, judge, summary};
use super::reference;
use super::util::{Lcg, median, scene};

/// The e1086 benchmark location's centre (a deep minibrot), to 120 digits: enough for
/// views to 1e-100.
const MINIBROT: [&str; 2] = [
    "-1.76861049301467707450317565327026522023967790758866549483767725757530464097880847527463570736246404425301437028994853855",
    "0.00126661350386871770206641119224260157619394056047140981718501017176252479258890361669150134602850245253041759926938411",
];
/// The liiiines location's centre: -2 + 1.6e-102 + 1.4e-211 i.
const LIIIINES: [&str; 2] = [
    "-1.99999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999837485382669331911167033522316925483202642018042879214193261311019861349448517336056952538528636093441258319101518468947695052924660781278387926133612368999268678559118848357284879481437613458535637431620616343911585652641236167774248507873",
    "1.37178052090609414145729128541350514525330839736695026708710030908880680107546729978680204559181338295039364573873196577319068006687895587728672855990826461331344843897843243379157581698185171855284714599499709801317677506729468150382879822938996916336090559197836550022966441254042166415444219105895943405807252402353950295056242178258440758e-211",
];

struct View {
    center: [&'static str; 2],
    radius: &'static str,
    julia: Option<[&'static str; 2]>,
    max_iter: u32,
    engine: &'static str,
    samples: u32,
    /// Extra `[render]` lines.
    render: &'static str,
    /// Iterate against a reference computed for a view centred this far away (in radii,
    /// x and y) and built to reach 3 views, moved here as the viewer moves it on a pan.
    reference_from: Option<[f64; 2]>,
    /// Iterate against the reference orbits of the same centre at this deeper radius (a
    /// zoom-out keyframe reading the deepest frame's orbits).
    reference_radius: Option<&'static str>,
    /// `[view] rotate`, `stretch_angle`, `stretch_amount`.
    transform: Option<[f64; 3]>,
    /// Store this many reference iterations densely and pack the rest (`render
    /// --dense-orbit`).
    dense_orbit: Option<u32>,
}

impl View {
    /// A Mandelbrot view with the engine chosen automatically and BLA at its default.
    fn mandelbrot(center: [&'static str; 2], radius: &'static str, max_iter: u32, samples: u32) -> View {
        View {
            center,
            radius,
            julia: None,
            max_iter,
            engine: "auto",
            samples,
            render: "",
            reference_from: None,
            reference_radius: None,
            transform: None,
            dense_orbit: None,
        }
    }
}

/// The view's rotation and stretch matrix (image offset, y up, to plane offset), written
/// out here from its definition rather than taken from the engine: Rot(-rotate) ·
/// Rot(angle) · diag(2^amount, 2^-amount) · Rot(-angle), angles in degrees.
fn view_matrix([rotate, angle, amount]: [f64; 3]) -> [[f64; 2]; 2] {
    let rot = |d: f64| {
        let (s, c) = d.to_radians().sin_cos();
        [[c, -s], [s, c]]
    };
    let mul = |a: [[f64; 2]; 2], b: [[f64; 2]; 2]| -> [[f64; 2]; 2] {
        std::array::from_fn(|i| std::array::from_fn(|j| a[i][0] * b[0][j] + a[i][1] * b[1][j]))
    };
    let k = amount.exp2();
    mul(mul(mul(rot(-rotate), rot(angle)), [[k, 0.0], [0.0, 1.0 / k]]), rot(-angle))
}

const SIZE: (u32, u32) = (40, 30);

/// Renders the view and compares `samples` random pixels with the reference.
fn measure(v: &View) -> (Vec<Sample>, String) {
    let (s, engine, _) = measure_with_reference(v);
    (s, engine)
}

/// [`measure`], also returning where the primary reference orbit ended (its last index)
/// and the largest N the sampled pixels escaped at, when the reference escaped.
fn measure_with_reference(v: &View) -> (Vec<Sample>, String, Option<(u32, u32)>) {
    let formula = match v.julia {
        Some([re, im]) => format!("[formula]\nkind = \"julia\"\nc = [\"{re}\", \"{im}\"]\n"),
        None => String::new(),
    };
    let transform = match v.transform {
        Some([r, a, k]) => format!("rotate = {r:?}\nstretch_angle = {a:?}\nstretch_amount = {k:?}\n"),
        None => String::new(),
    };
    let text = format!(
        "version = 1\n{formula}[view]\ncenter = [\"{}\", \"{}\"]\nradius = \"{}\"\nwidth = {}\nheight = {}\n{transform}[iteration]\nmax = {}\n[render]\nengine = \"{}\"\n{}\n",
        v.center[0], v.center[1], v.radius, SIZE.0, SIZE.1, v.max_iter, v.engine, v.render
    );
    let s = scene(&text);
    let plan = deepfield::render::engine::plan(&s).unwrap_or_else(|e| panic!("{e}"));
    let cancel = AtomicBool::new(false);
    let mut options = Options { dense_orbit: v.dense_orbit, ..Options::with_channels(ChannelSet::default_exr()) };
    if let Some(shift) = v.reference_from {
        // The other view's scene, its engine, and that engine moved to this view.
        let radius = Decimal::parse(v.radius).unwrap().to_rational();
        let other: [Decimal; 2] = std::array::from_fn(|k| {
            let c = Decimal::parse(v.center[k]).unwrap().to_rational();
            Decimal::from_rational(&(c + radius.clone() * Rational::try_from(shift[k]).unwrap()), 400)
        });
        let other_text = text.replacen(v.center[0], other[0].text(), 1).replacen(v.center[1], other[1].text(), 1);
        let wide = Options { deep_reach: Some(3.0), ..options.clone() };
        let other_scene = scene(&other_text);
        let other_plan = render::engine::plan(&other_scene).unwrap();
        let engine = render::prepare_deep(&other_scene, &other_plan, &wide, &cancel, &|_| {}).unwrap().expect("deep");
        let origin: [FloatExp; 2] = std::array::from_fn(|k| {
            let d = s.center[k].to_rational() - other[k].to_rational();
            bigfloat::to_floatexp(&Float::from_rational_prec(d, 64).0)
        });
        options.deep = Some(std::sync::Arc::new(engine.with_origin(origin).expect("within reach")));
    }
    if let Some(radius) = v.reference_radius {
        let deeper = scene(&text.replacen(&format!("radius = \"{}\"", v.radius), &format!("radius = \"{radius}\""), 1));
        let plan = deepfield::render::engine::plan(&deeper).unwrap();
        let spec = render::deep_spec(&deeper, &plan, &options).1.expect("deep");
        let refs = deepfield::orbit::references(&spec, &|_, _| {}, &cancel).unwrap();
        let key = deepfield::orbit::saved::key_of(&spec);
        options.references = Some(std::sync::Arc::new(deepfield::orbit::saved::SavedReferences {
            key,
            refs: std::sync::Arc::new(refs),
        }));
    }
    let (params, _) = render::prepare_field(&s, &plan, options, &cancel, &|_| {}).expect("prepared");
    if let (Some(n), Some(d)) = (v.dense_orbit, &params.deep) {
        // (A Julia set's centre orbit may escape first; the orbit of 0 goes on.)
        let packed = d.references().iter().any(|r| r.last() == n && r.end() > n);
        assert!(packed, "a reference is stored densely to {n} only and packed after");
    }
    if let (Some(_), Some(d)) = (v.reference_from, &params.deep) {
        assert_ne!(d.origin(), [FloatExp::ZERO; 2], "the moved engine served the view");
    }
    let planes = field::compute_strip(&params, 0..SIZE.1, &cancel).expect("computed").planes;
    let ln_r = params.orbit.escape_radius.ln();
    // Enough bits to place every pixel exactly and iterate it without loss.
    let bits = (-s.log10_spacing() * std::f64::consts::LOG2_10) as usize + 160;
    let rm = astro_float::RoundingMode::ToEven;
    let spacing = reference::parse(v.radius, bits).mul(&BigFloat::from_f64(2.0 / SIZE.1 as f64, bits), bits, rm);
    let julia_c = v.julia.map(|c| [reference::parse(c[0], bits), reference::parse(c[1], bits)]);
    let mut rng = Lcg(0xdee9 ^ v.max_iter as u64);
    let mut out = Vec::new();
    let mut latest = 0;
    for _ in 0..v.samples {
        let (i, j) = (rng.below(SIZE.0), rng.below(SIZE.1));
        let p = match v.transform {
            None => reference::pixel(v.center, v.radius, SIZE.0, SIZE.1, i, j, bits),
            Some(t) => {
                // The offset in spacings through the matrix (f64, as a scene defines it),
                // then placed exactly.
                let m = view_matrix(t);
                let o = [(2.0 * i as f64 + 1.0 - SIZE.0 as f64) / 2.0, -(2.0 * j as f64 + 1.0 - SIZE.1 as f64) / 2.0];
                let po = [m[0][0] * o[0] + m[0][1] * o[1], m[1][0] * o[0] + m[1][1] * o[1]];
                std::array::from_fn(|k| {
                    let d = BigFloat::from_f64(po[k], bits).mul(&spacing, bits, rm);
                    reference::parse(v.center[k], bits).add(&d, bits, rm)
                })
            }
        };
        let t =
            reference::orbit_scaled(&p, julia_c.as_ref(), v.max_iter, params.orbit.escape_radius, bits, Some(&spacing));
        latest = latest.max(t.n.unwrap_or(0));
        if !t.near_circle {
            let mut sample = judge(&t, &planes, (j * SIZE.0 + i) as usize, 1.0, ln_r);
            if v.transform.is_some() {
                // The engine reports the distance vector in image terms; the rotation of
                // vectors has its own test. Length only here.
                sample.de_err = sample.d.map(|d| {
                    let k = (j * SIZE.0 + i) as usize;
                    ((planes.dex[k] as f64).hypot(planes.dey[k] as f64) - d).abs() / d
                });
            }
            out.push(sample);
        }
    }
    let reference = params.deep.as_ref().filter(|d| d.reference_escaped()).map(|d| (d.reference_length(), latest));
    (out, plan.name.to_string(), reference)
}

/// Asserts the accuracy targets.
fn check(name: &str, v: View, expect_engine: &str) {
    let (s, engine) = measure(&v);
    assert_targets(name, &s, &engine, expect_engine, v.samples);
}

fn assert_targets(name: &str, s: &[Sample], engine: &str, expect_engine: &str, samples: u32) {
    summary(&format!("{name} ({engine})"), s);
    assert_eq!(engine, expect_engine, "{name}: engine");
    assert!(s.len() as u32 >= samples * 9 / 10, "{name}: too few comparable pixels");
    for x in s {
        assert!(x.n_ok, "{name}: N differs from the reference: {x:?}");
        if let Some(e) = x.nf_err {
            let allowed = match x.d {
                Some(d) if d < 1e-6 => 1e-4f64.max(1e-10 / d),
                _ => 1e-4,
            };
            assert!(e <= allowed, "{name}: NF error {e} at d = {:?} px", x.d);
        }
    }
    let de_median = median(s.iter().filter_map(|x| x.de_err).collect());
    assert!(de_median <= 1e-3, "{name}: median distance error {de_median}");
}

/// The shipped seahorse spiral, `scenes/spiral-deep.toml` at zoom 4e8: direct f64 still
/// resolves its coordinates (millions of ulps per sample), but its rounding shows in N and
/// NF (`deepfield compare scenes/spiral-deep.toml --samples 200 --sample-only`: 12.6% of N
/// wrong with `f64`), so `auto` chooses perturbation past zoom 1e5, and every configuration
/// of it meets the deep fuzzer's bar on sampled pixels of the full 800×600 view. Both sides
/// of that line, at 3e4 and 2e6, from the engine plans (a forced `f64` still resolves them).
#[test]
fn auto_leaves_direct_f64_past_zoom_1e5() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/spiral-deep.toml");
    let spiral = super::util::scene(&std::fs::read_to_string(path).expect("shipped scene"));
    assert_eq!(deepfield::render::engine::plan(&spiral).expect("an engine").name, "perturb-f64");
    let levels = deepfield::simd_level::SimdLevel::usable();
    let verdict =
        fuzz::check(&spiral, spiral.formula, 24, &levels, fuzz::BAR, &AtomicBool::new(false)).expect("checked");
    let names: Vec<&str> = verdict.rows.iter().map(|r| r.engine.as_str()).collect();
    assert!(names.iter().all(|n| n.starts_with("perturb")), "{names:?}");
    assert!(verdict.failures.is_empty(), "{}", verdict.failures.join("\n"));
    let [re, im] = [spiral.center[0].to_string(), spiral.center[1].to_string()];
    for (zoom, engine) in [("3e4", "f64"), ("9e4", "f64"), ("2e5", "perturb-f64"), ("2e6", "perturb-f64")] {
        let text = format!(
            "version = 1\n[view]\ncenter = [\"{re}\", \"{im}\"]\nzoom = \"{zoom}\"\nwidth = 3840\nheight = 2160\n"
        );
        let plan = deepfield::render::engine::plan(&super::util::scene(&text)).expect("an engine");
        assert_eq!(plan.name, engine, "zoom {zoom}: {}", plan.reason);
        let forced =
            deepfield::render::engine::plan(&super::util::scene(&format!("{text}[render]\nengine = \"f64\"\n")));
        assert_eq!(forced.expect("forced f64 resolves the view").name, "f64", "zoom {zoom}");
    }
}

#[test]
fn zoom_1e14_and_1e16_where_f64_breaks_down() {
    let v = |radius| View::mandelbrot(MINIBROT, radius, 5000, 60);
    check("minibrot 1e14", v("2e-14"), "perturb-f64");
    check("minibrot 1e16", v("2e-16"), "perturb-f64");
}

#[test]
fn zoom_1e50() {
    let v = View::mandelbrot(MINIBROT, "2e-50", 10000, 40);
    check("minibrot 1e50", v, "perturb-f64");
}

#[test]
fn zoom_1e300_and_1e320_past_the_f64_exponent_range() {
    let v = |radius| View::mandelbrot(LIIIINES, radius, 12500, 24);
    check("liiiines 1e300", v("2e-300"), "perturb-floatexp");
    check("liiiines 1e320", v("2e-320"), "perturb-floatexp");
}

/// A view iterated against the reference of a view centred elsewhere (as the viewer pans
/// about an older reference): at 1e50 with f64 deltas and 1e320 with FloatExp deltas.
#[test]
fn against_a_reference_computed_for_a_view_elsewhere() {
    let v = View { reference_from: Some([0.9, -0.6]), ..View::mandelbrot(MINIBROT, "2e-50", 10000, 40) };
    check("minibrot 1e50, reference 1.1 radii away", v, "perturb-f64");
    let v = View { reference_from: Some([-1.5, 0.4]), ..View::mandelbrot(LIIIINES, "2e-320", 12500, 24) };
    check("liiiines 1e320, reference 1.6 radii away", v, "perturb-floatexp");
}

/// A view centred on a period-2578 minibrot's nucleus (found by `locate` from the e1086
/// location at zoom 1e60; size 4.3e-115), 1000 of its framing radii wide, with an iteration
/// limit of 1e8: the reference is one period of the nucleus's orbit, stored densely and
/// whole, and samples rebase through it.
#[test]
fn a_nucleus_centred_view_stores_one_period_for_any_iteration_limit() {
    let e1086 = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bench-e1086.toml")).unwrap();
    let c = scene(&e1086).center;
    let near = deepfield::num::bigcomplex::BigC::from_decimals(&c[0], &c[1], 300);
    let m = deepfield::locate::search::minibrot_in_view(&near, FloatExp::exp10(-60.0).mul_f64(3.4), 100_000)
        .expect("a minibrot");
    assert_eq!(m.period, 2578);
    let [re, im] = m.nucleus.to_decimals(3);
    let radius = deepfield::locate::search::framing_radius(m.size).mul_f64(1000.0);
    let l = radius.log2() * std::f64::consts::LOG10_2;
    let radius = deepfield::num::scientific(l, 6);
    let leak = |t: String| -> &'static str { Box::leak(t.into_boxed_str()) };
    let v = View::mandelbrot([leak(re.text().to_string()), leak(im.text().to_string())], leak(radius), 100_000_000, 24);
    let (samples, engine, _) = measure_with_reference(&v);
    assert_targets("nucleus of period 2578, 1e8 iterations", &samples, &engine, "perturb-f64", 24);
}

/// Views served by the reference orbits of a deeper view of the same centre (as zoom-out
/// keyframes are): 1e300 from 1e320's, and 1e20 from 1e50's.
#[test]
fn against_the_reference_of_a_deeper_view_of_the_same_centre() {
    let v = View { reference_radius: Some("2e-320"), ..View::mandelbrot(LIIIINES, "2e-300", 12500, 24) };
    check("liiiines 1e300 from 1e320's reference", v, "perturb-floatexp");
    let v = View { reference_radius: Some("2e-50"), ..View::mandelbrot(MINIBROT, "2e-20", 10000, 30) };
    check("minibrot 1e20 from 1e50's reference", v, "perturb-f64");
}

/// A reference that repeats itself exactly (`orbit::reference::Reference::cycle`): the
/// e102 minibrot's interior off its nucleus (`scenes/long-orbit-e102.toml`), whose orbit
/// settles on the minibrot's attracting cycle and repeats to the last bit at iteration
/// 265001. The reference stops there, and the view (to 340000 iterations, past the
/// reference's end at 330735) agrees with big floats with interior detection and without.
/// (That samples going round the cycle end as along the whole orbit, bit for bit, is
/// `orbit::perturb::tests::samples_go_round_a_repeating_reference_as_along_the_whole_orbit`.)
#[test]
fn through_a_reference_that_repeats() {
    const OFF_NUCLEUS: [&str; 2] = [
        "-0.83031842675693053553109980802050591726924580592100415017586803599827560339120465373468510811787516730485186454892834980632246054605795",
        "0.23612476396680780363307856325882633547132442124365456398110558858530832926040168389957117374824216611996058042279006600832794659929318",
    ];
    check("minibrot 1e102 off its nucleus, cut", View::mandelbrot(OFF_NUCLEUS, "1.2e-102", 340_000, 8), "perturb-f64");
    let v = View { render: "interior_detection = false", ..View::mandelbrot(OFF_NUCLEUS, "1.2e-102", 340_000, 8) };
    check("minibrot 1e102 off its nucleus, cut, no interior detection", v, "perturb-f64");
}

/// References stored densely for a few hundred iterations and packed after
/// (`orbit::reference::packed`, as limits past 2^25 store them): samples run through the packed tail
/// by single steps, in f64 and FloatExp deltas, with BLA in the dense part, for the
/// Mandelbrot set (a reference that escapes late and one that does not escape) and a Julia
/// set.
#[test]
fn through_packed_reference_tails() {
    let v = View { dense_orbit: Some(300), ..View::mandelbrot(MINIBROT, "2e-50", 10000, 24) };
    check("minibrot 1e50, packed after 300", v, "perturb-f64");
    let v = View { dense_orbit: Some(1000), ..View::mandelbrot(LIIIINES, "2e-320", 12500, 16) };
    check("liiiines 1e320, packed after 1000", v, "perturb-floatexp");
    let v = View {
        julia: Some(["-0.7436447860", "0.1318252536"]),
        dense_orbit: Some(200),
        ..View::mandelbrot(
            [
                "1.49899848626690059854946357005252043405194888410281635160902340639312066973795336",
                "-0.06597870537952971836904746440551643923003302222753852735309069970961233737180929",
            ],
            "2e-40",
            3000,
            24,
        )
    };
    check("julia 1e40, packed after 200", v, "perturb-f64");
}

/// Past the first 2^20 iterations of an orbit, samples take BLA steps of whole blocks
/// (`orbit::bla::TailSteps`): by the cusp of the main cardioid (c = 1/4 + 5e-12, where every
/// orbit lingers near z = 1/2 and escapes after about 1.4 million iterations), with the
/// orbit past 2^20 stored densely and packed.
#[test]
fn past_two_to_the_twenty_by_steps_of_blocks() {
    const CUSP: [&str; 2] = ["0.250000000005", "0"];
    check("cusp 1e18, dense", View::mandelbrot(CUSP, "1e-18", 2_000_000, 4), "perturb-f64");
    let v = View { dense_orbit: Some(1 << 20), ..View::mandelbrot(CUSP, "1e-18", 2_000_000, 4) };
    check("cusp 1e18, packed past 2^20", v, "perturb-f64");
}

/// BLA off: every iteration is a perturbation step, in FloatExp while deltas are tiny and
/// in f64 after; the switch points are what this checks (a too-early switch to f64 once
/// put N off by one on 5% of these pixels).
#[test]
fn without_bla_at_1e320_and_1e50() {
    let v = View { render: "bla = false", ..View::mandelbrot(LIIIINES, "2e-320", 12500, 24) };
    check("liiiines 1e320 without BLA", v, "perturb-floatexp");
    let v = View { render: "bla = false", ..View::mandelbrot(MINIBROT, "2e-50", 10000, 24) };
    check("minibrot 1e50 without BLA", v, "perturb-f64");
}

#[test]
fn zoom_1e1000_next_to_minus_two_where_z_lingers_at_two() {
    // c = -2 + 3e-1000 + small imaginary parts: |z| stays near 2 for ~1660 iterations.
    let v = View {
        center: [
            "-1.999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999997",
            "1e-1000",
        ],
        ..View::mandelbrot(MINIBROT, "2e-1000", 5000, 24)
    };
    check("next to -2 at 1e1000", v, "perturb-floatexp");
}

/// The e1086 benchmark location (scenes/bench-e1086.toml): orbits pass within 1e-1000 of 0
/// on their way to escaping at ~538000 iterations, where the derivative's f64 update would
/// underflow (it did: every distance estimate sat at the 1e30 cap). Two pixels, because the
/// reference iterates each in 3800-bit floats.
#[test]
fn zoom_1e1086_where_orbits_pass_within_1e_1000_of_zero() {
    const CENTER: [&str; 2] = [
        "-1.768610493014677074503175653270226520239677907588665494837677257575304640978808475274635707362464044253014370289948538552508877464736415873052958422861932774670165994201643419934807500290056179906392909880374230601661671965436663874506006355684166693059189687544326482526337453326360163639772818993753021740632937840115380957766425092940720439911920812397880443241274616212526380871555846532502156439892026352831619587768336768186345867565251889103622267866223055366872757385322485553606302984011695749730200727740242949661790906981449438923948817795927101980894917081591610562406554244675206099799522186446427884314773626993347929810277790888202019035845973880637832335294368222957931354735878969938534303074032237618397187328436715391758039680667871461788151793412286894565873237610467572174105629653438005433391873958639508124883860426968801537270756998560434335574379853659221182422319763412022530545421664765603500398209444536908432136868648907188939238968853841659746686717617541828417173199448336773447645561102873230388632254317334566170379314718589610910079079436175134148945650553411",
        "0.001266613503868717702066411192242601576193940560471409817185010171762524792588903616691501346028502452530417599269384116816237002586460261272462170615382790262110756215389780859682964779212455295242650488799024701023353984576434859496345393442867544784349509799966996827374525729583822627564832207860235000491856039278975203253540119195661182532106440194050352510825207428197675168479460252154208762204074041030502712772770772439567249008997886131809082319952112293668096363959700371035596685905429248221153089843201890985651976151989928496969024027810874574434857210174914227391125217932725188214796457327981771026544613194033736960542354861910879704489564999937473456191049937984461971508132204319961501958583967780282332682705656745932852354591955251196335374396883193221988201865629549575259395090238463522557833659758739138043696167112257784649600743807944457388512639475417466113111928274012056049434349358618953361438127758918999578120953045365596358997480091072548929426951083179599722132179281125708039705266879359303320165515458347343055671220673027817611220892213570374041225632346",
    ];
    check("bench-e1086 location", View::mandelbrot(CENTER, "2e-1086", 600100, 2), "perturb-floatexp");
}

/// "Floral fantasy" (rust-fractal-core's public locations; zoom 1.6e85 near c = -1.999096)
/// and the same neighbourhood at 3.1e85 (its "glitch test 4"): the reference escapes at
/// iteration ~2156 while samples escape as late as ~2212, and orbits linger near |z| = 2,
/// where a BLA step's quadratic term is as large as a quarter of its linear one. The view's
/// common BLA steps (`Skip`) once composed those steps as a quadratic in the offset,
/// dropping cubic terms no radius bounded: every pixel was displaced (62% of N wrong, NF
/// off by 0.15 at the median). The test asserts that the view still has its reference
/// escape before some of its samples.
#[test]
fn reference_escaping_before_its_samples_near_minus_two() {
    const FLORAL: [&str; 2] = [
        "-1.9990959962659111838532086240451464723873699879106041072875027138225861729613819461216022699999999999999999999999",
        "0.0000002758071979815309980117897130508770848629719975198765589767776483289612775591171197799999999999999999999999",
    ];
    const GLITCH4: [&str; 2] = [
        "-1.999095996265911183853208624045146472387369987910604107287502713822586172961381946121551866831936458883511",
        "2.758071979815309980117897130508770848629719975198765589767776483289612775591171065536367492835368050791947e-7",
    ];
    let views = [
        ("floral fantasy 1.6e85", FLORAL, "1.2869e-85", "perturb-f64"),
        ("glitch test 4 3.1e85", GLITCH4, "6.4345e-86", "perturb-f64"),
        ("floral fantasy 1.6e85 in FloatExp", FLORAL, "1.2869e-85", "perturb-floatexp"),
    ];
    for (name, center, radius, engine) in views {
        let v = View { engine, ..View::mandelbrot(center, radius, 12000, 30) };
        let (s, ran, reference) = measure_with_reference(&v);
        let (end, latest) = reference.unwrap_or_else(|| panic!("{name}: the reference must escape"));
        assert!(latest > end, "{name}: the reference ({end}) must escape before some sample ({latest})");
        assert_targets(name, &s, &ran, engine, v.samples);
    }
}

/// Rotated and stretched views, shallow enough for f64 deltas and past the f64 range: each
/// sample's point is the matrix applied to its offset, placed exactly, and iterated
/// directly. (The views are the tuned minibrot and liiiines locations at depths this file
/// tests unrotated.)
#[test]
fn rotated_and_stretched_views() {
    for (name, v, engine) in [
        (
            "1e50 rotated 30°",
            View { transform: Some([30.0, 0.0, 0.0]), ..View::mandelbrot(MINIBROT, "2e-50", 10000, 30) },
            "perturb-f64",
        ),
        (
            "1e50 stretched 2^0.7 at 20°, rotated -65°",
            View { transform: Some([-65.0, 20.0, 0.7]), ..View::mandelbrot(MINIBROT, "2e-50", 10000, 30) },
            "perturb-f64",
        ),
        (
            "1e320 rotated 100°, stretched 2^-1.5 at 80°",
            View { transform: Some([100.0, 80.0, -1.5]), ..View::mandelbrot(LIIIINES, "2e-320", 12500, 24) },
            "perturb-floatexp",
        ),
    ] {
        check(name, v, engine);
    }
}

#[test]
fn cusp_at_one_quarter() {
    // Orbits near c = 0.25 crawl past the parabolic fixed point 1/2 (thousands of
    // iterations); the reference sits just outside the set.
    let v = View { engine: "perturb-f64", ..View::mandelbrot(["0.2500001", "0"], "2e-7", 20000, 40) };
    check("cusp 0.25", v, "perturb-f64");
}

#[test]
fn julia_sets_at_1e40_and_1e310() {
    let e40 = View {
        center: [
            "1.49899848626690059854946357005252043405194888410281635160902340639312066973795336",
            "-0.06597870537952971836904746440551643923003302222753852735309069970961233737180929",
        ],
        radius: "2e-40",
        julia: Some(["-0.7436447860", "0.1318252536"]),
        max_iter: 3000,
        engine: "auto",
        samples: 40,
        render: "",
        reference_from: None,
        reference_radius: None,
        transform: None,
        dense_orbit: None,
    };
    check("julia 1e40", e40, "perturb-f64");
    let e310 = View {
        center: [
            "1.498998059701593679863611269389471455923467487587207729632622361597165205414479266771001741604374880670827981821234891802701425395767007388531111033739859140450966250423798082016562443577765107061115497084206684010748981623142526398371956157555964949563876573643348089626811132808802434072359836986035651410273612093408366424625471686597567303179761716120900262",
            "-0.065979059180909288508764626796452334526732369424523752491501200244877730170502430981529834329747396126521012785968015176337244600588494150764797829550193024781486072003694559842281658712296844476789446962510048136872670014639735191502853264175589134843720724066093486413512758440443041841060428572420332017483341677543572054285646284865668016892106466686005806",
        ],
        radius: "2e-310",
        julia: Some(["-0.743643887037151", "0.131825904205330"]),
        max_iter: 10000,
        engine: "auto",
        samples: 24,
        render: "",
        reference_from: None,
        reference_radius: None,
        transform: None,
        dense_orbit: None,
    };
    check("julia 1e310", e310, "perturb-floatexp");
}

/// Renders a view with an engine and returns its planes.
fn planes(text: &str) -> (field::Planes, String) {
    let s = scene(text);
    let plan = deepfield::render::engine::plan(&s).unwrap_or_else(|e| panic!("{e}"));
    let cancel = AtomicBool::new(false);
    let (params, _) =
        render::prepare_field(&s, &plan, Options::with_channels(ChannelSet::default_exr()), &cancel, &|_| {})
            .expect("prepared");
    let h = params.grid.height;
    (field::compute_strip(&params, 0..h, &cancel).expect("computed").planes, plan.name.to_string())
}

/// At shallow zoom, where direct f64 iteration is exact enough, every perturbation engine
/// (with and without BLA) agrees with it, Mandelbrot and Julia.
#[test]
fn perturbation_agrees_with_direct_f64_at_shallow_zoom() {
    for formula in ["", "[formula]\nkind = \"julia\"\nc = [\"-0.8\", \"0.156\"]\n"] {
        let view = format!(
            "version = 1\n{formula}[view]\ncenter = [\"-0.1\", \"0.3\"]\nzoom = \"3\"\nwidth = 64\nheight = 48\n[iteration]\nmax = 2000\n"
        );
        let (direct, name) = planes(&format!("{view}[render]\nengine = \"f64\"\n"));
        assert_eq!(name, "f64");
        for render in
            ["engine = \"perturb-f64\"\nbla = false", "engine = \"perturb-f64\"", "engine = \"perturb-floatexp\""]
        {
            let (p, _) = planes(&format!("{view}[render]\n{render}\n"));
            let same = direct.n.iter().zip(&p.n).filter(|(a, b)| a == b).count();
            assert!(same as f64 >= 0.995 * p.n.len() as f64, "{render}: N agrees on {same} of {}", p.n.len());
            let mut nf_err: Vec<f64> = Vec::new();
            for k in 0..p.n.len() {
                if direct.n[k] == p.n[k] && p.n[k] != deepfield::formula::end::INTERIOR {
                    nf_err.push((direct.nf[k] - p.nf[k]).abs() as f64);
                }
            }
            assert!(median(nf_err) < 1e-6, "{render}: NF differs");
        }
    }
}

/// BLA on and off agree within the tolerance's accuracy, and no output channel holds a NaN
/// or an infinity at any depth.
#[test]
fn bla_on_and_off_agree_and_every_channel_is_finite() {
    let views = [(MINIBROT, "2e-30", 6000), (LIIIINES, "2e-310", 12500), (LIIIINES, "2e-700", 12500)];
    for (center, radius, max) in views {
        let view = format!(
            "version = 1\n[view]\ncenter = [\"{}\", \"{}\"]\nradius = \"{radius}\"\nwidth = 48\nheight = 32\n[iteration]\nmax = {max}\n",
            center[0], center[1]
        );
        let (on, _) = planes(&view);
        let (off, _) = planes(&format!("{view}[render]\nbla = false\n"));
        for p in [&on, &off] {
            assert!(
                p.nf.iter().chain(&p.t).chain(&p.dex).chain(&p.dey).all(|v| v.is_finite()),
                "{radius}: non-finite value"
            );
        }
        let same = on.n.iter().zip(&off.n).filter(|(a, b)| a == b).count();
        assert!(same as f64 >= 0.999 * on.n.len() as f64, "{radius}: BLA changes N on {} pixels", on.n.len() - same);
        let nf: Vec<f64> =
            (0..on.n.len()).filter(|&k| on.n[k] == off.n[k]).map(|k| (on.nf[k] - off.nf[k]).abs() as f64).collect();
        assert!(median(nf) < 1e-6, "{radius}: NF differs with BLA");
    }
}

/// The truth's NF takes the logarithm in the formula's own degree: on the shipped power-3
/// minibrot at 2e50 (`scenes/bench-mandelbrot3-e50.toml`) and on a shallow view of z^4 + c
/// (direct f64 and perturbation alike), every configuration meets the deep fuzzer's bar,
/// NF included (a truth taking log2 there is off by up to ~0.2 in NF on every pixel).
#[test]
fn the_truths_nf_is_in_the_formulas_degree() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/scenes/bench-mandelbrot3-e50.toml");
    let mut cubic = super::util::scene(&std::fs::read_to_string(path).expect("shipped scene"));
    (cubic.width, cubic.height) = (80, 60);
    let quartic = super::util::scene(
        "version = 1\n[formula]\nkind = \"mandelbrot\"\npower = 4\n[view]\ncenter = [\"0.5\", \"0.6\"]\nzoom = \"40\"\nwidth = 80\nheight = 60\n[iteration]\nmax = 2000\n",
    );
    let levels = [deepfield::simd_level::SimdLevel::detect()];
    for (name, scene) in [("mandelbrot^3 at 2e50", &cubic), ("mandelbrot^4 at 40", &quartic)] {
        let verdict =
            fuzz::check(scene, scene.formula, 24, &levels, fuzz::BAR, &AtomicBool::new(false)).expect("checked");
        assert!(verdict.failures.is_empty(), "{name}: {}", verdict.failures.join("\n"));
        // NF included: every configuration's NF errors are over escaped pixels, not none.
        assert!(verdict.rows.iter().all(|r| r.compared > 0 && r.nf_scored > 0), "{name}: {:?}", verdict.rows);
    }
}
