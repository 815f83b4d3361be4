//! Tests of the perturbation loop: every driver, lane and shortcut against one sample at a time, the derivative near zero, the view-wide skip and cancelled builds.

use std::sync::atomic::AtomicBool;

use malachite_float::Float;

use super::*;
use crate::cancel::NEVER;
use crate::num::Decimal;
use crate::orbit::{DeepSpec, Scale, prepare, reference};

const MINIBROT: [&str; 2] = [
    "-1.768610493014677074503175653270265220239677907588665494837677257575304640978808475274635707362464",
    "0.001266613503868717702066412241102601576193940560471409817185010171762524792588903616691501346028",
];
/// -2 + 1.6e-102 + 1.4e-211 i (the liiiines location), to 1e-330.
const LIIIINES: [&str; 2] = [
    "-1.99999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999999837485382669331911167033522316925483202642018042879214193261311019861349448517336056952538528636093441258319101518468947695052924660781278387926133612368999268678559118848357284879481437613458535637431620616343911585652641236167774248507873",
    "1.37178052090609414145729128541350514525330839736695026708710030908880680107546729978680204559181338295039364573873196577319068006687895587728672855990826461331344843897843243379157581698185171855284714599499709801317677506729468150382879822938996916336090559197836550022966441254042166415444219105895943405807252402353950295056242178258440758e-211",
];
/// The 1e50 benchmark location, to 1e-70: thousands of single steps per sample, with
/// derivatives that leave their exponent window many times on the way.
const E50: [&str; 2] = [
    "-0.04947002906310409375169222672735363011874571248822487931810494023264219477268690",
    "-0.67478757584467536401139205313059765633477070682240348069799979479099419834548451",
];
/// The nucleus of a period-1429 minibrot near the all-seeing-eye location (`deepfield
/// find scenes/locations/all-seeing-eye.toml --zoom 1e70`), size 1.6e-102.
const EYE_MINIBROT: [&str; 2] = [
    "-0.83031842675693053553109980802050591726924580592100415017586803599827560339120465373468510811787516730515186454892834980632246054605795",
    "0.23612476396680780363307856325882633547132442124365456398110558858530832926040168389957117374824216611986058042279006600832794659929318",
];
/// Seahorse valley, the descent every zoom into it passes through: at 1e-6 a sample
/// rebases about every 50 steps (the lanes rebase inside their bursts).
const SEAHORSE: [&str; 2] = ["-0.743643887037158704752191506114774", "0.131825904205311970493132056385139"];
const JULIA_CENTER: [&str; 2] = [
    "1.49899848626690059854946357005252043405194888410281635160902340639312066973795336",
    "-0.06597870537952971836904746440551643923003302222753852735309069970961233737180929",
];

/// Where an orbit passes near 0 the Mandelbrot derivative collapses to its added term
/// (dz -> 2 z dz + 1): a single step from a tiny z, or a BLA step with a tiny multiplier,
/// must keep that term although it is far below the derivative's f64 mantissa (at depth
/// it underflows there; bench-e1086 lost its distance estimates this way).
#[test]
fn derivative_keeps_its_added_term_where_the_orbit_passes_near_zero() {
    let spacing = FloatExp::new(1.0, -3600);
    let close = |v: [FloatExp; 2], want: [f64; 2]| {
        let got = [v[0].ldexp(3600).to_f64(), v[1].ldexp(3600).to_f64()];
        assert!((got[0] - want[0]).abs() < 1e-12 && (got[1] - want[1]).abs() < 1e-12, "{got:?} != {want:?}");
    };
    // dz/dc ~ 2^3000, so the scaled derivative is ~2^-600 and the spacing is 2^-3000 of it.
    let start = Der::from_fe([FloatExp::new(1.5, -600), FloatExp::new(-0.5, -600)], spacing);
    let tiny = [FloatExp::new(1.0, -3200), FloatExp::new(1.0, -3201)];
    let mut der = start;
    der.step(cto_f64(tiny), tiny, spacing);
    close(der.to_fe(), [1.0, 0.0]);
    // A BLA step whose multiplier is below f64's range and whose added part is 3 + 2i.
    let (m, n) = (tiny, [FloatExp::from(3.0), FloatExp::from(2.0)]);
    let mut der = start;
    der.jacobian(cto_f64(m), cto_f64(n), || (m, n), spacing);
    close(der.to_fe(), [3.0, 2.0]);
    // Away from 0 the f64 path gives 2 z dz (+ a negligible spacing).
    let z = [FloatExp::from(0.5), FloatExp::from(0.25)];
    let mut der = start;
    der.step(cto_f64(z), z, spacing);
    let want = cmul([FloatExp::from(1.0), FloatExp::from(0.5)], start.to_fe());
    let got = der.to_fe();
    for k in 0..2 {
        assert!((got[k].ldexp(600).to_f64() - want[k].ldexp(600).to_f64()).abs() < 1e-15, "{got:?} {want:?}");
    }
}

/// The view's common BLA steps, composed as a quadratic in the offset u, against single
/// perturbation steps of each sample (FloatExp, exact to rounding) at the floral-fantasy
/// location (c near -2: orbits linger at |z| = 2, where a step's quadratic term is up to
/// a quarter of its linear one). The composite once dropped the cubic terms of that
/// composition unchecked and was off by tens of percent at the view's corners.
#[test]
fn view_wide_skip_agrees_with_stepping_each_sample() {
    const FLORAL: [&str; 2] = [
        "-1.9990959962659111838532086240451464723873699879106041072875027138225861729613819461216022699999999999999999999999",
        "0.0000002758071979815309980117897130508770848629719975198765589767776483289612775591171197799999999999999999999999",
    ];
    for (eps, radius) in [(1e-8, "1.2869e-85"), (1e-14, "1.2869e-85"), (1e-10, "1e-60")] {
        let (w, h) = (64.0, 48.0);
        let max_offset = f64::hypot(w, h) / 2.0;
        let spec = DeepSpec {
            center: dec(FLORAL),
            julia: None,
            spacing: Scale::Radius(Decimal::parse(radius).unwrap()).spacing(h as u32),
            max_offset,
            max_iter: 12000,
            escape_radius: 65536.0,
            derivative: false,
            bla: Some(eps),
            interior: Detection::Off,
            numbers: Numbers::FloatExp,
            simd: SimdLevel::detect(),
            references: None,
            dense_orbit: None,
        };
        let p = prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
        let skip = p.skip.expect("the view has common steps");
        assert!(skip.m > 100, "{radius}: the skip covers {} iterations", skip.m);
        let r = &p.refs[0];
        let mut worst = 0.0f64;
        for k in 0..16 {
            let angle = k as f64 * std::f64::consts::TAU / 16.0;
            let scale = if k % 2 == 0 { 1.0 } else { 0.37 };
            let off = [scale * max_offset * angle.cos(), scale * max_offset * angle.sin()];
            let u = [p.spacing.mul_f64(off[0]), p.spacing.mul_f64(off[1])];
            let mut d = u;
            for m in 1..skip.m {
                let zm = r.get_fe(m);
                d = cadd(cmul(cadd([zm[0].ldexp(1), zm[1].ldexp(1)], d), d), u);
            }
            let [k1, k2] = skip.k;
            let composite = cadd(cmul(k1, u), cmul(cmul(k2, u), u));
            let diff = cadd(composite, [-d[0], -d[1]]);
            worst = worst.max((norm2(diff).sqrt() / norm2(d).sqrt()).to_f64());
        }
        // Rounding in ~skip.m single steps, plus ε per composed step at most.
        let allowed = eps * skip.steps as f64 + 1e-13;
        assert!(
            worst <= allowed,
            "{radius} ε {eps}: relative error {worst:e} > {allowed:e} after {} steps",
            skip.steps
        );
    }
}

/// A Mandelbrot view's spec with BLA at `eps`, escape radius 2^16, no derivative, no
/// interior detection, f64 deltas and this CPU's SIMD level; tests set what they vary.
fn bla_spec(center: [&str; 2], spacing: FloatExp, max_offset: f64, max_iter: u32, eps: f64) -> DeepSpec {
    DeepSpec {
        center: dec(center),
        julia: None,
        spacing,
        max_offset,
        max_iter,
        escape_radius: 65536.0,
        derivative: false,
        bla: Some(eps),
        interior: Detection::Off,
        numbers: Numbers::F64,
        simd: SimdLevel::detect(),
        references: None,
        dense_orbit: None,
    }
}

fn dec(v: [&str; 2]) -> [Decimal; 2] {
    [Decimal::parse(v[0]).unwrap(), Decimal::parse(v[1]).unwrap()]
}

/// A render cancelled while its samples wait on the build of the steps of whole blocks
/// (here through a packed tail): the build stops and keeps nothing, the samples are
/// abandoned rather than single-stepped to the limit, and a later call that is not
/// cancelled builds the steps and gets the same samples as an engine that was never
/// cancelled.
#[test]
fn a_cancelled_build_of_blocks_abandons_its_samples_and_keeps_nothing() {
    let (w, h) = (8i32, 6i32);
    let max_iter = 400_000;
    let spec = DeepSpec {
        // Inside the main cardioid near its cusp, where the orbit settles so slowly that it
        // does not repeat itself exactly within the dense part (and so is not cut there):
        // every sample runs to the limit, through the tail.
        center: dec(["0.2499", "0"]),
        julia: None,
        spacing: Scale::Radius(Decimal::parse("1e-6").unwrap()).spacing(h as u32),
        max_offset: ((w * w + h * h) as f64).sqrt() / 2.0,
        max_iter,
        escape_radius: 2.0,
        derivative: false,
        bla: Some(1e-12),
        interior: Detection::Off,
        numbers: Numbers::F64,
        simd: SimdLevel::detect(),
        references: None,
        dense_orbit: Some(2000),
    };
    let engine = || prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
    let offsets: Vec<[f64; 2]> =
        (0..h).flat_map(|j| (0..w).map(move |i| [f64::from(i - w / 2), f64::from(j - h / 2)])).collect();
    let run = |p: &Perturbation, cancel: &AtomicBool, simd: SimdLevel| {
        let mut out = vec![Orbit::interior(); offsets.len()];
        let mut c = Counters::default();
        p.orbits(&offsets, &mut out, &mut c, simd, cancel);
        (out, c)
    };
    let built = |p: &Perturbation| p.bla_f64[0].as_ref().and_then(|t| t.built()).is_some();
    let bits = |o: &Orbit| (o.n, o.z.map(f64::to_bits));
    // Never cancelled, in the scalar loop: what every level must give.
    let (fresh, c_fresh) = run(&engine(), &NEVER, SimdLevel::Scalar);
    let abandoned = offsets.len() as u64 * u64::from(max_iter);
    assert!(c_fresh.iterations > abandoned / 10 * 9, "every sample to about the limit: {}", c_fresh.iterations);
    // The scalar loop and every level's lanes (which hand their samples back to it for
    // the tail's steps) stop alike.
    for simd in SimdLevel::usable() {
        let p = engine();
        assert!(p.refs[0].packed().is_some() && !built(&p), "a packed tail, its blocks not built yet");
        let (_, c) = run(&p, &AtomicBool::new(true), simd);
        assert!(!built(&p), "{simd}: a cancelled build keeps nothing");
        assert_eq!(p.blocks_progress(), None, "{simd}: and shows no progress");
        assert!(c.iterations < abandoned / 10, "{simd}: the samples were abandoned: {} iterations", c.iterations);
        let (again, c) = run(&p, &NEVER, simd);
        assert!(built(&p), "{simd}: built when not cancelled");
        assert_eq!(c, c_fresh, "{simd}: the same counts as never cancelled");
        let same = again.iter().zip(&fresh).all(|(a, b)| bits(a) == bits(b));
        assert!(same, "{simd}: the same samples as never cancelled");
    }
}

/// Every sample of a 32x24 view through `orbits` with every instruction set this CPU
/// runs (the vector lanes of each width, and the two-sample scalar loop) and one at a
/// time through `orbit`, with interior detection off and on: bit for bit the same
/// escape, z_n and derivative, and the same iteration, step and interior counts. Interior
/// detection changes no sample's end but for stopping interior ones earlier (same N,
/// INTERIOR). Returns the samples found interior by detection, and of those the samples in
/// certified disks.
fn same_both_ways(
    center: [&str; 2],
    julia: Option<[&str; 2]>,
    radius: &str,
    max_iter: u32,
    numbers: Numbers,
    bla: Option<f64>,
    dense_limit: Option<u32>,
) -> (u64, u64) {
    let (w, h) = (32i32, 24i32);
    let (mut found, mut disks) = (0, 0);
    for derivative in [false, true] {
        let mut without: Option<Vec<Orbit>> = None;
        for interior in [Detection::Off, Detection::On] {
            let spec = DeepSpec {
                center: dec(center),
                julia: julia.map(dec),
                spacing: Scale::Radius(Decimal::parse(radius).unwrap()).spacing(h as u32),
                max_offset: ((w * w + h * h) as f64).sqrt() / 2.0,
                max_iter,
                escape_radius: 2.0,
                derivative,
                bla,
                interior,
                numbers,
                simd: SimdLevel::detect(),
                references: None,
                dense_orbit: dense_limit,
            };
            let p = prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
            let packed = p.refs.iter().any(|r| r.packed().is_some());
            assert_eq!(packed, dense_limit.is_some(), "{radius}: packed as asked");
            let offsets: Vec<[f64; 2]> = (0..h)
                .flat_map(|j| (0..w).map(move |i| [i as f64 - w as f64 / 2.0 + 0.5, j as f64 - h as f64 / 2.0 + 0.5]))
                .collect();
            let mut c_one = Counters::default();
            let mut escaped = 0;
            let one: Vec<Orbit> = offsets.iter().map(|off| p.orbit(*off, &[], &mut [], &mut c_one, &NEVER)).collect();
            let bits = |o: &Orbit| (o.n, o.z.map(f64::to_bits), o.dz.map(f64::to_bits));
            let what = format!("{radius} derivative {derivative} interior {interior:?}");
            // The turns of a nucleus's reference in their own loop and in the general
            // one: the same bits and counts.
            let general = Perturbation {
                refs: p.refs.clone(),
                bla_fe: p.bla_fe.clone(),
                bla_f64: p.bla_f64.clone(),
                turn_loop: false,
                ..p
            };
            let mut c_general = Counters::default();
            for (k, off) in offsets.iter().enumerate() {
                let o = general.orbit(*off, &[], &mut [], &mut c_general, &NEVER);
                assert_eq!(bits(&o), bits(&one[k]), "{what}: sample {k} differs through the general loop");
            }
            assert_eq!(c_general, c_one, "{what}: counts through the general loop");
            // With disks, the same bits, and the same samples found interior, as each
            // sample iterated; without them, the same counts too.
            let each = Perturbation {
                refs: p.refs.clone(),
                bla_fe: p.bla_fe.clone(),
                bla_f64: p.bla_f64.clone(),
                disks: false,
                ..p
            };
            for simd in SimdLevel::usable() {
                // Every sample through the batch loop, held to its bits alone.
                let run = |engine: &Perturbation, how: &str| {
                    let mut many = vec![Orbit::interior(); offsets.len()];
                    let mut c = Counters::default();
                    engine.orbits(&offsets, &mut many, &mut c, simd, &NEVER);
                    for k in 0..offsets.len() {
                        assert_eq!(bits(&many[k]), bits(&one[k]), "{what} {simd}{how}: sample {k}");
                    }
                    c
                };
                let c_disks = run(&p, " with disks");
                let counts = |c: &Counters| (c.interior, c.newton);
                assert_eq!(counts(&c_disks), counts(&c_one), "{what} {simd} with disks");
                disks += c_disks.disks;
                let c_many = run(&each, "");
                // Bursts with their addresses in vector registers where lanes rebase often
                // (as on AMD's cores) and in memory throughout (as on others): both forced,
                // whichever this CPU picks.
                if simd != SimdLevel::Scalar {
                    let held = &lanes::burst::HELD_IN_TESTS;
                    for choice in [false, true] {
                        held.set(Some(choice));
                        let c = run(&each, if choice { " addresses held" } else { " addresses in memory" });
                        held.set(None);
                        assert_eq!(c, c_many, "{what} {simd}: counts with addresses held {choice}");
                    }
                }
                // A vector level runs its own lanes, never the scalar loop in their place
                // (which would pass every comparison above without testing them).
                let mut lanes_out = vec![Orbit::interior(); offsets.len()];
                let mut c_lanes = Counters::default();
                let ran = lanes::orbits(&each, &offsets, None, &mut lanes_out, &mut c_lanes, simd, &NEVER);
                assert_eq!(ran, simd != SimdLevel::Scalar, "{what} {simd}: its lanes ran");
                escaped += one.iter().filter(|o| o.n != crate::formula::end::INTERIOR).count() as u32;
                assert_eq!(c_many.iterations, c_one.iterations, "{what} {simd}: iteration counts");
                let steps = |c: &Counters| c.steps + c.bla_steps;
                assert_eq!(steps(&c_many), steps(&c_one), "{what} {simd}: step counts");
                assert_eq!(c_many.rebases, c_one.rebases, "{what} {simd}: rebases");
                assert_eq!(c_many.interior, c_one.interior, "{what} {simd}: samples found interior");
                assert_eq!(c_many.newton, c_one.newton, "{what} {simd}: samples found by Newton's test");
            }
            assert!(escaped > 0 && c_one.steps > 1000, "{radius}: the view must exercise single steps");
            // A packed tail with BLA: samples cross it by its blocks' steps too (the Julia
            // view's tail is its orbit of 0's, which samples follow after a rebase with
            // deltas as large as the orbit, too large for a block's step).
            let tail = packed && bla.is_some() && julia.is_none();
            assert!(c_one.tail_steps > 0 || !tail, "{what}: steps through the packed tail");
            assert!(c_one.tail_steps == 0 || bla.is_some(), "{what}: tail steps without BLA");
            match &without {
                None => {
                    assert_eq!(c_one.interior, 0, "{what}");
                    without = Some(one);
                }
                Some(off) => {
                    for k in 0..offsets.len() {
                        assert_eq!(bits(&one[k]), bits(&off[k]), "{what}: sample {k} differs from detection off");
                    }
                    found += c_one.interior;
                }
            }
        }
    }
    (found, disks)
}

#[test]
fn lanes_match_one_sample_at_a_time() {
    let eps = Some(crate::orbit::DEFAULT_BLA_TOLERANCE);
    same_both_ways(MINIBROT, None, "2e-30", 6000, Numbers::F64, eps, None);
    same_both_ways(MINIBROT, None, "2e-30", 6000, Numbers::F64, None, None);
    same_both_ways(MINIBROT, None, "1e-12", 3000, Numbers::F64, eps, None);
    same_both_ways(SEAHORSE, None, "2e-6", 5000, Numbers::F64, eps, None);
    same_both_ways(SEAHORSE, None, "2e-10", 5000, Numbers::F64, eps, None);
    same_both_ways(LIIIINES, None, "2e-310", 12500, Numbers::FloatExp, eps, None);
    same_both_ways(E50, None, "2e-50", 263010, Numbers::F64, eps, None);
    // Without BLA, |z| lingers at 2 and the derivative leaves its window in the lanes.
    same_both_ways(LIIIINES, None, "2e-310", 12500, Numbers::FloatExp, None, None);
    same_both_ways(JULIA_CENTER, Some(["-0.7436447860", "0.1318252536"]), "2e-40", 3000, Numbers::F64, eps, None);
    same_both_ways(JULIA_CENTER, Some(["-0.7436447860", "0.1318252536"]), "2e-40", 3000, Numbers::F64, None, None);
    // References packed after a few hundred iterations: the lanes hand samples back at
    // the dense part's end and the scalar loop takes them through the tail.
    same_both_ways(MINIBROT, None, "2e-30", 6000, Numbers::F64, eps, Some(400));
    same_both_ways(LIIIINES, None, "2e-310", 12500, Numbers::FloatExp, eps, Some(900));
    let julia = Some(["-0.7436447860", "0.1318252536"]);
    same_both_ways(JULIA_CENTER, julia, "2e-40", 3000, Numbers::F64, eps, Some(300));
}

/// The step the turn loop takes at Z_1 of a nucleus's reference without searching
/// ([`BlaTable::fixed_step`]) is the one the search finds, for every |δ|^2 below its
/// bound and every budget that holds it; at the bound, or with a budget one short, the
/// search finds another.
#[test]
fn the_turn_loops_step_is_the_one_the_search_finds() {
    let (w, h) = (32u32, 24u32);
    let spacing = Scale::Radius(Decimal::parse("1e-102").unwrap()).spacing(h);
    let max_offset = f64::from(w * w + h * h).sqrt() / 2.0;
    let spec = DeepSpec {
        escape_radius: 2.0,
        derivative: true,
        ..bla_spec(EYE_MINIBROT, spacing, max_offset, 100_000, crate::orbit::DEFAULT_BLA_TOLERANCE)
    };
    let p = prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
    let r = &p.refs[0];
    assert_eq!(r.period(), Some(r.last()), "one period of the nucleus's orbit");
    let table = p.bla_f64[0].as_ref().expect("tables");
    let (step, len, bound) = table.fixed_step(1).expect("an aligned step from Z_1");
    assert_eq!(1 + len, r.last(), "the step reaches the period's end");
    assert!(bound > 0.0, "{bound}");
    let same = |found: Option<(Step<'_, f64>, u32)>| {
        found.is_some_and(|(s, l)| l == len && std::ptr::eq(s.first, step.first) && std::ptr::eq(s.second, step.second))
    };
    for k in 0..400 {
        let z2 = bound * (1.0 - 1e-15) * 10f64.powf(-f64::from(k) / 10.0);
        for budget in [len, len + 1, u32::MAX] {
            assert!(same(table.lookup(1, z2, budget)), "|z|^2 = {z2:e}, budget {budget}");
        }
    }
    assert!(!same(table.lookup(1, bound, u32::MAX)), "at the bound");
    assert!(!same(table.lookup(1, bound * 0.5, len - 1)), "a budget one short");
}

/// The period-1429 minibrot of the all-seeing-eye location (size 1.6e-102): its
/// interior samples are found by detection in the vector lanes, the two-sample loop and
/// one at a time alike, with f64 and FloatExp deltas, with and without BLA.
#[test]
fn lanes_match_one_sample_at_a_time_with_interior_found() {
    let eps = Some(crate::orbit::DEFAULT_BLA_TOLERANCE);
    for (numbers, bla) in [(Numbers::F64, eps), (Numbers::FloatExp, eps), (Numbers::F64, None)] {
        let (found, disks) = same_both_ways(EYE_MINIBROT, None, "1e-102", 100_000, numbers, bla, None);
        assert!(found > 100, "{numbers:?} {bla:?}: {found} samples found interior");
        // Disks need f64 deltas (Newton's arithmetic).
        assert_eq!(disks > 0, numbers == Numbers::F64, "{numbers:?} {bla:?}: {disks} samples in disks");
    }
    // A nucleus's reference packed before its period ends: no Newton test, found by
    // the contraction alone.
    let (found, _) = same_both_ways(EYE_MINIBROT, None, "1e-102", 100_000, Numbers::F64, eps, Some(700));
    assert!(found > 100, "packed after 700: {found} samples found interior");
    // The whole of a Julia set whose parameter is inside the period-3 bulb (the rabbit).
    let (found, _) = same_both_ways(["0", "0"], Some(["-0.12", "0.75"]), "1.3", 20000, Numbers::F64, eps, None);
    assert!(found > 100, "rabbit: {found} samples found interior");
}

/// Samples that reach the end of a reference cut where it repeats itself
/// (`Reference::cycle`) go round its cycle and end exactly as they do along the whole
/// orbit computed to the limit: with BLA off both engines do the same operations on the
/// same values, so every escape, z_n and derivative is the same bits, on every SIMD level
/// this CPU has (the lanes hand a sample at the end back to the scalar loop, which wraps). The view is the e102
/// minibrot's interior off its nucleus (the reference repeats at iteration 265001), and
/// the samples are by its exterior, where they escape after millions of iterations, past
/// many turns of the cycle.
#[test]
fn samples_go_round_a_repeating_reference_as_along_the_whole_orbit() {
    const OFF_NUCLEUS: [&str; 2] = [
        "-0.83031842675693053553109980802050591726924580592100415017586803599827560339120465373468510811787516730485186454892834980632246054605795",
        "0.23612476396680780363307856325882633547132442124365456398110558858530832926040168389957117374824216611996058042279006600832794659929318",
    ];
    let max_iter = 7_000_000;
    let spec = DeepSpec {
        center: dec(OFF_NUCLEUS),
        julia: None,
        spacing: Scale::Zoom(Decimal::parse("1.7e102").unwrap()).spacing(300),
        max_offset: 250.0,
        max_iter,
        escape_radius: 65536.0,
        derivative: true,
        bla: None,
        interior: Detection::Off,
        numbers: Numbers::F64,
        simd: SimdLevel::detect(),
        references: None,
        dense_orbit: None,
    };
    let cut = prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
    let w = cut.refs[0].cycle().expect("the reference repeats itself");
    let end = cut.refs[0].last();
    let steps = reference::Stepping { cut_cycles: false, ..crate::orbit::stepping(&spec, false) };
    let c = dec(OFF_NUCLEUS).map(|d| crate::num::bigfloat::from_decimal(&d, cut.refs[0].bits()));
    let z0 = [Float::from(0.0), Float::from(0.0)];
    let never = AtomicBool::new(false);
    let bits = cut.refs[0].bits();
    let whole = Reference::compute(&z0, &c, max_iter, 65536.0, bits, steps, &|_| {}, &never).expect("whole orbit");
    assert_eq!((whole.cycle(), whole.end()), (None, max_iter));
    let along = prepare(&DeepSpec { references: Some(std::sync::Arc::new(vec![whole])), ..spec }, &|_, _| {}, &never)
        .expect("prepared");
    // Pixel (252, 116) of scenes/long-orbit-e102.toml and its neighbours, in spacings.
    let offsets: Vec<[f64; 2]> =
        (0..16).map(|k| [51.0 + f64::from(k % 4) * 0.5, 32.0 + f64::from(k / 4) * 0.5]).collect();
    let run = |p: &Perturbation, simd: SimdLevel| {
        let mut out = vec![Orbit::interior(); offsets.len()];
        p.orbits(&offsets, &mut out, &mut Counters::default(), simd, &never);
        out
    };
    // Along the whole orbit in the scalar loop: what every level must give, cut or not.
    let want = run(&along, SimdLevel::Scalar);
    let bits = |o: &Orbit| (o.n, o.z.map(f64::to_bits), o.dz.map(f64::to_bits));
    let mut got = want.clone();
    for simd in SimdLevel::usable() {
        for (engine, p) in [("cut", &cut), ("whole", &along)] {
            got = run(p, simd);
            for (k, (g, x)) in got.iter().zip(&want).enumerate() {
                assert_eq!(bits(g), bits(x), "{simd}, {engine} orbit: sample {k} at {:?}", offsets[k]);
            }
        }
    }
    let past = got.iter().filter(|o| o.n != crate::formula::end::INTERIOR && o.n > end + w).count();
    assert!(past >= 2, "samples that escaped after going round the cycle: {past} ({got:?})");
}

/// The view's series ([`Series`]) against direct big-float iteration of each sample (big
/// floats at 100 bits past the spacing, written out here, not the engine's reference): where
/// a sample's bounds let it start from the series, its delta stands for an offset within
/// 1e-9 of its spacing and its derivative is within 1e-9 of itself (the truncation is held
/// to 1e-10 at ε = 1e-14; the rounding's worst-case bound only to 1e-6, and this checks
/// that the rounding itself stays far below that). At the bench-e14 location, two zooms of the seahorse descent and a
/// Julia set, with and without a derivative; the series reaches past the BLA skip and
/// serves most samples of each view.
#[test]
fn series_agrees_with_big_float_iteration() {
    use crate::num::bigcomplex::BigC;
    const E14: [&str; 2] = [
        "-1.759817130804847813610825010561798238243999999999999999999800",
        "-0.012593310799749865383746631843264858450340000000000000000000",
    ];
    const SEAHORSE: [&str; 2] = ["-0.743643887037158704752191506114774", "0.131825904205311970493132056385139"];
    // (centre, Julia parameter, radius, width, height, iteration limit, least reach: the
    // iterations the degree-32 series of the module's bounds reached in a model of them, for
    // the Mandelbrot views; the Julia view's only has to pass the skip)
    type View = ([&'static str; 2], Option<[&'static str; 2]>, &'static str, f64, f64, u32, u32);
    let views: [View; 4] = [
        (E14, None, "2e-14", 800.0, 600.0, 4036, 300),
        (SEAHORSE, None, "2e-8", 1024.0, 768.0, 5000, 600),
        (SEAHORSE, None, "2e-10", 1024.0, 768.0, 5000, 900),
        (["0.3", "0.01"], Some(["-0.8", "0.156"]), "1e-9", 400.0, 300.0, 3000, 0),
    ];
    for (center, julia, radius, w, h, max_iter, reach) in views {
        for derivative in [false, true] {
            let max_offset = f64::hypot(w, h) / 2.0;
            let spacing = Scale::Radius(Decimal::parse(radius).unwrap()).spacing(h as u32);
            let spec = DeepSpec {
                julia: julia.map(dec),
                derivative,
                ..bla_spec(center, spacing, max_offset, max_iter, 1e-14)
            };
            let p = prepare(&spec, &|_, _| {}, &AtomicBool::new(false)).expect("prepared");
            let what = format!("{radius} at {center:?}, derivative {derivative}");
            let series = p.series.expect("the series reaches past the BLA skip");
            let skip = p.skip.map_or(0, |k| k.m);
            assert!(series.far.m >= reach && series.far.m > skip, "{what}: reach {} (skip {skip})", series.far.m);
            let bits = crate::num::bigfloat::precision_for(spacing.log2() / std::f64::consts::LOG2_10) + 100;
            let big = |v: [&str; 2]| {
                BigC::from_decimals(&Decimal::parse(v[0]).unwrap(), &Decimal::parse(v[1]).unwrap(), bits)
            };
            let fe = |v: [FloatExp; 2]| {
                let part = |x: FloatExp| {
                    if x.is_zero() {
                        BigC::zero(bits)
                    } else {
                        BigC::from_f64(x.mantissa(), 0.0, bits).ldexp(x.exponent())
                    }
                };
                let (re, im) = (part(v[0]), part(v[1]));
                BigC { re: re.re, im: im.re, bits }
            };
            let (centre, param) = (big(center), julia.map(big));
            let (mut served, mut tried) = (0, 0);
            let mut dcs = Vec::new();
            for k in 0..48 {
                // Rings out to the view's corners, and the corners themselves.
                let angle = k as f64 * 0.61803398875 * std::f64::consts::TAU;
                let scale = if k < 4 { 1.0 } else { ((k % 12) as f64 + 0.5) / 12.0 };
                let off = if k < 4 {
                    [if k % 2 == 0 { w / 2.0 } else { -w / 2.0 }, if k < 2 { h / 2.0 } else { -h / 2.0 }]
                } else {
                    [scale * max_offset * angle.cos() * 0.8, scale * max_offset * angle.sin() * 0.6]
                };
                let dc = [spacing.mul_f64(off[0]), spacing.mul_f64(off[1])];
                dcs.push(dc);
                tried += 1;
                let Some(st) = series.start(dc, spacing, derivative) else { continue };
                served += 1;
                // z_m and dz_m/d(offset) of the sample, and Z_m of the centre, directly.
                let one = BigC::from_f64(1.0, 0.0, bits);
                let zero = BigC::zero(bits);
                let (mut z, mut dz, c) = match &param {
                    None => (BigC::zero(bits), BigC::zero(bits), centre.add(&fe(dc))),
                    Some(c) => (centre.add(&fe(dc)), one.clone(), c.clone()),
                };
                let mut zr = if param.is_some() { centre.clone() } else { BigC::zero(bits) };
                let start = if param.is_some() { 0 } else { 1 };
                let add = if param.is_some() { &zero } else { &one };
                if start == 1 {
                    (z, dz) = (c.clone(), one.clone());
                    zr = zr.square().add(&centre);
                }
                for _ in start..st.m {
                    dz = z.mul(&dz).ldexp(1).add(add);
                    z = z.square().add(&c);
                    zr = zr.square().add(param.as_ref().unwrap_or(&centre));
                }
                let delta = z.sub(&zr);
                let err = |a: [FloatExp; 2], b: &BigC| fe(a).sub(b).abs().to_f64();
                let slope = dz.abs().to_f64() * spacing.to_f64();
                let e = err(st.dz, &delta) / slope;
                assert!(e <= 1e-9, "{what}: offset {off:?} from iteration {}: {e:e} of a spacing", st.m);
                if derivative {
                    let scaled = dz.mul(&BigC::from_f64(spacing.to_f64(), 0.0, bits));
                    let e = err(st.der, &scaled) / slope;
                    assert!(e <= 1e-9, "{what}: offset {off:?}: derivative off by {e:e} of itself");
                }
            }
            assert!(served * 10 >= tried * 9, "{what}: {served} of {tried} samples started from the series");
            // Eight at a time (`Series::starts`, as the lanes' feed takes them), the same
            // starts bit for bit, and the same refusals past the series' disk.
            dcs.extend((0..8).map(|i| [spacing.mul_f64(max_offset * (1.2 + 0.1 * i as f64)), spacing.mul_f64(1.0)]));
            let bits = |v: [FloatExp; 2]| v.map(|x| (x.mantissa().to_bits(), x.exponent()));
            let key = |s: Option<super::series::Start>| s.map(|s| (bits(s.dz), bits(s.der), s.m));
            let mut refused = 0;
            for chunk in dcs.chunks_exact(8) {
                let many = series.starts::<8>(chunk.try_into().expect("eight"), spacing, derivative);
                for (dc, s) in chunk.iter().zip(many) {
                    let one = series.start(*dc, spacing, derivative);
                    refused += usize::from(one.is_none());
                    assert_eq!(key(s), key(one), "{what}: δc {dc:?} in a batch of eight");
                }
            }
            assert!(refused >= 8, "{what}: {refused} samples refused, the 8 past the disk among them");
        }
    }
}
