//! BLA steps of whole blocks, for the part of a long reference orbit past the reach of the
//! table's tree: the rest of a densely stored orbit, and a packed tail
//! ([`crate::orbit::reference::packed`]), stored in about a byte per iteration and read in order only.
//!
//! The tree holds a step of every length 2^k at every index it can start from, about 100
//! bytes per iteration in f64 and 450 in FloatExp: 3.4 or 15 GB for the 2^25 iterations an
//! orbit may keep dense, and a hundred times the packed store's own size past them. So the
//! tree stops at 2^20 iterations, and past it the orbit is cut into blocks of 2^shift
//! iterations (at most 2^[`BLOCK_BITS`] of them: 2^4 iterations for short tails, 2^11 for
//! 10^9). Each block's step is folded from its single steps one iteration at a time
//! (the tree's merge with a single step, its zero and unit coefficients left out), and a tree of whole blocks is
//! merged over those. For a packed tail the table also keeps a reader ([`Cursor`]) standing
//! at each block boundary, so that a sample that takes a step goes on reading the tail
//! from where the step ends.
//!
//! A sample past the tree takes single steps (the loop's own) until it stands at a block
//! boundary, then the longest step from there that is valid for its delta, as the tree's
//! lookup climbs its levels. A sample whose delta is too large for a block's step takes
//! that block's iterations one at a time; near its escape it would in the tree too. The
//! tree's period-aligned stages have no counterpart here: an orbit is this long because it
//! has no period to rebase at.
//!
//! Folding a block costs about as much per iteration as the reference orbit itself, so the
//! blocks are built the first time a sample gets past the tree ([`Blocks`]), not with the
//! tree: a view whose samples all end before never pays for them. They are a function of
//! the orbit alone, so when they are built changes no bit of the output. The build looks at
//! the asking render's cancel flag between blocks: a cancelled build keeps nothing, and the
//! next sample to ask (of a render not cancelled) builds them again.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex, OnceLock, TryLockError};

use rayon::prelude::*;

use super::{Bla, Node, Second, Step, entry_to_f64, merge, then_single};
use crate::cancel::Cancelled;
use crate::num::{FloatExp, Real, Scaled};
use crate::orbit::reference::Reference;
use crate::orbit::reference::packed::{Cursor, Packed};

/// A tail table has at most 2^BLOCK_BITS blocks (the block length grows with the tail).
const BLOCK_BITS: u32 = 19;
/// Blocks are at least 2^MIN_SHIFT iterations long.
const MIN_SHIFT: u32 = 4;
/// How often a sample waiting on another's build of the blocks looks at its cancel flag.
const WAIT_LOOK: std::time::Duration = std::time::Duration::from_millis(5);

/// Steps of whole blocks of an orbit from an index on, and for a packed tail readers at
/// the blocks' boundaries.
#[derive(Debug, Clone)]
pub struct TailSteps<T> {
    /// Where block 0 starts: the tree's end, or a packed tail's seed.
    seed: u32,
    /// Blocks are 2^shift iterations long.
    shift: u32,
    /// For a packed tail, a reader standing at each block boundary, seed + j 2^shift, the
    /// end of the last whole block included (empty for a dense orbit, read by index).
    marks: Arc<[Cursor]>,
    /// levels[k][j]: the step over blocks j 2^k to (j + 1) 2^k - 1, first-order parts.
    levels: Vec<Vec<Bla<T>>>,
    /// Their second-order parts.
    seconds: Vec<Vec<Second<T>>>,
    /// Their squared start radii (a delta tested at the step's first index, as
    /// [`super::BlaTable::lookup`] takes them); negative where never valid.
    starts: Vec<Vec<T>>,
}

/// The steps of whole blocks past a table's tree, for the dense part past it and for a
/// packed tail, built the first time a sample needs them ([`Blocks::parts`]): a view whose
/// samples all end within the tree's reach never pays for them (the blocks cost about as
/// much per iteration as the reference orbit itself). Built once for both number types'
/// tables, which share this.
#[derive(Debug)]
pub struct Blocks {
    /// The orbits; the blocks are over `refs[k]`'s.
    refs: Arc<Vec<Reference>>,
    k: usize,
    /// Where the dense part's blocks begin (the tree's end).
    from: u32,
    how: Build,
    /// Keep the FloatExp steps too (a view with FloatExp deltas), not only the f64 ones.
    floatexp: bool,
    parts: OnceLock<Parts>,
    /// Held while a build runs: a second asker waits for it, or until its own cancel flag is
    /// raised (and builds again if the build it waited on was cancelled).
    building: Mutex<()>,
    /// Iterations folded into blocks so far, of `total` (while they are built: a render
    /// reports them, [`Blocks::progress`]).
    done: AtomicU64,
    total: AtomicU64,
}

/// What [`Blocks`] builds: [dense part past the tree, packed tail] in both number types.
#[derive(Debug, Default)]
pub struct Parts {
    /// The FloatExp steps (None unless requested).
    pub fe: [Option<TailSteps<FloatExp>>; 2],
    /// The f64 steps.
    pub f64: [Option<TailSteps<f64>>; 2],
    /// Seconds the build took.
    pub seconds: f64,
}

impl Blocks {
    /// The blocks of `refs[k]` past index `from`, where its orbit goes on past it (densely
    /// or packed); None where it does not.
    pub(super) fn new(refs: Arc<Vec<Reference>>, k: usize, from: u32, how: Build, floatexp: bool) -> Option<Self> {
        let r = refs.get(k)?;
        (r.last() > from || r.packed().is_some()).then(|| Blocks {
            refs,
            k,
            from,
            how,
            floatexp,
            parts: OnceLock::new(),
            building: Mutex::new(()),
            done: AtomicU64::new(0),
            total: AtomicU64::new(0),
        })
    }

    /// While the steps are being built, the iterations folded so far and of how many; None
    /// before the build starts and once it is done. Read by a render's progress display
    /// (the build can take seconds, during which no row finishes).
    pub fn progress(&self) -> Option<(u64, u64)> {
        let total = self.total.load(Ordering::Relaxed);
        (self.parts.get().is_none() && total > 0).then(|| (self.done.load(Ordering::Relaxed).min(total), total))
    }

    /// The steps, built now if they have not been. A sample's thread that asks while another
    /// builds them waits. `cancel` is the asking render's flag: raised during the build, the
    /// build stops between blocks, keeps nothing and gives `Cancelled`; an asker waiting
    /// on a build gives `Cancelled` as soon as its own flag is raised, and one whose flag is
    /// not raised builds them again where the build it waited on was cancelled.
    ///
    /// The build runs in a thread pool of its own, as wide as the one asking, started from
    /// a plain thread: the workers of the pool asking may all be waiting here, and one that
    /// helped with other work while it waited could take a sample that asks again (a
    /// re-entrant wait). Where no thread can be started the steps are left out and samples
    /// take single steps past the tree, as without BLA there.
    pub fn parts(&self, cancel: &AtomicBool) -> Result<&Parts, Cancelled> {
        if let Some(p) = self.parts.get() {
            return Ok(p);
        }
        // Waits for a build in flight (another sample's, perhaps another render's) while its
        // own flag is not raised.
        let _building = loop {
            match self.building.try_lock() {
                Ok(guard) => break guard,
                Err(TryLockError::Poisoned(e)) => break e.into_inner(),
                Err(TryLockError::WouldBlock) if cancel.load(Ordering::Relaxed) => return Err(Cancelled),
                Err(TryLockError::WouldBlock) => std::thread::sleep(WAIT_LOOK),
            }
        };
        if let Some(p) = self.parts.get() {
            return Ok(p);
        }
        if cancel.load(Ordering::Relaxed) {
            return Err(Cancelled);
        }
        let threads = rayon::current_num_threads();
        let built = std::thread::scope(|scope| {
            let run = move || {
                let pool = |n| rayon::ThreadPoolBuilder::new().num_threads(n).use_current_thread().build();
                // One thread (this one) where no more can be started.
                let pool = pool(threads).or_else(|_| pool(1));
                pool.map_or_else(|_| Ok(Parts::default()), |p| p.install(|| self.build(cancel)))
            };
            std::thread::Builder::new()
                .spawn_scoped(scope, run)
                .ok()
                .and_then(|h| h.join().ok())
                .unwrap_or_else(|| Ok(Parts::default()))
        });
        match built {
            Ok(parts) => Ok(self.parts.get_or_init(|| parts)),
            Err(Cancelled) => {
                self.total.store(0, Ordering::Relaxed);
                Err(Cancelled)
            }
        }
    }

    /// The steps if they have been built (for statistics, which must not build them).
    pub fn built(&self) -> Option<&Parts> {
        self.parts.get()
    }

    fn build(&self, cancel: &AtomicBool) -> Result<Parts, Cancelled> {
        let started = std::time::Instant::now();
        let r = &self.refs[self.k];
        let dense_len = r.last().saturating_sub(self.from);
        let total = u64::from(dense_len) + r.packed().map_or(0, |p| u64::from(p.len()));
        self.done.store(0, Ordering::Relaxed);
        self.total.store(total.max(1), Ordering::Relaxed);
        let fold = Fold { how: self.how, done: &self.done, cancel };
        let dense = if dense_len > 0 { TailSteps::dense(r, self.from, fold)? } else { None };
        let packed = match r.packed() {
            Some(p) => TailSteps::packed(p, r.get_fe(p.seed_index()), fold)?,
            None => None,
        };
        let f64 = [dense.as_ref().map(TailSteps::to_f64), packed.as_ref().map(TailSteps::to_f64)];
        let fe = if self.floatexp { [dense, packed] } else { [None, None] };
        Ok(Parts { fe, f64, seconds: started.elapsed().as_secs_f64() })
    }
}

/// What a build of whole blocks folds with: the steps' settings, the count of iterations
/// folded, and the asking render's cancel flag (looked at once per block).
#[derive(Clone, Copy)]
pub(super) struct Fold<'a> {
    how: Build,
    done: &'a AtomicU64,
    cancel: &'a AtomicBool,
}

impl Fold<'_> {
    /// Counts a block of `len` iterations folded; Cancelled where the flag is raised.
    fn folded(&self, len: u32) -> Result<(), Cancelled> {
        self.done.fetch_add(u64::from(len), Ordering::Relaxed);
        self.go_on()
    }

    fn go_on(&self) -> Result<(), Cancelled> {
        if self.cancel.load(Ordering::Relaxed) { Err(Cancelled) } else { Ok(()) }
    }
}

/// The block length's exponent for a tail of `len` values.
fn block_shift(len: u32) -> u32 {
    let bits = u32::BITS - len.leading_zeros();
    bits.saturating_sub(BLOCK_BITS).max(MIN_SHIFT)
}

/// The parts of one single step's merge that a table's builder fixes: the unit B (or zero
/// for a Julia set), the tolerance, the largest |δc| and the escape radius.
#[derive(Debug, Clone, Copy)]
pub(super) struct Build {
    pub one: Scaled,
    pub epsilon: f64,
    pub dc_max: FloatExp,
    pub escape: FloatExp,
}

impl Build {
    /// What a table is built for: `mandelbrot` sets B = 1 (else 0), `epsilon` is the
    /// relative tolerance, `dc_max` the largest |c offset|, `escape` the escape radius.
    pub(super) fn new(mandelbrot: bool, epsilon: f64, dc_max: FloatExp, escape: f64) -> Build {
        let one = Scaled::from_f64([if mandelbrot { 1.0 } else { 0.0 }, 0.0]);
        Build { one, epsilon, dc_max, escape: FloatExp::from(escape) }
    }

    /// One block's step: its values' single steps folded in order.
    fn block(&self, mut values: impl Iterator<Item = [FloatExp; 2]>) -> Node {
        let single = |z| Node::single(z, self.one, self.epsilon, self.escape);
        let first = values.next().map_or_else(|| single([FloatExp::ZERO; 2]), single);
        values.fold(first, |acc, z| then_single(&acc, &single(z), self.dc_max, self.epsilon))
    }
}

impl TailSteps<FloatExp> {
    /// The steps of `packed`'s whole blocks; `seed` is the seed's value at full range (kept
    /// with the dense part). None where the tail holds no whole block.
    /// `fold` counts the iterations folded and stops the build when it is cancelled.
    pub(super) fn packed(packed: &Packed, seed: [FloatExp; 2], fold: Fold<'_>) -> Result<Option<Self>, Cancelled> {
        let shift = block_shift(packed.len());
        let blocks = (packed.len() >> shift) as usize;
        if blocks == 0 {
            return Ok(None);
        }
        let block = 1u32 << shift;
        // One pass in order for the readers at the boundaries.
        let mut cursor = packed.cursor();
        let mut marks = Vec::with_capacity(blocks + 1);
        marks.push(cursor);
        for _ in 0..blocks {
            for _ in 0..block {
                let more = cursor.advance(packed);
                debug_assert!(more, "whole blocks lie within the tail");
            }
            marks.push(cursor);
            fold.go_on()?;
        }
        let how = fold.how;
        let first: Vec<Node> = (0..blocks)
            .into_par_iter()
            .map(|j| {
                let mut c = marks[j];
                // The seed's own exponent, when it is tiny, is kept with the dense part.
                let z = if j == 0 { seed } else { c.get_fe(packed) };
                let rest = (1..block).map(move |_| {
                    c.advance(packed);
                    c.get_fe(packed)
                });
                let node = how.block(std::iter::once(z).chain(rest));
                fold.folded(block).map(|()| node)
            })
            .collect::<Result<_, _>>()?;
        Ok(Some(Self::tree(packed.seed_index(), shift, marks.into(), first, how)))
    }

    /// The steps of whole blocks of a densely stored orbit from index `from` to its last
    /// (read by index: no readers). None where that holds no whole block. `fold` counts the
    /// iterations folded and stops the build when it is cancelled.
    pub(super) fn dense(orbit: &Reference, from: u32, fold: Fold<'_>) -> Result<Option<Self>, Cancelled> {
        let Some(len) = orbit.last().checked_sub(from) else { return Ok(None) };
        let shift = block_shift(len);
        let blocks = (len >> shift) as usize;
        if blocks == 0 {
            return Ok(None);
        }
        let how = fold.how;
        let first: Vec<Node> = (0..blocks as u32)
            .into_par_iter()
            .map(|j| {
                let at = from + (j << shift);
                let node = how.block((at..at + (1 << shift)).map(|i| orbit.get_fe(i)));
                fold.folded(1 << shift).map(|()| node)
            })
            .collect::<Result<_, _>>()?;
        Ok(Some(Self::tree(from, shift, Arc::new([]), first, how)))
    }

    /// The tree of whole blocks above the blocks' own steps `first`.
    fn tree(seed: u32, shift: u32, marks: Arc<[Cursor]>, first: Vec<Node>, how: Build) -> Self {
        let (mut levels, mut seconds, mut starts) = (Vec::new(), Vec::new(), Vec::new());
        let mut level = first;
        loop {
            let (l, q): (Vec<_>, Vec<_>) = level.par_iter().map(Node::parts).unzip();
            levels.push(l);
            seconds.push(q);
            starts.push(level.par_iter().map(|n| n.r0 * n.r0).collect());
            if level.len() < 2 {
                break;
            }
            level = level.par_chunks_exact(2).map(|p| merge(&p[0], &p[1], how.dc_max, how.epsilon)).collect();
        }
        TailSteps { seed, shift, marks, levels, seconds, starts }
    }

    /// The same steps for the f64 loop; steps f64 cannot hold are never valid.
    pub(super) fn to_f64(&self) -> TailSteps<f64> {
        let mut levels = Vec::new();
        let mut seconds = Vec::new();
        let mut starts = Vec::new();
        for ((l, q), r) in self.levels.iter().zip(&self.seconds).zip(&self.starts) {
            let (l, q): (Vec<_>, Vec<_>) = l.iter().zip(q).map(|(e, q)| entry_to_f64(e, q)).unzip();
            starts.push(q.iter().zip(r).map(|(q, r)| if q.r2 < 0.0 { -1.0 } else { r.to_f64() }).collect());
            levels.push(l);
            seconds.push(q);
        }
        TailSteps { seed: self.seed, shift: self.shift, marks: self.marks.clone(), levels, seconds, starts }
    }
}

impl<T: Real> TailSteps<T> {
    /// The longest valid step from index `m` for a delta with |z|^2 = `z2` that was tested
    /// at `m` (no rebase, no escape), at most `budget` iterations long: the step, its length
    /// and the block boundary where it ends (for [`TailSteps::reader`]). None where `m` is no
    /// block boundary or no step from it is valid. A longer step from the same boundary is
    /// valid on a subset of where a shorter one is, so the search stops at the first that
    /// fails.
    #[inline]
    pub fn lookup(&self, m: u32, z2: T, budget: u32) -> Option<(Step<'_, T>, u32, usize)> {
        let i = m.checked_sub(self.seed)?;
        if i & ((1 << self.shift) - 1) != 0 {
            return None;
        }
        let j = (i >> self.shift) as usize;
        let mut best = None;
        for (k, radii) in self.starts.iter().enumerate() {
            if j & ((1 << k) - 1) != 0 {
                break;
            }
            let Some(r) = radii.get(j >> k) else { break };
            let len = 1u64 << (self.shift as usize + k);
            // Written so that a NaN radius fails as "not valid".
            let valid = z2 < *r;
            if len > u64::from(budget) || !valid {
                break;
            }
            best = Some(k);
        }
        let k = best?;
        let step = Step { first: &self.levels[k][j >> k], second: &self.seconds[k][j >> k] };
        Some((step, 1 << (self.shift as usize + k), j + (1 << k)))
    }

    /// A reader of a packed tail standing at block boundary `j`; None for a dense orbit's
    /// blocks.
    #[inline]
    pub fn reader(&self, j: usize) -> Option<Cursor> {
        self.marks.get(j).copied()
    }

    /// Bytes of memory the steps and readers use.
    pub fn bytes(&self) -> usize {
        fn each<E>(v: &[Vec<E>]) -> usize {
            v.iter().map(|l| l.capacity() * std::mem::size_of::<E>()).sum()
        }
        each(&self.levels) + each(&self.seconds) + each(&self.starts) + self.marks.len() * std::mem::size_of::<Cursor>()
    }

    /// How many block steps it holds (every level).
    pub fn steps(&self) -> usize {
        self.levels.iter().map(Vec::len).sum()
    }

    /// The index where the first block begins.
    pub fn first(&self) -> u32 {
        self.seed
    }

    /// The block length in iterations.
    pub fn block(&self) -> u32 {
        1 << self.shift
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fold's composite is `merge`'s with a single step, to rounding: over the orbit of
    /// the period-3 nucleus near c = -0.1226 + 0.7449i, for offsets shallow and deep.
    #[test]
    fn a_single_step_folds_as_merge_composes_it() {
        let one = Scaled::from_f64([1.0, 0.0]);
        let escape = FloatExp::from(1e8);
        let c = [-0.1225611668766536, 0.7448617666197442];
        let mut z = [0.0f64, 0.0];
        for gamma in [FloatExp::from(1e-30), FloatExp::from(1e-300).mul_f64(1e-300)] {
            let fe = |z: [f64; 2]| [FloatExp::from(z[0]), FloatExp::from(z[1])];
            let mut fold = Node::single(fe([0.3, 0.1]), one, 1e-14, escape);
            let mut merged = fold;
            for _ in 0..300 {
                z = [z[0] * z[0] - z[1] * z[1] + c[0], 2.0 * z[0] * z[1] + c[1]];
                let y = Node::single(fe(z), one, 1e-14, escape);
                fold = then_single(&fold, &y, gamma, 1e-14);
                merged = merge(&merged, &y, gamma, 1e-14);
                let near = |u: FloatExp, v: FloatExp| u == v || ((u - v).abs() / u.abs().max(v.abs())).to_f64() < 1e-12;
                let (fp, mp) = (fold.parts(), merged.parts());
                for (u, v) in [(fp.1.r2, mp.1.r2), (fp.0.lin2, mp.0.lin2), (fold.r0, merged.r0)] {
                    assert!(near(u, v), "{u:?} {v:?}");
                }
                for (u, v) in
                    [fp.0.a, fp.0.b, fp.1.a2, fp.1.ab, fp.1.b2].iter().zip([mp.0.a, mp.0.b, mp.1.a2, mp.1.ab, mp.1.b2])
                {
                    for k in 0..2 {
                        assert!(near(u[k], v[k]), "{u:?} {v:?}");
                    }
                }
            }
        }
    }

    /// The build's progress ([`Blocks::progress`]): none before it starts and none once it
    /// is done; it counted every iteration of the whole blocks it folded, dense past the
    /// tree and packed, of a total that also holds the remainder past the last whole block.
    #[test]
    fn the_blocks_build_counts_what_it_folds() {
        use malachite_float::Float;
        let c = [Float::from(-0.7), Float::from(0.2)];
        let z0 = [Float::from(0.0), Float::from(0.0)];
        let how = Build::new(true, 1e-8, FloatExp::from(1e-14), 2.0);
        for dense_limit in [None, Some(1500)] {
            let steps = crate::orbit::reference::Stepping { dense_limit, ..Default::default() };
            let cancel = std::sync::atomic::AtomicBool::new(false);
            let r = Reference::compute(&z0, &c, 4005, 2.0, 128, steps, &|_| {}, &cancel).unwrap();
            let (last, tail) = (r.last(), r.packed().map_or(0, |p| p.len()));
            let blocks = Blocks::new(Arc::new(vec![r]), 0, 1000, how, false).expect("an orbit past 1000");
            assert_eq!(blocks.progress(), None, "not begun");
            let parts = blocks.parts(&crate::cancel::NEVER).expect("not cancelled");
            assert_eq!(blocks.progress(), None, "done");
            let whole: u64 = parts.f64.iter().flatten().map(|t| t.levels[0].len() as u64 * u64::from(t.block())).sum();
            let total = u64::from(last - 1000) + u64::from(tail);
            assert_eq!(blocks.done.load(Ordering::Relaxed), whole, "{dense_limit:?}");
            assert_eq!(blocks.total.load(Ordering::Relaxed), total, "{dense_limit:?}");
            assert!(whole > total * 9 / 10 && whole <= total, "{whole} of {total}");
            assert_eq!(parts.f64[1].is_some(), dense_limit.is_some());
        }
    }

    /// A build whose cancel flag is raised stops (`Cancelled`, from the fold of the blocks
    /// as from the start, and while it waits on another build), keeps nothing and shows no
    /// progress; the next ask with a flag not raised builds the steps whole.
    #[test]
    fn a_cancelled_build_keeps_nothing() {
        use malachite_float::Float;
        let c = [Float::from(-0.7), Float::from(0.2)];
        let z0 = [Float::from(0.0), Float::from(0.0)];
        let how = Build::new(true, 1e-8, FloatExp::from(1e-14), 2.0);
        let steps = crate::orbit::reference::Stepping { dense_limit: Some(1500), ..Default::default() };
        let never = AtomicBool::new(false);
        let r = Reference::compute(&z0, &c, 4005, 2.0, 128, steps, &|_| {}, &never).unwrap();
        let raised = AtomicBool::new(true);
        let (done, packed) = (AtomicU64::new(0), r.packed().expect("a packed tail"));
        let fold = Fold { how, done: &done, cancel: &raised };
        assert_eq!(TailSteps::dense(&r, 1000, fold).err(), Some(Cancelled), "dense");
        assert_eq!(TailSteps::packed(packed, r.get_fe(packed.seed_index()), fold).err(), Some(Cancelled), "packed");
        let blocks = Blocks::new(Arc::new(vec![r]), 0, 1000, how, false).expect("an orbit past 1000");
        {
            // Another build in flight: a waiter whose flag is raised stops waiting.
            let _held = blocks.building.lock().unwrap();
            assert_eq!(blocks.parts(&raised).err(), Some(Cancelled), "waiting");
        }
        assert_eq!(blocks.parts(&raised).err(), Some(Cancelled));
        assert!(blocks.built().is_none() && blocks.progress().is_none(), "nothing kept, no progress");
        let parts = blocks.parts(&never).expect("built");
        assert!(parts.f64.iter().all(Option::is_some), "both parts");
        assert!(blocks.built().is_some() && blocks.parts(&raised).is_ok(), "kept once built");
    }

    #[test]
    fn blocks_grow_with_the_tail_to_bound_the_table() {
        assert_eq!(block_shift(1000), MIN_SHIFT);
        assert_eq!(block_shift(1 << 20), MIN_SHIFT);
        assert_eq!(block_shift(1 << 25), 7);
        // 10^9 values: blocks of 2048, fewer than 2^19 of them.
        assert_eq!(block_shift(1_000_000_000), 11);
        assert!(1_000_000_000u32 >> block_shift(1_000_000_000) < 1 << BLOCK_BITS);
    }
}
