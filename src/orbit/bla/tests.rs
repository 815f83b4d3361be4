//! Tests of the BLA tables: merged steps against single steps, validity radii, the f64 tables against the FloatExp ones.

use malachite_float::Float;
use std::sync::atomic::AtomicBool;

use super::*;
use crate::num::real::norm2;

fn cabs(v: [FloatExp; 2]) -> FloatExp {
    norm2(v).sqrt()
}

#[test]
fn merged_step_matches_iterated_steps_to_second_order() {
    // Reference at c = -0.75 + 0.1i; one merged step over 4 iterations equals four exact
    // perturbed steps, at a delta where the linear terms alone would be far off.
    let c = [Float::from(-0.75), Float::from(0.1)];
    let z0 = [Float::from(0.0), Float::from(0.0)];
    let r = Reference::compute(&z0, &c, 64, 1e10, 128, Default::default(), &|_| {}, &AtomicBool::new(false)).unwrap();
    let dc = [FloatExp::from(1e-9), FloatExp::from(-2e-9)];
    let eps = 1e-6;
    let t = BlaTable::build(&r, 1, true, eps, cabs(dc), 2.0);
    let start = [FloatExp::from(3e-5), FloatExp::from(1e-5)];
    let (e, len) = t.lookup(1, norm2(start), 4).expect("valid");
    assert_eq!(len, 4);
    // Exact steps, with the derivative d(z)/d(c) carried from 0.
    let (mut z, mut dz) = (start, [FloatExp::ZERO; 2]);
    for m in 1..5 {
        let zm = r.get_fe(m);
        let two_z = [zm[0].ldexp(1), zm[1].ldexp(1)];
        let w = cadd(two_z, z);
        dz = cadd(cmul(cadd(two_z, [z[0].ldexp(1), z[1].ldexp(1)]), dz), [FloatExp::ONE, FloatExp::ZERO]);
        z = cadd(cmul(w, z), dc);
    }
    let err = |v: [FloatExp; 2], w: [FloatExp; 2]| cabs(cadd(v, [-w[0], -w[1]])).to_f64() / cabs(w).to_f64();
    let step = e.apply(start, dc);
    assert!(err(step, z) <= 4.0 * eps, "second order: relative error {}", err(step, z));
    let linear = cadd(cmul(e.first.a, start), cmul(e.first.b, dc));
    assert!(err(linear, z) > 100.0 * eps, "the delta must be past first order: {}", err(linear, z));
    // The Jacobian's offset column is the derivative from a zero one.
    let (_, _, n) = e.apply_with_jacobian(start, dc);
    assert!(err(n, dz) <= 4.0 * eps, "derivative: relative error {}", err(n, dz));
    // Too large a delta gets no step; an unaligned index gets none longer than allowed.
    assert!(t.lookup(1, FloatExp::from(1.0), 64).is_none());
    assert_eq!(t.lookup(3, FloatExp::from(1e-24), 64).map(|x| x.1), Some(2));
    assert!(t.lookup(2, FloatExp::from(1e-24), 64).is_none());
}

/// Exact perturbed steps from index `m`: `len` of them from delta `z` at offset `dc`.
fn iterate(r: &Reference, m: u32, len: u32, start: [FloatExp; 2], dc: [FloatExp; 2]) -> [FloatExp; 2] {
    let mut z = start;
    for k in m..m + len {
        let zm = r.get_fe(k);
        z = cadd(cmul(cadd([zm[0].ldexp(1), zm[1].ldexp(1)], z), z), dc);
    }
    z
}

fn rel_err(v: [FloatExp; 2], w: [FloatExp; 2]) -> f64 {
    cabs(cadd(v, [-w[0], -w[1]])).to_f64() / cabs(w).to_f64()
}

/// A reference next to the period-3 nucleus c = -1.7548776662466927...: its orbit comes
/// back near 0 every 3 iterations, closer at the multiples of 3 of later near-periods.
fn airship() -> Reference {
    let c = [Float::from(-1.754877666246), Float::from(1e-9)];
    let z0 = [Float::from(0.0), Float::from(0.0)];
    Reference::compute(&z0, &c, 4000, 2.0, 128, Default::default(), &|_| {}, &AtomicBool::new(false)).unwrap()
}

/// [`airship`] with its table: tolerance 1e-8, offsets up to |(1 + 2i) 1e-14|, and that
/// offset.
fn airship_table() -> (Reference, BlaTable<FloatExp>, f64, [FloatExp; 2]) {
    let r = airship();
    let (eps, dc) = (1e-8, [FloatExp::from(1e-14), FloatExp::from(2e-14)]);
    let t = BlaTable::build(&r, 1, true, eps, cabs(dc), 2.0);
    (r, t, eps, dc)
}

/// Steps of whole blocks past the tree, through a dense orbit and through a packed tail
/// cut at the same index: the same steps (the same values, folded alike), and each
/// matches the exact perturbed steps it skips to second order, from single blocks to
/// the longest the delta allows. The reference lies inside the main cardioid, near its
/// edge (multiplier 0.98): a long orbit that neither escapes nor dips towards 0, so that
/// steps hold deltas whose second-order terms count.
#[test]
fn steps_of_blocks_match_iterated_steps_dense_and_packed() {
    let c = [Float::from(-0.7), Float::from(0.2)];
    let z0 = [Float::from(0.0), Float::from(0.0)];
    let compute = |dense_limit| {
        let steps = crate::orbit::reference::Stepping { dense_limit, ..Default::default() };
        Reference::compute(&z0, &c, 4000, 2.0, 128, steps, &|_| {}, &AtomicBool::new(false)).unwrap()
    };
    let (dense, packed) = (compute(None), compute(Some(1000)));
    assert!(packed.packed().is_some() && dense.last() > 3000, "a long orbit, packed after 1000");
    let (eps, dc) = (1e-8, [FloatExp::from(1e-14), FloatExp::from(2e-14)]);
    let tables = |r: Reference| {
        let refs = Arc::new(vec![r]);
        let how = tail::Build::new(true, eps, cabs(dc), 2.0);
        BlaTable::build_with_tree(&refs[0], 1, how, 1000).with_blocks(refs, 0, true)
    };
    let (td, tp) = (tables(dense.clone()), tables(packed.clone()));
    assert!(td.built().is_none(), "built only when first needed");
    let never = &cancel::NEVER;
    let (bd, bp) = (
        td.blocks(never).unwrap().expect("blocks past the tree"),
        tp.tail(never).unwrap().expect("blocks in the tail"),
    );
    assert!(tp.blocks(never).unwrap().is_none() && td.tail(never).unwrap().is_none());
    assert_eq!((bd.first(), bp.first(), bd.block()), (1000, 1000, 16));
    let (mut longest, mut quadratic) = (0, 0);
    for m in (1000..dense.last()).step_by(16) {
        for d in [1e-30, 1e-20, 1e-14, 1e-10, 1e-8, 1e-6, 1e-5, 1e-4, 1e-3] {
            let start = [FloatExp::from(d), FloatExp::from(-0.5 * d)];
            let (a, b) = (bd.lookup(m, norm2(start), 4000), bp.lookup(m, norm2(start), 4000));
            assert_eq!(a.as_ref().map(|x| (x.1, x.2)), b.as_ref().map(|x| (x.1, x.2)), "at {m}");
            let Some((step, len, end)) = a else { continue };
            let other = b.expect("the same step").0;
            assert_eq!(step.apply(start, dc), other.apply(start, dc), "at {m}: the same step");
            assert_eq!(bp.reader(end).map(|r| r.index()), Some(m + len), "the tail's reader at the end");
            // The table's own lookup past the tree gives the dense blocks' step.
            assert_eq!(td.lookup(m, norm2(start), 4000).map(|x| x.1), Some(len));
            let want = iterate(&dense, m, len, start, dc);
            let err = rel_err(step.apply(start, dc), want);
            assert!(err <= 4.0 * eps, "at {m}, |delta| {d}, {len} iterations: relative error {err}");
            longest = longest.max(len);
            let linear = cadd(cmul(step.first.a, start), cmul(step.first.b, dc));
            quadratic += usize::from(rel_err(linear, want) > 100.0 * eps);
        }
    }
    assert!(longest >= 256, "steps over many blocks: the longest {longest}");
    assert!(quadratic > 10, "steps where the second order counts: {quadratic}");
}

#[test]
fn dips_keep_the_first_and_each_new_low() {
    let mag2 = [1.0, 1.0, 1e-5, 1.0, 1.0, 1e-5, 1.0, 1e-12];
    let f = |i: u32| FloatExp::from(mag2[i as usize]);
    let stage0 = dips(0..8, f);
    assert_eq!(stage0, [0, 2, 5, 7]);
    // Among the marks, 5 dips no deeper than 2: only 7 is a longer near-period's return.
    assert_eq!(dips(stage0.iter().copied(), f), [0, 7]);
    assert_eq!(dips([0, 7], f), [0]);
    assert!(dips([], f).is_empty());
}

#[test]
fn steps_run_from_dip_to_dip_and_match_iterated_steps() {
    let (r, t, eps, dc) = airship_table();
    let s = &t.stages;
    assert!(s.len.len() > 10, "the orbit's near-periods give period-aligned steps");
    // Stage 0's first step ends at the first dip: where the reference comes nearer to 0
    // than a 64th of anywhere on the way.
    let end = 1 + s.len[s.at[0] as usize];
    let dip = cabs(r.get_fe(end)).mul_f64(64.0);
    for m in 2..end {
        assert!(cabs(r.get_fe(m)) > dip, "Z_{m} is not far above the step's end Z_{end}");
    }
    // A tiny delta from the origin: the longest step is a period-aligned one (the
    // reference's dips lie at multiples of 3), and it agrees with iterating.
    let start = [FloatExp::from(1e-13), FloatExp::from(-1e-13)];
    let (e, len) = t.lookup(1, norm2(start), u32::MAX).expect("a step");
    assert!(!len.is_power_of_two(), "length {len}");
    let err = rel_err(e.apply(start, dc), iterate(&r, 1, len, start, dc));
    assert!(err <= 100.0 * eps, "over {len} iterations: relative error {err}");
    // Every stored step agrees with iterating, for a delta at a tenth of its radius.
    let mut checked = 0;
    for i in 0..t.levels[0].len() as u32 * 2 {
        if !s.marked(i) {
            continue;
        }
        for k in s.at[i as usize] as usize..s.at[i as usize + 1] as usize {
            let radius = s.start2[k].sqrt().to_f64();
            if radius.is_nan() || radius <= 1e-30 {
                continue;
            }
            let z = [FloatExp::from(0.06 * radius), FloatExp::from(-0.08 * radius)];
            let step = Step { first: &s.first[k], second: &s.second[k] };
            let m = i + 1;
            // Only where the loop would step from here: no rebase, no escape at m.
            let full = cadd(r.get_fe(m), z);
            if norm2(full) < norm2(z) || norm2(full).to_f64() > 4.0 {
                continue;
            }
            let err = rel_err(step.apply(z, dc), iterate(&r, m, s.len[k], z, dc));
            assert!(err <= 100.0 * eps, "step {k} from {m} over {}: relative error {err}", s.len[k]);
            checked += 1;
        }
    }
    assert!(checked > 10, "{checked} steps checked");
}

#[test]
fn a_delta_tested_at_a_dip_steps_on_where_an_untested_one_may_not() {
    let (r, t, eps, dc) = airship_table();
    // A dip deep inside the orbit, and a delta as large as the reference there, in the
    // same direction: |Z + δ| = 2 |δ|, so the loop does not rebase, but the delta is
    // beyond |Z_m| / 2, where a run may not start untested.
    let i = (1..t.levels[0].len() as u32 * 2).rev().find(|&i| t.stages.marked(i) && i % 3 == 2).expect("a dip");
    let m = i + 1;
    let zm = r.get_fe(m);
    let z = zm;
    assert!(norm2(cadd(zm, z)) >= norm2(z));
    let (e, len) = t.lookup(m, norm2(z), u32::MAX).expect("a step from a tested delta");
    assert!(len > 1);
    let untested = t.lookup_untested(m, norm2(z), u32::MAX).map_or(0, |x| x.1);
    assert!(untested < len, "untested {untested}, tested {len}");
    let err = rel_err(e.apply(z, dc), iterate(&r, m, len, z, dc));
    assert!(err <= 100.0 * eps, "over {len} iterations from the dip at {m}: relative error {err}");
}

/// The tables are built level by level on every thread of the pool (each merge a pure
/// function of its two inputs): built on one thread and on four they are the same bits, in
/// both number types (the 1e50 benchmark's centre, at that view's precision).
#[test]
fn tables_built_on_any_number_of_threads_are_the_same_bits() {
    let c = [
        "-0.04947002906310409375169222672735363011874571248822487931810494023264219477268690",
        "-0.67478757584467536401139205313059765633477070682240348069799979479099419834548451",
    ]
    .map(|t| crate::num::bigfloat::from_decimal(&crate::num::Decimal::parse(t).unwrap(), 300));
    let z0 = [Float::from(0.0), Float::from(0.0)];
    let r =
        Reference::compute(&z0, &c, 30_000, 1e10, 300, Default::default(), &|_| {}, &AtomicBool::new(false)).unwrap();
    assert!(r.last() > 10_000, "{} iterations", r.last());
    let dc = FloatExp::from(1e-49);
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| {
            let t = BlaTable::build(&r, 1, true, 1e-14, dc, 1e10);
            (format!("{t:?}"), format!("{:?}", t.to_f64()))
        })
    };
    let one = on(1);
    assert!(one == on(4), "tables built on 1 and 4 threads differ");
}
