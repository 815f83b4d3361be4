//! Per-sample raw data (N, NF, T, DEX/DEY, trap planes) and the f64 kernels that fill it.
//!
//! The field computes only what is asked of it ([`Needs`]): escape counts always; the final
//! z only when NF or T is wanted (it is free once the orbit is done); the derivative only for
//! distance estimates; traps only when a layer or channel uses them. Orbits without traps, or
//! with one geometric trap, go through the vectorised kernel ([`simd`]); a bitmap trap or
//! several traps go through the scalar kernel ([`scalar`]), which shares the exact step
//! functions so both agree bit for bit.

pub mod generic;
pub mod generic_lanes;
mod grid;
mod planes;
pub mod projection;
pub mod quantities;
pub mod scalar;
pub mod simd;
pub mod single;
pub mod transform;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use rayon::prelude::*;

pub use grid::{SampleGrid, image_offset};
pub use planes::{Channel, ChannelSet, Planes, TrapPlane, UnknownChannel};
pub use projection::Projection;
pub use transform::Transform;

use crate::cancel::Cancelled;
use crate::formula::end::{INTERIOR, Orbit};
use crate::formula::{Family, Formula};
use crate::orbit::{Counters, Perturbation};
use crate::simd_level::SimdLevel;
use crate::trap::{Trap, TrapState};

/// Parameters of the orbit loop itself.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct OrbitParams {
    /// Mandelbrot or Julia form.
    pub family: Family,
    /// The map (z² + c runs its own kernels; every other formula [`generic`]'s).
    pub formula: Formula,
    /// Largest iteration index examined.
    pub max_iter: u32,
    /// Escape radius R.
    pub escape_radius: f64,
    /// Track dz for distance estimates.
    pub derivative: bool,
    /// The instruction set the kernels run with (the same bits on every one).
    pub simd: SimdLevel,
}

/// What the field must compute.
#[derive(Debug, Clone, Default)]
pub struct Needs {
    /// Smooth iteration fraction.
    pub nf: bool,
    /// Final phase.
    pub t: bool,
    /// Distance estimate vector.
    pub de: bool,
    /// Orbit traps, one plane each.
    pub traps: Vec<Trap>,
}

impl Needs {
    /// Adds everything `other` needs.
    pub fn merge(&mut self, other: &Needs) {
        self.nf |= other.nf;
        self.t |= other.t;
        self.de |= other.de;
        self.traps.extend(other.traps.iter().cloned());
    }
}

/// Everything a strip computation needs to know.
#[derive(Debug, Clone)]
pub struct FieldParams {
    /// The orbit loop.
    pub orbit: OrbitParams,
    /// The quantities to produce.
    pub needs: Needs,
    /// Where samples lie.
    pub grid: SampleGrid,
    /// The deep engine's shared data; None runs the direct kernels.
    pub deep: Option<Arc<Perturbation>>,
    /// The deep engine of a formula other than z² + c ([`crate::orbit::generic`]).
    pub deep_generic: Option<Arc<crate::orbit::generic::Engine>>,
    /// Run the direct f32 kernel instead of f64 (comparisons only; traps are not computed).
    pub single: bool,
}

impl FieldParams {
    /// Builds the parameters; the derivative is tracked exactly when distance is needed.
    pub fn new(family: Family, max_iter: u32, escape_radius: f64, needs: Needs, grid: SampleGrid) -> Self {
        let orbit = OrbitParams {
            family,
            formula: Formula::default(),
            max_iter,
            escape_radius,
            derivative: needs.de,
            simd: SimdLevel::detect(),
        };
        Self { orbit, needs, grid, deep: None, deep_generic: None, single: false }
    }
}

/// Raw planes of a band of sample rows, and the iterations it took.
#[derive(Debug, Clone)]
pub struct Strip {
    /// The planes, `grid.width` wide.
    pub planes: Planes,
    /// Iterations performed by the orbit loops (skipped samples count zero; for the
    /// perturbation engine, iterations the samples advanced, BLA-skipped ones included).
    pub iterations: u64,
    /// What the perturbation loop did (zero for the direct kernels).
    pub counters: Counters,
}

/// Computes sample rows `rows` of the grid. Distance vectors come out in image terms (the
/// view's rotation and stretch undone, [`Transform::gradient_to_image`]; an exponential
/// map's in the strip's terms, [`Projection::gradient_to_image`]).
pub fn compute_strip(
    params: &FieldParams,
    rows: std::ops::Range<u32>,
    cancel: &AtomicBool,
) -> Result<Strip, Cancelled> {
    let first = rows.start;
    let mut strip = compute_plane_strip(params, rows, cancel)?;
    let grid = &params.grid;
    let t = grid.transform;
    if params.needs.de && !t.is_identity() {
        let planes = &mut strip.planes;
        for (x, y) in planes.dex.iter_mut().zip(planes.dey.iter_mut()) {
            let g = t.gradient_to_image([*x as f64, *y as f64]);
            [*x, *y] = [g[0] as f32, g[1] as f32];
        }
    }
    if let (true, Projection::Exponential { ln_factor }) = (params.needs.de, grid.projection) {
        let planes = &mut strip.planes;
        let width = grid.width as usize;
        for (k, (x, y)) in planes.dex.iter_mut().zip(planes.dey.iter_mut()).enumerate() {
            let (i, j) = ((k % width) as u32, first + (k / width) as u32);
            let g = Projection::gradient_to_image(ln_factor, grid.width, grid.height, i, j, [*x as f64, *y as f64]);
            [*x, *y] = [g[0] as f32, g[1] as f32];
        }
    }
    Ok(strip)
}

/// [`compute_strip`] with distance vectors in plane terms.
fn compute_plane_strip(
    params: &FieldParams,
    rows: std::ops::Range<u32>,
    cancel: &AtomicBool,
) -> Result<Strip, Cancelled> {
    let grid = &params.grid;
    let width = grid.width as usize;
    let count = width * rows.len();
    let mut planes = Planes::new(width, rows.len(), &params.needs);
    if let Some(deep) = &params.deep {
        let counters = deep_strip(Deep::Quadratic(deep), params, rows, &mut planes, cancel)?;
        return Ok(Strip { planes, iterations: counters.iterations, counters });
    }
    if let Some(deep) = &params.deep_generic {
        let counters = deep_strip(Deep::Generic(deep), params, rows, &mut planes, cancel)?;
        return Ok(Strip { planes, iterations: counters.iterations, counters });
    }
    let mut points = Vec::with_capacity(count);
    for j in rows {
        // (An exact-size iterator: no capacity test per point.)
        points.extend((0..grid.width).map(|i| grid.point(i, j)));
    }
    if !params.orbit.formula.is_quadratic() {
        return generic_strip(params, &points, planes, cancel);
    }
    // The IFS field observes no orbit: alone it leaves the vectorised kernel in charge.
    let orbit_free = params.needs.traps.iter().all(|t| !t.observes_orbit());
    let n = &params.needs;
    if orbit_free && !params.single && !(n.nf || n.t || n.de || params.orbit.derivative) {
        // N alone: straight into its plane.
        let iterations =
            in_direct_chunks(&points, &mut planes.n, |points, n| simd::iterate_n(&params.orbit, points, n, cancel))?;
        fill_ifs(&params.needs.traps, &points, &mut planes);
        return Ok(Strip { planes, iterations, counters: Counters::default() });
    }
    let ln_r = params.orbit.escape_radius.ln();
    let spacing = grid.spacing();
    let mut orbits = vec![Orbit::interior(); count];
    let iterations = match params.needs.traps.as_slice() {
        _ if params.single => {
            let mut its = 0;
            for (o, p) in orbits.iter_mut().zip(&points) {
                let (orbit, n) = single::orbit(&params.orbit, *p);
                *o = orbit;
                its += n;
            }
            its
        }
        _ if orbit_free => {
            let n = &params.needs;
            let final_z = n.nf || n.t || n.de;
            in_direct_chunks(&points, &mut orbits, |points, out| {
                simd::iterate(&params.orbit, points, out, final_z, cancel)
            })?
        }
        // One geometric trap (the common case) runs vectorised; several traps or a bitmap
        // (a texture lookup per step) run in the scalar kernel.
        [Trap::Geometric(shape)] => {
            let mut dist = vec![0.0f64; count];
            let its = simd::iterate_with_trap(&params.orbit, *shape, &points, &mut orbits, &mut dist, cancel)?;
            if let Some(TrapPlane::Distance(plane)) = planes.traps.first_mut() {
                for (p, d) in plane.iter_mut().zip(&dist) {
                    *p = d.min(f32::MAX as f64) as f32;
                }
            }
            its
        }
        traps => scalar::iterate_with_traps(&params.orbit, traps, &points, &mut orbits, &mut planes.traps, cancel)?,
    };
    fill_quantities(&params.needs, &orbits, ln_r, std::f64::consts::LN_2, spacing, &mut planes);
    fill_ifs(&params.needs.traps, &points, &mut planes);
    Ok(Strip { planes, iterations, counters: Counters::default() })
}

/// The direct kernel of a formula other than z² + c over `points`, in parallel calls of
/// [`GENERIC_CHUNK`] samples (each sample's result the same in any call).
fn generic_strip(
    params: &FieldParams,
    points: &[[f64; 2]],
    mut planes: Planes,
    cancel: &AtomicBool,
) -> Result<Strip, Cancelled> {
    let traps = &params.needs.traps;
    let mut orbits = vec![Orbit::interior(); points.len()];
    let formula = params.orbit.formula;
    let iterations = if traps.iter().all(|t| !t.observes_orbit()) && formula.phases().len() == 1 {
        crate::with_map!(formula.phases()[0], m: M => {
            points
                .par_chunks(GENERIC_CHUNK)
                .zip(orbits.par_chunks_mut(GENERIC_CHUNK))
                .map(|(p, o)| generic_lanes::iterate::<M>(m, &params.orbit, p, o, cancel))
                .try_reduce(|| 0, |a, b| Ok(a + b))?
        }, unreachable!("a validated formula has compiled code"))
    } else if traps.iter().all(|t| !t.observes_orbit()) {
        points
            .par_chunks(GENERIC_CHUNK)
            .zip(orbits.par_chunks_mut(GENERIC_CHUNK))
            .map(|(p, o)| generic_lanes::iterate_cycle(&params.orbit, formula, p, o, cancel))
            .try_reduce(|| 0, |a, b| Ok(a + b))?
    } else {
        crate::with_stepper!(params.orbit.formula, s => {
            generic::iterate(s, &params.orbit, traps, points, &mut orbits, &mut planes.traps, cancel)?
        })
    };
    let ln_r = params.orbit.escape_radius.ln();
    fill_quantities(&params.needs, &orbits, ln_r, params.orbit.formula.ln_degree(), params.grid.spacing(), &mut planes);
    fill_ifs(traps, points, &mut planes);
    Ok(Strip { planes, iterations, counters: Counters::default() })
}

/// Samples per parallel call of the generic direct kernel.
const GENERIC_CHUNK: usize = 1024;

/// Runs a direct kernel `f` over `points` and their outputs `out` in calls of
/// [`DIRECT_CHUNK`] samples, in parallel; the iterations summed.
fn in_direct_chunks<T: Send>(
    points: &[[f64; 2]],
    out: &mut [T],
    f: impl Fn(&[[f64; 2]], &mut [T]) -> Result<u64, Cancelled> + Sync,
) -> Result<u64, Cancelled> {
    points
        .par_chunks(DIRECT_CHUNK)
        .zip(out.par_chunks_mut(DIRECT_CHUNK))
        .map(|(p, o)| f(p, o))
        .try_reduce(|| 0, |a, b| Ok(a + b))
}

/// Writes the IFS density of each sample's point into the IFS planes.
fn fill_ifs(traps: &[Trap], points: &[[f64; 2]], planes: &mut Planes) {
    for (trap, plane) in traps.iter().zip(planes.traps.iter_mut()) {
        if let (Trap::Ifs(p), TrapPlane::Density(d)) = (trap, plane) {
            for (v, pt) in d.iter_mut().zip(points) {
                *v = crate::trap::ifs::density(p, pt[0] as f32, pt[1] as f32);
            }
        }
    }
}

/// Writes N and the quantities derived from each orbit's end into the planes, and smooths
/// stripe averages across bands.
/// `ln_degree` is the formula's escape rate (ln 2 for z² + c).
fn fill_quantities(needs: &Needs, orbits: &[Orbit], ln_r: f64, ln_degree: f64, spacing: f64, planes: &mut Planes) {
    for plane in &mut planes.traps {
        if let TrapPlane::Stripe { value, prev } = plane {
            for (k, orbit) in orbits.iter().enumerate() {
                if orbit.n != INTERIOR {
                    let nf = quantities::smooth_fraction_of_degree(orbit.z, ln_r, ln_degree);
                    value[k] = crate::trap::stripe::smoothed(prev[k], value[k], nf);
                }
            }
            *prev = Vec::new();
        }
    }
    for (k, orbit) in orbits.iter().enumerate() {
        planes.n[k] = orbit.n;
        if orbit.n == INTERIOR {
            continue;
        }
        if needs.nf {
            planes.nf[k] = quantities::smooth_fraction_of_degree(orbit.z, ln_r, ln_degree);
        }
        if needs.t {
            planes.t[k] = quantities::phase(orbit.z);
        }
        if needs.de {
            let [dx, dy] = quantities::distance_vector(orbit.z, orbit.dz, spacing);
            planes.dex[k] = dx;
            planes.dey[k] = dy;
        }
    }
}

/// Samples per call of the direct kernels without traps: the calls of a strip run in
/// parallel (an 800 x 600 image is only 7 strips), each sample's result the same in any
/// call.
const DIRECT_CHUNK: usize = 4096;

/// Samples per call of the deep engine's many-sample loop (whole rows, at least this many),
/// in images of at least [`DEEP_CHUNKS`] such calls.
const DEEP_CHUNK: usize = 8192;
/// Calls of the deep engine a smaller image is cut into at least (of at least
/// [`DEEP_CHUNK_MIN`] samples each): the viewer's coarse pass (an eighth of the size, about
/// 12000 samples) was two calls, so at most two threads on any machine.
const DEEP_CHUNKS: usize = 32;
/// The fewest samples per call of the deep engine (the lanes drain at each call's end).
const DEEP_CHUNK_MIN: usize = 1024;

/// Rows per call of the deep engine for a grid of `width` x `height` samples: a function of
/// the image alone, so that every batch, and so every bit and count, is the same on any
/// number of threads.
fn deep_chunk_rows(width: usize, height: usize) -> usize {
    let samples = (width * height / DEEP_CHUNKS).clamp(DEEP_CHUNK_MIN, DEEP_CHUNK);
    samples.div_ceil(width.max(1)).max(1)
}

/// Computes sample rows `rows` with the perturbation engine (many samples at once, or one
/// at a time when traps observe z = Z + δ). The derivative it returns is already scaled by
/// the spacing.
/// The deep engine a strip runs: z² + c's, or the generic one of every other formula.
#[derive(Clone, Copy)]
enum Deep<'a> {
    Quadratic(&'a Perturbation),
    Generic(&'a crate::orbit::generic::Engine),
}

impl Deep<'_> {
    fn orbits(self, offsets: &[[f64; 2]], out: &mut [Orbit], c: &mut Counters, simd: SimdLevel, cancel: &AtomicBool) {
        match self {
            Deep::Quadratic(d) => d.orbits(offsets, out, c, simd, cancel),
            Deep::Generic(d) => d.orbits(offsets, out, c, simd, cancel),
        }
    }

    fn orbit(
        self,
        offset: [f64; 2],
        traps: &[Trap],
        states: &mut [TrapState],
        c: &mut Counters,
        cancel: &AtomicBool,
    ) -> Orbit {
        match self {
            Deep::Quadratic(d) => d.orbit(offset, traps, states, c, cancel),
            Deep::Generic(d) => d.orbit(offset, traps, states, c, cancel),
        }
    }
}

fn deep_strip(
    deep: Deep<'_>,
    params: &FieldParams,
    rows: std::ops::Range<u32>,
    planes: &mut Planes,
    cancel: &AtomicBool,
) -> Result<Counters, Cancelled> {
    let grid = &params.grid;
    let traps = &params.needs.traps;
    let mut states: Vec<TrapState> = traps.iter().map(Trap::initial).collect();
    let mut counters = Counters::default();
    let width = grid.width as usize;
    let mut orbits = vec![Orbit::interior(); width * rows.len()];
    if traps.iter().all(|t| !t.observes_orbit()) {
        // Several rows at a time (`deep_chunk_rows`: at least DEEP_CHUNK samples, fewer in
        // small images): the vector lanes run partly empty only while a call drains, and
        // Ctrl-C is looked at between calls. The calls
        // of a strip run in parallel, so that threads left idle by too few strips (an 800 x
        // 600 image is 7 strips) take them; each call's samples, and so every bit and
        // count, are the same whichever thread runs it and in whatever order.
        let chunk_rows = deep_chunk_rows(width, grid.height as usize);
        let row_list: Vec<u32> = rows.clone().collect();
        counters = orbits
            .par_chunks_mut(width * chunk_rows)
            .zip(row_list.par_chunks(chunk_rows))
            .map(|(out, chunk)| {
                if cancel.load(Ordering::Relaxed) {
                    return Err(Cancelled);
                }
                let offsets: Vec<[f64; 2]> =
                    chunk.iter().flat_map(|&j| (0..grid.width).map(move |i| grid.offset(i, j))).collect();
                let mut c = Counters::default();
                deep.orbits(&offsets, out, &mut c, params.orbit.simd, cancel);
                Ok(c)
            })
            .try_reduce(Counters::default, |mut a, b| {
                a.add(&b);
                Ok(a)
            })?;
    } else {
        // Traps see every iteration: one sample at a time, row by row.
        for (row, j) in orbits.chunks_mut(width).zip(rows.clone()) {
            if cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let row_start = (j - rows.start) as usize * width;
            for (i, orbit) in row.iter_mut().enumerate() {
                for (state, trap) in states.iter_mut().zip(traps) {
                    *state = trap.initial();
                }
                *orbit = deep.orbit(grid.offset(i as u32, j), traps, &mut states, &mut counters, cancel);
                for (plane, state) in planes.traps.iter_mut().zip(&states) {
                    plane.store(row_start + i, state);
                }
            }
        }
    }
    // Raised during the last samples, the flag may have abandoned some of them (the engine
    // cuts short those that waited on a cancelled build): none is kept.
    if cancel.load(Ordering::Relaxed) {
        return Err(Cancelled);
    }
    let ln_degree = params.orbit.formula.ln_degree();
    fill_quantities(&params.needs, &orbits, params.orbit.escape_radius.ln(), ln_degree, 1.0, planes);
    if traps.iter().any(|t| !t.observes_orbit()) {
        let points: Vec<[f64; 2]> =
            rows.flat_map(|j| (0..grid.width).map(move |i| (i, j))).map(|(i, j)| grid.point(i, j)).collect();
        fill_ifs(traps, &points, planes);
    }
    Ok(counters)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The deep engine's calls: whole rows of at least DEEP_CHUNK samples in large images (an
    /// 800 x 600 render keeps its 11-row batches), and small images (the viewer's coarse
    /// pass) cut into many calls for the threads to share, none below DEEP_CHUNK_MIN samples
    /// where the image holds that many.
    #[test]
    fn small_images_are_cut_into_many_calls_of_the_deep_engine() {
        assert_eq!(deep_chunk_rows(800, 600), 11);
        assert_eq!(deep_chunk_rows(1100, 680), 8);
        for (w, h) in [(137, 85), (275, 170), (160, 120), (64, 48), (550, 340)] {
            let rows = deep_chunk_rows(w, h);
            let calls = h.div_ceil(rows);
            assert!(rows * w >= DEEP_CHUNK_MIN.min(w * h), "{w}x{h}: {rows} rows");
            assert!(calls >= 8 || w * h < 8 * DEEP_CHUNK_MIN, "{w}x{h}: {calls} calls");
        }
        assert!(deep_chunk_rows(5, 1) >= 1 && deep_chunk_rows(0, 0) >= 1, "a row at least");
        assert_eq!(deep_chunk_rows(100_000, 10), 1);
    }
}
