//! The lanes' bursts: plain steps of every vector while nothing can happen but a step, the
//! deltas in registers and the only test per step one for an event ([`burst`]), and the
//! rebases a burst takes in the lane ([`settle`] brings the samples' records up to date
//! after it; [`Rate`] decides from how often they happen where a burst holds its lanes'
//! addresses). Split from the lanes' loop (`lanes.rs`, whose module doc says how the two
//! meet) as the part that runs nearly all of a deep view's single steps.
#![allow(unsafe_code)]

use super::*;

/// The lanes that rebased inside a burst (see [`burst`]): every vector's lanes that rebased
/// at least once, those of them that leave the lanes after their step from Z_0 (their delta
/// at or below `single_d2`, where the scalar loop looks for a BLA step), and how many
/// rebases were taken.
#[derive(Clone, Copy, Default)]
pub(super) struct Moved {
    pub(super) rebased: [u32; G],
    pub(super) leave: [u32; G],
    pub(super) count: u64,
    /// Steps every lane took in the burst.
    pub(super) steps: u64,
}

/// How often the lanes have rebased inside bursts so far, which decides where the next
/// burst holds its lanes' addresses (see [`retarget`]).
#[derive(Clone, Copy)]
pub(super) struct Rate {
    rebases: u64,
    lane_steps: u64,
    /// Whether this CPU takes addresses out of vector registers cheaply ([`held_pays`]).
    held: bool,
}

impl Rate {
    /// A rebase in more than one lane step in this many: the addresses in vector registers.
    const OFTEN: u64 = 150;

    pub(super) fn new() -> Rate {
        Rate { rebases: 0, lane_steps: 0, held: held_pays() }
    }

    pub(super) fn add(&mut self, moved: &Moved, lanes: usize) {
        self.rebases += moved.count;
        self.lane_steps += moved.steps * (lanes * G) as u64;
    }

    /// Whether lanes rebase often enough that the burst holds the addresses in registers,
    /// on a CPU where that pays.
    pub(super) fn often(&self) -> bool {
        self.held && self.rebases * Self::OFTEN > self.lane_steps
    }
}

/// Whether holding a burst's addresses in vector registers ([`retarget`]) can pay on this
/// CPU: on AMD's cores (measured on Zen 4, against [`retarget_apart`] when it was a call;
/// not measured there since it is inlined), not on Intel's. A burst that holds them takes
/// each lane's address out of a vector register for its load (`vmovq`, `vpextrq`,
/// `vextracti32x4`: 22 operations every two steps of 16 lanes with AVX-512), and on Intel's
/// cores those run on the port that also takes every 512-bit shuffle, every comparison into
/// a mask and half of the 512-bit arithmetic, which the lanes already keep busy: on a Xeon
/// of the Emerald Rapids generation the seahorse at zoom 1e6 took 1.05 s with them held and
/// 0.96 s without (the call still in place), and 1.33 against 1.25 s with `--simd avx2`
/// (docs/performance.md, "The 1e5–1e15 range"). Speed only: both places give the same
/// bits, and the lanes' tests run both on every CPU.
fn held_pays() -> bool {
    #[cfg(test)]
    if let Some(held) = HELD_IN_TESTS.get() {
        return held;
    }
    #[cfg(target_arch = "x86_64")]
    {
        static AMD: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        *AMD.get_or_init(|| {
            let id = std::arch::x86_64::__cpuid(0);
            // "AuthenticAMD" in EBX, EDX, ECX.
            [id.ebx, id.edx, id.ecx] == [0x6874_7541, 0x6974_6e65, 0x444d_4163]
        })
    }
    #[cfg(not(target_arch = "x86_64"))]
    true
}

/// Plain steps of every vector while nothing can happen but a step: every lane active,
/// none just rebased, none within reach of its stop, and (tested before each step) no lane
/// at an event. The deltas stay in registers for the whole run and each lane's Z_m is read
/// at its start address plus the bytes stepped, so a step is the arithmetic and the loads
/// alone. Returns before the first step at which any lane of any vector has an event,
/// leaving it to [`step`]: every vector has then taken the same number of steps, each
/// exactly as [`step`] takes it.
///
/// With `REBASE`, a rebase is not such an event: the lane's delta becomes its full value and
/// it steps at once from Z_0 = 0 of the orbit of 0, as the scalar loop's `op` does (a rebase
/// and the step after it in one call), and it goes on from Z_1 there. Near the 1e6 zooms of
/// an ordinary descent a sample rebases about every 50 steps: with 16 lanes in flight, a
/// burst that ended at each rebase ran three steps on average and [`step`] took the rest.
/// A lane whose delta after that step is at or below `single_d2` ends the burst (the scalar
/// loop looks for a BLA step for it, as `op`'s next call would; [`settle`] hands it back).
#[inline(always)]
pub(super) fn burst<U: Unit, const DER: bool, const REBASE: bool, const HELD: bool>(
    u: U,
    lanes: &mut [Lanes<U>; G],
    k: &Consts<U>,
    refs: &Refs,
    p: &Perturbation,
) -> Moved {
    let mut moved = Moved::default();
    let full = Lanes::<U>::FULL;
    if per_vector!(|g| lanes[g].act != full || lanes[g].fresh != 0) != [false; G] {
        return moved;
    }
    // Pairs of steps while every vector has two steps before any stop.
    let [r0, r1] = per_vector!(|g| (lanes[g].next_stop - lanes[g].t16) / 32);
    let room = r0.min(r1);
    if room < 2 {
        return moved;
    }
    let mut at: [[usize; MAX_W]; G] = per_vector!(|g| lanes[g].addresses(refs));
    let mut d: [Z<U>; G] = per_vector!(|g| (lanes[g].dzr, lanes[g].dzi));
    let c: [Z<U>; G] = per_vector!(|g| (lanes[g].dcr, lanes[g].dci));
    let mut der: [Z<U>; G] = per_vector!(|g| (lanes[g].der_r, lanes[g].der_i));
    let add: [U::f64s; G] = per_vector!(|g| lanes[g].add);
    let mut off = 0usize;
    let mut end = room as usize * 32;
    // Lanes that rebased at the first step of the pair (their second step reads Z_1), and
    // Z_1 of the orbit of 0 in every lane.
    let mut first = [0u32; G];
    let mut first_m: [U::m64s; G] = [u.less_than_f64s(k.zero, k.zero); G];
    let which = p.refs.len() - 1;
    let (zero, last) = (refs.start[which] as usize, p.refs[which].last() as usize);
    let z1 = if REBASE { p.refs[which].get(1) } else { [0.0; 2] };
    let z1: Z<U> = (u.splat_f64s(z1[0]), u.splat_f64s(z1[1]));
    'pairs: while off < end {
        // SAFETY: every lane is active and at least two steps from its stop (`room`, and
        // `end` lowered for a lane that rebased), so Z_m and Z_m+1 lie inside its reference.
        let z: [(Z<U>, Z<U>); G] = per_vector!(|g| unsafe { u.load_pair(&at[g].map(|x| x.wrapping_add(off))) });
        for second in [false, true] {
            let mut zs: [Z<U>; G] = per_vector!(|g| if second { z[g].1 } else { z[g].0 });
            if REBASE && second && first != [0; G] {
                zs = per_vector!(|g| (
                    u.select_f64s(first_m[g], z1.0, zs[g].0),
                    u.select_f64s(first_m[g], z1.1, zs[g].1)
                ));
                first = [0; G];
            }
            // Z_m + δ of every vector, which the event test and the derivative's step share
            // (a lane that rebases at this step steps from Z_0 = 0 with δ = Z_m + δ: the
            // same full value).
            let f: [Z<U>; G] = per_vector!(|g| plus(u, zs[g], d[g]));
            // A step after which a derivative must be renormalised is left to `step`, which
            // hands the sample back for it; tested before anything changes, a rebase
            // included (`step` takes the rebase and the step together, and after it the
            // look for a BLA step).
            let next: [Z<U>; G] = if DER { per_vector!(|g| der_step(u, k, f[g], der[g], add[g])) } else { der };
            if DER && per_vector!(|g| renorm_bits(u, k, next[g])) != [0; G] {
                break 'pairs;
            }
            let mut ev = event::<U, DER>(u, k, f[0], d[0]);
            for g in 1..G {
                ev = u.or_m64s(ev, event::<U, DER>(u, k, f[g], d[g]));
            }
            let mut now = [0u32; G];
            if u.bits(ev) != 0 {
                if !REBASE {
                    break 'pairs;
                }
                let esc = per_vector!(|g| u.bits(u.greater_than_f64s(norm(u, f[g]), k.esc2)));
                if esc != [0; G] {
                    break 'pairs;
                }
                // With the derivative, a step from a tiny |z| is the scalar loop's.
                if DER && per_vector!(|g| u.bits(u.less_than_f64s(norm(u, f[g]), k.tiny))) != [0; G] {
                    break 'pairs;
                }
                // Any other event is a rebase: δ becomes the full value and this step reads
                // Z_0 = 0 (the derivative steps from the full value, as `op`'s does).
                let reb: [U::m64s; G] = per_vector!(|g| u.less_than_f64s(norm(u, f[g]), norm(u, d[g])));
                for g in 0..G {
                    d[g] = (u.select_f64s(reb[g], f[g].0, d[g].0), u.select_f64s(reb[g], f[g].1, d[g].1));
                    zs[g] = (u.select_f64s(reb[g], k.zero, zs[g].0), u.select_f64s(reb[g], k.zero, zs[g].1));
                }
                now = per_vector!(|g| u.bits(reb[g]) & full);
                for g in 0..G {
                    // The lane reads Z_1 of the orbit of 0 after this step: its address at
                    // `off + 16` is Z_0's plus 16. Its stop is settled after the burst.
                    if HELD {
                        retarget(&mut at[g], now[g], zero.wrapping_sub(off));
                    } else {
                        retarget_apart(&mut at[g], now[g], zero.wrapping_sub(off));
                    }
                    moved.rebased[g] |= now[g];
                    moved.count += u64::from(now[g].count_ones());
                }
                // A lane's new stop is `last` steps on, or the iteration limit, which is
                // where it stood before the rebase and so no earlier than `end`.
                end = end.min((off + 16 * last) / 32 * 32);
                if !second {
                    (first, first_m) = (now, reb);
                }
            }
            der = next;
            for g in 0..G {
                d[g] = plain(u, k, zs[g], d[g], c[g]);
            }
            off += 16;
            if REBASE && now != [0; G] {
                // `op` looks for a BLA step after a rebase's step unless |δ|^2 > single_d2.
                moved.leave = per_vector!(|g| !u.bits(u.greater_than_f64s(norm(u, d[g]), k.single_d2)) & now[g]);
                if moved.leave != [0; G] {
                    break 'pairs;
                }
            }
        }
    }
    moved.steps = off as u64 / 16;
    for (g, l) in lanes.iter_mut().enumerate() {
        (l.dzr, l.dzi) = d[g];
        if DER {
            (l.der_r, l.der_i) = der[g];
        }
        l.t16 += off as i64;
        if moved.rebased[g] != 0 {
            replace(l, &at[g], moved.rebased[g], off, which, p, refs);
        }
    }
    moved
}

#[cfg(test)]
thread_local! {
    /// A test's choice for [`held_pays`] on its own thread, so that both places for the
    /// addresses run on every CPU.
    pub(in crate::orbit::perturb) static HELD_IN_TESTS: std::cell::Cell<Option<bool>> = const { std::cell::Cell::new(None) };
}

/// Sets `at[i]` to `to` in every lane of `mask`, without a branch per lane. Inlined, it
/// lets the compiler keep the burst's addresses in vector registers and take each lane's
/// out for its load: on Zen 4, where lanes rebase often (about every 50 steps near zoom
/// 1e6), that measured 9% faster than [`retarget_apart`] out of line (a call, and every
/// vector register saved around it); where they rebase rarely (bench-e50: once in 450
/// steps) 4% slower. [`Rate`] picks between them, and on Intel's cores always the other
/// ([`held_pays`]).
#[inline(always)]
fn retarget(at: &mut [usize; MAX_W], mask: u32, to: usize) {
    for (i, a) in at.iter_mut().enumerate() {
        let r = 0usize.wrapping_sub((mask >> i) as usize & 1);
        *a = (to & r) | (*a & !r);
    }
}

/// [`retarget`] over the mask's bits: indexed stores, so that the addresses stay in memory
/// where the burst's loads read them as scalars. Inlined: out of line, the call and the
/// vector registers saved around it cost the Emerald Rapids Xeon 10% of the seahorse at
/// zoom 1e6 (0.91–1.02 s against 1.01–1.24 s; docs/performance.md, "The 1e5–1e15 range").
#[inline(always)]
fn retarget_apart(at: &mut [usize; MAX_W], mask: u32, to: usize) {
    let mut b = mask;
    while b != 0 {
        at[b.trailing_zeros() as usize % MAX_W] = to;
        b &= b - 1;
    }
}

/// Places the lanes of `mask`, which rebased inside a burst that has just ended `off` bytes
/// in (`t16` already moved on), where `at` says they now read (their address at the
/// burst's start plus `off`): on the orbit of 0 (reference `which`), with their stops.
#[inline(never)]
fn replace<S: Simd>(
    l: &mut Lanes<S>,
    at: &[usize; MAX_W],
    mask: u32,
    off: usize,
    which: usize,
    p: &Perturbation,
    refs: &Refs,
) {
    for i in 0..S::F64_LANES {
        if mask & (1 << i) != 0 {
            let m = ((at[i].wrapping_add(off) as i64 - refs.start[which]) / 16) as u32;
            let n = (l.n0[i] + l.t16 / 16) as u32;
            l.place(i, which, m, n, p, refs);
        }
    }
    l.restop();
}

/// After a burst in which lanes rebased: their samples now follow the orbit of 0, in
/// single-step mode, but for those that leave the lanes for the scalar loop's BLA lookup.
pub(super) fn settle<U: Unit, F: FnMut(Option<Held>, &mut Counters) -> Option<Held>>(
    lanes: &mut [Lanes<U>; G],
    meta: &mut [[Option<Held>; MAX_W]; G],
    moved: &Moved,
    p: &Perturbation,
    refs: &Refs,
    feed: &mut F,
    counters: &mut Counters,
) {
    counters.rebases += moved.count;
    let which = p.refs.len() - 1;
    for g in 0..G {
        for (i, slot) in meta[g].iter_mut().enumerate().take(U::F64_LANES) {
            if let Some(h) = slot
                && moved.rebased[g] & (1 << i) != 0
            {
                h.s.which = which;
                h.s.single = moved.leave[g] & (1 << i) == 0;
            }
        }
        if moved.leave[g] != 0 {
            hand_back(&mut lanes[g], &mut meta[g], moved.leave[g], false, p, refs, feed, counters);
        }
    }
}
