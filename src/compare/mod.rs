//! `deepfield compare`: every engine that can address a view, timed and measured against
//! a direct big-float ground truth on a sample of pixels.
//!
//! The variants are the direct kernels (f32, f64) while their arithmetic still resolves a
//! sample, and the perturbation engines (f64 deltas while the spacing is inside the f64
//! range, FloatExp deltas always) without BLA and with BLA at two tolerances. Each renders
//! the raw field (no colouring) of the whole image, or only the rows holding the sampled
//! pixels; its time includes the reference orbit and BLA tables. Errors are measured on
//! the sampled pixels only: N mismatches, |NF - NF_true| where N agrees, and the relative
//! error of the distance-estimate vector. Two kinds of pixel have an ill-conditioned N and
//! are left out of the N count: those whose orbit passes within 1e-9 relative of the
//! escape circle, and those whose true N changes when the pixel moves 1e-9 sample
//! spacings (checked only where some engine disagrees with the truth, so it costs two
//! more big-float orbits per disagreeing pixel and nothing elsewhere).
//!
//! The GPU engines (`gpu`, `gpu-df`) are listed where they can address the view; whether a
//! GPU adapter exists is for the caller to check ([`crate::gpu::GpuContext::shared`]).

pub mod boundary;
pub mod fuzz;
pub mod kf_maps;
pub mod peer;
mod truth;
pub mod views;

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::time::Instant;

use malachite_float::Float;
use rayon::prelude::*;

pub use truth::Truth;

use crate::cancel::Cancelled;
use crate::field::{self, ChannelSet, Planes, Transform};
use crate::formula::Formula;
use crate::formula::end::INTERIOR;
use crate::gpu::{GpuContext, GpuError, Precision};
use crate::num::bigfloat;
use crate::orbit::{self, Numbers};
use crate::render::engine::{self, EngineKind, EnginePlan};
use crate::render::{self, Options, Progress};
use crate::scene::{EngineChoice, FamilySpec, Scene};
use crate::simd_level::SimdLevel;

/// One engine configuration to compare.
#[derive(Debug, Clone, PartialEq)]
pub struct Variant {
    /// Row label, e.g. "perturb-f64 bla 1e-12".
    pub name: String,
    /// What runs.
    pub kind: VariantKind,
    /// Reference iterations stored densely, the rest packed (None: the engine's rule; see
    /// `orbit::dense_split`).
    pub dense_orbit: Option<u32>,
}

/// The kernels a variant runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum VariantKind {
    /// Direct f32 iteration.
    F32,
    /// An engine plan (direct f64 or perturbation).
    Engine(EngineKind),
    /// Direct iteration on the GPU.
    Gpu(Precision),
}

impl VariantKind {
    /// True for the GPU variants.
    pub fn is_gpu(self) -> bool {
        matches!(self, VariantKind::Gpu(_))
    }
}

/// Why a variant did not run to the end.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// Cancelled by the user.
    #[error("cancelled")]
    Cancelled,
    /// The GPU failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The engine could not prepare the view.
    #[error("{0}")]
    Engine(String),
}

impl From<render::RenderError> for RunError {
    fn from(e: render::RenderError) -> Self {
        match e {
            render::RenderError::Cancelled => RunError::Cancelled,
            e => RunError::Engine(e.to_string()),
        }
    }
}

impl From<Cancelled> for RunError {
    fn from(_: Cancelled) -> Self {
        RunError::Cancelled
    }
}

/// One row of the comparison.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Row {
    /// Variant name.
    pub engine: String,
    /// Wall-clock seconds (reference orbit and BLA tables included).
    pub seconds: f64,
    /// Iterations the samples advanced per second.
    pub iterations_per_second: f64,
    /// Fraction of compared pixels whose N differs from the truth.
    pub n_mismatch_fraction: f64,
    /// Median |NF - NF_true| over pixels whose N agrees.
    pub nf_error_p50: f64,
    /// 99th percentile of the same.
    pub nf_error_p99: f64,
    /// Median relative error of the distance-estimate vector.
    pub de_error_p50: f64,
    /// 99th percentile of the same.
    pub de_error_p99: f64,
    /// Pixels compared (sampled minus those near the escape circle and the ill-conditioned
    /// ones this variant got wrong).
    pub compared: usize,
    /// Pixels the NF errors are taken over (escaped, N right, not left out); with none, the
    /// NF quantiles are NaN (nothing measured), not 0.
    pub nf_scored: usize,
    /// Pixels the distance-estimate errors are taken over (those of `nf_scored` with a finite
    /// true distance); with none, the DE quantiles are NaN.
    pub de_scored: usize,
    /// Pixels whose N this variant got wrong where N is ill-conditioned (it changes within
    /// 1e-9 sample spacings, [`mark_ill_conditioned`]); not counted as mismatches.
    pub ill_conditioned: usize,
    /// Pixels left out of the NF and distance errors because the true NF changes by more
    /// than [`NF_CONDITION`] within 1e-9 sample spacings, where this variant's NF is that far
    /// off.
    pub nf_ill_conditioned: usize,
    /// Pixels left out of the distance errors alone because the true distance-estimate
    /// vector moves by more than [`DE_CONDITION`] of its length within 1e-9 sample spacings
    /// (or N is ill-conditioned there), where this variant's is more than [`DE_SUSPECT`]
    /// off.
    pub de_ill_conditioned: usize,
}

/// Smallest f32/f64 ulps per sample at which a direct kernel is still listed.
const DIRECT_MIN_ULPS: f64 = 1.0;
/// The looser BLA tolerance shown beside the scene's (or the default) one.
pub const LOOSE_BLA_TOLERANCE: f64 = 1e-6;

/// The variants that can address the scene's view.
pub fn variants(scene: &Scene) -> Vec<Variant> {
    let mut out = Vec::new();
    let ulps64 = scene.ulps_per_sample();
    // The f32 kernel iterates z² + c only.
    if ulps64 * 2f64.powi(-29) >= DIRECT_MIN_ULPS && scene.formula.is_quadratic() {
        out.push(Variant { name: "f32".into(), kind: VariantKind::F32, dense_orbit: None });
    }
    if ulps64 >= DIRECT_MIN_ULPS {
        out.push(Variant { name: "f64".into(), kind: VariantKind::Engine(EngineKind::Direct), dense_orbit: None });
    }
    for (choice, precision) in [(EngineChoice::Gpu, Precision::F32), (EngineChoice::GpuDf, Precision::DoubleFloat)] {
        if engine::plan_for(scene, choice).is_ok() {
            out.push(Variant { name: precision.name().into(), kind: VariantKind::Gpu(precision), dense_orbit: None });
        }
    }
    let tight = scene.bla.unwrap_or(orbit::DEFAULT_BLA_TOLERANCE);
    let mut numbers = vec![];
    if engine::plan_for(scene, EngineChoice::PerturbF64).is_ok() {
        numbers.push((Numbers::F64, "perturb-f64"));
    }
    numbers.push((Numbers::FloatExp, "perturb-floatexp"));
    let bla_ok = scene.traps.is_empty();
    for (n, label) in numbers {
        out.push(Variant {
            name: label.into(),
            kind: VariantKind::Engine(EngineKind::Perturb { numbers: n, bla: None }),
            dense_orbit: None,
        });
        if bla_ok {
            for eps in [tight, LOOSE_BLA_TOLERANCE] {
                let kind = EngineKind::Perturb { numbers: n, bla: Some(eps) };
                out.push(Variant {
                    name: format!("{label} bla {eps:e}"),
                    kind: VariantKind::Engine(kind),
                    dense_orbit: None,
                });
            }
        }
    }
    out
}

/// `count` distinct sample positions (column, row) of the sample grid, chosen by a fixed
/// pseudo-random sequence so that runs are reproducible.
pub fn sample_pixels(scene: &Scene, count: u32) -> Vec<(u32, u32)> {
    let (w, h) = (scene.width * scene.aa, scene.height * scene.aa);
    let total = w as u64 * h as u64;
    let mut state = 0x00de_e9f1_e1d5_u64;
    let mut seen = std::collections::HashSet::new();
    let mut out = Vec::new();
    while (out.len() as u64) < (count as u64).min(total) {
        state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        let k = (state >> 20) % total;
        if seen.insert(k) {
            out.push(((k % w as u64) as u32, (k / w as u64) as u32));
        }
    }
    out
}

/// The sample grid in big floats, at the truth's precision.
struct TruthGrid<'a> {
    scene: &'a Scene,
    formula: Formula,
    bits: u64,
    spacing: Float,
    center: [Float; 2],
    julia: Option<[Float; 2]>,
}

impl<'a> TruthGrid<'a> {
    fn new(scene: &'a Scene, formula: Formula) -> Self {
        let bits = bigfloat::precision_for(scene.log10_spacing()) + 64;
        let spacing = scene.scale.spacing_big(scene.height * scene.aa, bits);
        let center = [bigfloat::from_decimal(&scene.center[0], bits), bigfloat::from_decimal(&scene.center[1], bits)];
        let julia = match &scene.family {
            FamilySpec::Mandelbrot => None,
            FamilySpec::Julia { c } => Some([bigfloat::from_decimal(&c[0], bits), bigfloat::from_decimal(&c[1], bits)]),
        };
        TruthGrid { scene, formula, bits, spacing, center, julia }
    }

    /// The truth at sample (i, j), moved by `shift` sample spacings.
    fn truth(&self, (i, j): (u32, u32), shift: [f64; 2]) -> Truth {
        let (cols, rows) = (self.scene.width * self.scene.aa, self.scene.height * self.scene.aa);
        let bits = self.bits;
        // The sample's offset is what the engines use (exact halves, or the f64 the view's
        // rotation and stretch map them to) and the shift a separate term: all exact in a Float.
        let offset = |o: f64, s: f64| {
            let a = Float::from(o).mul_prec_ref_ref(&self.spacing, bits).0;
            a.add_prec(Float::from(s).mul_prec_ref_ref(&self.spacing, bits).0, bits).0
        };
        let o = self.scene.transform.apply(crate::field::image_offset(cols, rows, i, j));
        let ox = offset(o[0], shift[0]);
        let oy = offset(o[1], shift[1]);
        let p = [self.center[0].add_prec_ref_ref(&ox, bits).0, self.center[1].add_prec_ref_ref(&oy, bits).0];
        let s = self.scene;
        truth::orbit_formula(&p, self.julia.as_ref(), self.formula, s.max_iter, s.escape_radius, &self.spacing, bits)
    }
}

/// The ground truth at the sampled pixels of `scene` iterating `formula`, computed in
/// parallel; `progress` receives the number of pixels done.
pub fn truths(
    scene: &Scene,
    formula: Formula,
    pixels: &[(u32, u32)],
    cancel: &AtomicBool,
    progress: &(dyn Fn(u64) + Sync),
) -> Result<Vec<Truth>, Cancelled> {
    let grid = TruthGrid::new(scene, formula);
    let done = AtomicU64::new(0);
    pixels
        .par_iter()
        .map(|&p| {
            if cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let t = grid.truth(p, [0.0; 2]);
            progress(done.fetch_add(1, Ordering::Relaxed) + 1);
            Ok(t)
        })
        .collect()
}

/// An engine's N as the truth states it: None for interior samples.
fn escape_index(n: u32) -> Option<u32> {
    (n != INTERIOR).then_some(n)
}

/// How far [`mark_ill_conditioned`] moves a pixel, in sample spacings.
pub const CONDITION_SHIFT: f64 = 1e-9;

/// An NF error above this, or a change of the true NF by more than this within
/// [`CONDITION_SHIFT`], makes a pixel's NF suspect or ill-conditioned (the fuzzer's bar for
/// NF's 99th percentile).
pub const NF_CONDITION: f64 = 1e-4;

/// A change of the true distance-estimate vector by more than this of its length within
/// [`CONDITION_SHIFT`] makes a pixel's distance estimate ill-conditioned: as with
/// [`NF_CONDITION`] and NF, it then varies by more than 1e5 times itself per pixel.
pub const DE_CONDITION: f64 = 1e-4;

/// A distance-estimate error above this (relative to the true distance; the fuzzer's bar
/// for the distance error's median) makes a pixel suspect, and is left out of the distance
/// errors where the pixel's distance estimate (or N) is ill-conditioned.
pub const DE_SUSPECT: f64 = 1e-6;

/// The sampled pixels (indices) whose N some variant got wrong, whose NF some variant got
/// more than [`NF_CONDITION`] wrong, or whose distance estimate some variant got more than
/// [`DE_SUSPECT`] wrong, near-circle ones left out: the only ones whose conditioning
/// matters.
pub fn suspects(measured: &[Measured], truths: &[Truth], escape_radius: f64, transform: Transform) -> Vec<usize> {
    let ln_r = escape_radius.ln();
    let wrong = |m: &Measured, k: usize| {
        let (n, nf, dx, dy) = m.values[k];
        let t = &truths[k];
        escape_index(n) != t.n
            || (t.n.is_some() && (nf as f64 - true_nf(t, ln_r)).abs() > NF_CONDITION)
            || (m.distance && de_error(t, [dx, dy], transform).is_some_and(|e| e > DE_SUSPECT))
    };
    (0..truths.len()).filter(|&k| !truths[k].near_circle && measured.iter().any(|m| wrong(m, k))).collect()
}

/// The true distance-estimate vector of an escaped orbit, in the plane's terms (|z| ln |z|
/// over |dz|, along the gradient of |z|): None where the orbit did not escape or the
/// distance is not a positive finite number.
fn true_de(t: &Truth) -> Option<[f64; 2]> {
    t.n?;
    let abs_z = t.z[0].hypot(t.z[1]);
    let d = abs_z * abs_z.ln() / t.dz[0].hypot(t.dz[1]);
    let (wx, wy) = (t.dz[0] * t.z[0] + t.dz[1] * t.z[1], t.dz[0] * t.z[1] - t.dz[1] * t.z[0]);
    let w = wx.hypot(wy);
    (d.is_finite() && d > 0.0 && w > 0.0).then(|| [d * wx / w, d * wy / w])
}

/// The error of an engine's distance-estimate vector `de` (in image terms) against the
/// truth's, relative to the true distance (infinite for a non-finite value); None where the
/// truth has no distance estimate.
fn de_error(t: &Truth, de: [f32; 2], transform: Transform) -> Option<f64> {
    let v = true_de(t)?;
    // The engines report the vector in image terms: the view's transform undone.
    let [tx, ty] = transform.gradient_to_image(v);
    let err = (de[0] as f64 - tx).hypot(de[1] as f64 - ty) / v[0].hypot(v[1]);
    Some(if err.is_finite() { err } else { f64::INFINITY })
}

/// Marks the truths at `suspects` whose N changes when the pixel moves [`CONDITION_SHIFT`]
/// sample spacings along x or along y. There N depends on digits a billion times finer
/// than the pixel: the orbit passes so close to the Julia set (or to a preimage of the
/// critical point) that no engine with f64 or FloatExp deltas, whose rounding alone is
/// worth ~1e-13 of the image, can be expected to reproduce it, and big-float iteration at
/// the pixel's centre is one draw among the many values inside the pixel. N is marked so as
/// well where the orbit spreads a disk of that radius to a unit ([`Truth::spreads`]): two
/// shifted orbits are then two more draws from a chaotic set, which need not land on an
/// escape where a few percent of the disk escapes, so their agreement proves nothing (at
/// a Burning Ship miniship's neighbourhood, f64-sized noise at every step made 2–6% of a
/// hundred runs escape within 20000 iterations at pixels whose big-float orbit and two
/// shifted ones stay bounded: docs/testing.md). Where N holds but
/// NF changes by more than [`NF_CONDITION`] under the same shifts, NF is ill-conditioned in
/// the same sense (it varies by more than 1e5 per pixel: the pixel shows noise at any
/// precision) and is marked so; likewise the distance estimate where its vector moves by
/// more than [`DE_CONDITION`] of its length (at a chaotic view's pixels whose distance is a
/// small fraction of the pixel, the derivative of a long orbit turns within 1e-9 of a
/// pixel, and an engine's rounding, worth about 1e-14 of a pixel, turns it too).
pub fn mark_ill_conditioned(
    scene: &Scene,
    formula: Formula,
    pixels: &[(u32, u32)],
    truths: &mut [Truth],
    suspects: &[usize],
    cancel: &AtomicBool,
) -> Result<(), Cancelled> {
    let grid = TruthGrid::new(scene, formula);
    let flags: Vec<(usize, bool, bool, bool)> = suspects
        .par_iter()
        .map(|&k| {
            if cancel.load(Ordering::Relaxed) {
                return Err(Cancelled);
            }
            let moved = [[CONDITION_SHIFT, 0.0], [0.0, CONDITION_SHIFT]];
            let t = &truths[k];
            let ln_r = scene.escape_radius.ln();
            let shifted: Vec<Truth> = moved.iter().map(|&s| grid.truth(pixels[k], s)).collect();
            let n_ill = t.spreads(CONDITION_SHIFT) || shifted.iter().any(|m| m.n != t.n);
            let nf_ill = shifted.iter().any(|m| (true_nf(m, ln_r) - true_nf(t, ln_r)).abs() > NF_CONDITION);
            let de_ill = true_de(t).is_some_and(|v| {
                shifted.iter().any(|m| {
                    true_de(m).is_none_or(|u| (u[0] - v[0]).hypot(u[1] - v[1]) > DE_CONDITION * v[0].hypot(v[1]))
                })
            });
            Ok((k, n_ill, nf_ill, de_ill))
        })
        .collect::<Result<_, _>>()?;
    for (k, n_ill, nf_ill, de_ill) in flags {
        truths[k].ill_conditioned = n_ill;
        truths[k].nf_ill_conditioned = !n_ill && nf_ill;
        truths[k].de_ill_conditioned = !n_ill && de_ill;
    }
    Ok(())
}

/// What a variant computed at the sampled pixels.
#[derive(Debug, Clone)]
pub struct Measured {
    /// (N, NF, DEX, DEY) per sampled pixel.
    pub values: Vec<(u32, f32, f32, f32)>,
    /// Iterations the samples advanced.
    pub iterations: u64,
    /// Wall-clock seconds; NaN where not this process's to measure (a peer's).
    pub seconds: f64,
    /// Whether `values` carry a distance estimate (DEX, DEY); a peer's do not, and
    /// [`score`] then reports no distance error.
    pub distance: bool,
}

/// Runs a variant over the whole sample grid (or only the rows holding `pixels`), its CPU
/// kernels with instruction set `simd`.
pub fn run(
    scene: &Scene,
    variant: &Variant,
    pixels: &[(u32, u32)],
    sample_only: bool,
    simd: SimdLevel,
    cancel: &AtomicBool,
) -> Result<Measured, RunError> {
    let start = Instant::now();
    let kind = match variant.kind {
        VariantKind::F32 => EngineKind::Direct,
        VariantKind::Engine(k) => k,
        VariantKind::Gpu(p) => return run_gpu(scene, p, pixels, sample_only, cancel),
    };
    let plan = EnginePlan { name: "compare", kind, reason: String::new() };
    let (mut params, _) = render::prepare_field(
        scene,
        &plan,
        Options { simd, dense_orbit: variant.dense_orbit, ..Options::with_channels(ChannelSet::default_exr()) },
        cancel,
        &|_: Progress| {},
    )?;
    params.single = variant.kind == VariantKind::F32;
    // Bands of up to 16 consecutive rows, computed in parallel.
    let bands = bands(params.grid.height, pixels, sample_only);
    let computed: Vec<(u32, Planes, u64)> = bands
        .par_iter()
        .map(|&(s, e)| field::compute_strip(&params, s..e, cancel).map(|st| (s, st.planes, st.iterations)))
        .collect::<Result<_, _>>()?;
    let seconds = start.elapsed().as_secs_f64();
    let iterations = computed.iter().map(|c| c.2).sum();
    Ok(Measured { values: pick(&computed, pixels), iterations, seconds, distance: true })
}

/// Rows of the sample grid to compute: all, or those holding `pixels`, in bands of up to
/// 16 consecutive rows.
fn bands(height: u32, pixels: &[(u32, u32)], sample_only: bool) -> Vec<(u32, u32)> {
    let mut rows: Vec<u32> = if sample_only { pixels.iter().map(|p| p.1).collect() } else { (0..height).collect() };
    rows.sort_unstable();
    rows.dedup();
    let mut bands: Vec<(u32, u32)> = Vec::new();
    for r in rows {
        match bands.last_mut() {
            Some((s, e)) if *e == r && r - *s < 16 => *e = r + 1,
            _ => bands.push((r, r + 1)),
        }
    }
    bands
}

/// The values at `pixels` from bands of planes (first row, planes, iterations).
fn pick(computed: &[(u32, Planes, u64)], pixels: &[(u32, u32)]) -> Vec<(u32, f32, f32, f32)> {
    pixels
        .iter()
        .map(|&(i, j)| {
            let (s, planes, _) = computed.iter().rev().find(|c| c.0 <= j).expect("row computed");
            let k = ((j - s) as usize) * planes.width + i as usize;
            (planes.n[k], planes.nf[k], planes.dex[k], planes.dey[k])
        })
        .collect()
}

/// [`run`] for the GPU variants: the whole grid in one call (or the sampled bands one after
/// another), on the shared context; iterations are estimated from N.
fn run_gpu(
    scene: &Scene,
    precision: Precision,
    pixels: &[(u32, u32)],
    sample_only: bool,
    cancel: &AtomicBool,
) -> Result<Measured, RunError> {
    let start = Instant::now();
    let ctx = GpuContext::shared()?;
    let params = render::field_params(scene, ChannelSet::default_exr());
    let height = params.grid.height;
    let bands = if sample_only { bands(height, pixels, true) } else { vec![(0, height)] };
    let mut computed = Vec::with_capacity(bands.len());
    for (s, e) in bands {
        if cancel.load(Ordering::Relaxed) {
            return Err(RunError::Cancelled);
        }
        let planes = crate::gpu::field::compute_planes(&ctx, &params, precision, s..e)?;
        let its = crate::gpu::field::estimated_iterations(&params, s..e, &planes);
        computed.push((s, planes, its));
    }
    let seconds = start.elapsed().as_secs_f64();
    let iterations = computed.iter().map(|c| c.2).sum();
    Ok(Measured { values: pick(&computed, pixels), iterations, seconds, distance: true })
}

/// The `q` quantile of `sorted`; NaN for no values (an error nobody measured is not 0).
fn quantile(sorted: &[f64], q: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    sorted[((sorted.len() - 1) as f64 * q).round() as usize]
}

/// The truth's NF (0 for interior pixels) for its formula's degree; `ln_r` is ln(escape
/// radius).
fn true_nf(t: &Truth, ln_r: f64) -> f64 {
    if t.n.is_none() {
        return 0.0;
    }
    let lnz = 0.5 * (t.z[0] * t.z[0] + t.z[1] * t.z[1]).ln();
    // log base p of ln|z| / ln R for the formula's degree p (log2 itself for p = 2).
    let log_p =
        if t.ln_degree == std::f64::consts::LN_2 { (lnz / ln_r).log2() } else { (lnz / ln_r).ln() / t.ln_degree };
    (1.0 - log_p).clamp(0.0, 1.0)
}

/// One CSV line per sampled pixel: its position, the truth (N, empty for interior; NF;
/// whether the orbit passes near the escape circle; whether N, NF and the distance estimate
/// are ill-conditioned, which is checked only where some variant's differs) and each
/// variant's N and NF. `names` and
/// `measured` are in the same order.
pub fn pixel_csv(
    pixels: &[(u32, u32)],
    truths: &[Truth],
    names: &[&str],
    measured: &[Measured],
    escape_radius: f64,
) -> String {
    let ln_r = escape_radius.ln();
    let mut out = String::from("x,y,n_true,nf_true,near_circle,ill_conditioned,nf_ill_conditioned,de_ill_conditioned");
    for name in names {
        out += &format!(",{name} n,{name} nf");
    }
    out.push('\n');
    let n_text = |n: Option<u32>| n.map(|n| n.to_string()).unwrap_or_default();
    for (k, (&(x, y), t)) in pixels.iter().zip(truths).enumerate() {
        let (nc, ill, nf_ill, de_ill) = (t.near_circle, t.ill_conditioned, t.nf_ill_conditioned, t.de_ill_conditioned);
        out += &format!("{x},{y},{},{:.9},{nc},{ill},{nf_ill},{de_ill}", n_text(t.n), true_nf(t, ln_r));
        for m in measured {
            let (n, f, _, _) = m.values[k];
            out += &format!(",{},{f:.9}", n_text(escape_index(n)));
        }
        out.push('\n');
    }
    out
}

/// Scores a variant's values against the truth.
pub fn score(name: &str, measured: &Measured, truths: &[Truth], escape_radius: f64, transform: Transform) -> Row {
    let ln_r = escape_radius.ln();
    let (mut compared, mut mismatched, mut excused, mut nf_excused, mut de_excused) = (0usize, 0, 0, 0, 0);
    let (mut nf, mut de) = (Vec::new(), Vec::new());
    for (&(n, f, dx, dy), t) in measured.values.iter().zip(truths) {
        if t.near_circle {
            continue;
        }
        let engine_n = escape_index(n);
        if engine_n != t.n && t.ill_conditioned {
            excused += 1;
            continue;
        }
        compared += 1;
        if engine_n != t.n {
            mismatched += 1;
            continue;
        }
        if t.n.is_none() {
            continue;
        }
        let nf_err = (f as f64 - true_nf(t, ln_r)).abs();
        if (t.ill_conditioned || t.nf_ill_conditioned) && nf_err > NF_CONDITION {
            nf_excused += 1;
            continue;
        }
        nf.push(nf_err);
        match de_error(t, [dx, dy], transform).filter(|_| measured.distance) {
            Some(err) if (t.ill_conditioned || t.de_ill_conditioned) && err > DE_SUSPECT => de_excused += 1,
            Some(err) => de.push(err),
            None => {}
        }
    }
    nf.sort_by(f64::total_cmp);
    de.sort_by(f64::total_cmp);
    Row {
        engine: name.to_string(),
        seconds: measured.seconds,
        // NaN for a time not measured (a peer's), 0 for none spent.
        iterations_per_second: if measured.seconds == 0.0 {
            0.0
        } else {
            measured.iterations as f64 / measured.seconds
        },
        n_mismatch_fraction: if compared > 0 { mismatched as f64 / compared as f64 } else { 0.0 },
        nf_error_p50: quantile(&nf, 0.5),
        nf_error_p99: quantile(&nf, 0.99),
        de_error_p50: quantile(&de, 0.5),
        de_error_p99: quantile(&de, 0.99),
        compared,
        nf_scored: nf.len(),
        de_scored: de.len(),
        ill_conditioned: excused,
        nf_ill_conditioned: nf_excused,
        de_ill_conditioned: de_excused,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn truth(n: u32) -> Truth {
        Truth {
            n: Some(n),
            z: [1e3, 0.0],
            dz: [1.0, 0.0],
            near_circle: false,
            spread_log2: 0,
            ill_conditioned: false,
            nf_ill_conditioned: false,
            de_ill_conditioned: false,
            ln_degree: std::f64::consts::LN_2,
        }
    }

    /// The truth's distance-estimate vector as the engines report it, in f32.
    fn engine_de(t: &Truth) -> (f32, f32) {
        let [x, y] = Transform::IDENTITY.gradient_to_image(true_de(t).unwrap());
        (x as f32, y as f32)
    }

    #[test]
    fn score_leaves_out_only_ill_conditioned_mismatches() {
        let mut truths = vec![truth(10), truth(10), truth(10), truth(10)];
        truths[1].ill_conditioned = true;
        truths[2].near_circle = true;
        // Wrong on every pixel but the last, whose NF is the truth's too.
        let nf = true_nf(&truths[3], 2f64.ln()) as f32;
        let (dx, dy) = engine_de(&truths[3]);
        let values = vec![(11, nf, dx, dy), (11, nf, dx, dy), (11, nf, dx, dy), (10, nf, dx, dy)];
        let m = Measured { values, iterations: 40, seconds: 1.0, distance: true };
        let row = score("x", &m, &truths, 2.0, Transform::IDENTITY);
        assert_eq!((row.compared, row.ill_conditioned), (2, 1), "{row:?}");
        assert_eq!(row.n_mismatch_fraction, 0.5, "{row:?}");
        assert_eq!(suspects(std::slice::from_ref(&m), &truths, 2.0, Transform::IDENTITY), vec![0, 1]);
        // NF: an ill-conditioned pixel's NF error is left out, an ordinary one's is not.
        let mut truths = vec![truth(10), truth(10)];
        truths[0].nf_ill_conditioned = true;
        let values = vec![(10, 0.3, dx, dy), (10, 0.3, dx, dy)];
        let m = Measured { values, iterations: 20, seconds: 1.0, distance: true };
        let row = score("x", &m, &truths, 2.0, Transform::IDENTITY);
        assert_eq!(row.nf_ill_conditioned, 1, "{row:?}");
        assert_eq!((row.nf_scored, row.de_scored), (1, 1), "{row:?}");
        assert_eq!(suspects(&[m], &truths, 2.0, Transform::IDENTITY), vec![0, 1]);
    }

    /// A distance estimate off by more than [`DE_SUSPECT`] makes a pixel suspect; where
    /// the true vector is ill-conditioned (or N is) it is left out of the distance errors
    /// alone, and an error within [`DE_SUSPECT`] is scored even there.
    #[test]
    fn score_leaves_out_only_ill_conditioned_distance_errors() {
        let mut truths = vec![truth(10), truth(10), truth(10), truth(10), truth(10)];
        truths[0].de_ill_conditioned = true;
        truths[1].ill_conditioned = true;
        truths[3].de_ill_conditioned = true;
        let nf = true_nf(&truths[0], 2f64.ln()) as f32;
        let (dx, dy) = engine_de(&truths[0]);
        let off = (dx * 1.01, dy);
        let near = (dx * (1.0 + 2e-7), dy);
        let values = vec![
            (10, nf, off.0, off.1),
            (10, nf, off.0, off.1),
            (10, nf, off.0, off.1),
            (10, nf, near.0, near.1),
            (10, nf, dx, dy),
        ];
        let m = Measured { values, iterations: 50, seconds: 1.0, distance: true };
        let row = score("x", &m, &truths, 2.0, Transform::IDENTITY);
        assert_eq!((row.compared, row.nf_scored, row.de_scored, row.de_ill_conditioned), (5, 5, 3, 2), "{row:?}");
        assert!(row.nf_error_p99 < 1e-6, "{row:?}");
        // Scored: the ordinary pixel 1% off, the ill-conditioned one within the bar, the exact one.
        assert!((row.de_error_p99 - 0.01).abs() < 1e-4 && row.de_error_p50 < 1e-6, "{row:?}");
        assert_eq!(suspects(&[m], &truths, 2.0, Transform::IDENTITY), vec![0, 1, 2]);
        // Without a distance estimate (a peer's values) nothing is suspect for it.
        let values = vec![(10, nf, 0.0, 0.0); 5];
        let peer = Measured { values, iterations: 0, seconds: f64::NAN, distance: false };
        assert!(suspects(&[peer], &truths, 2.0, Transform::IDENTITY).is_empty());
    }

    /// Errors over no pixel are NaN, not 0: a view whose sampled pixels are all interior (or
    /// all wrong in N) has its N scored and no NF or distance error to claim.
    #[test]
    fn errors_over_no_pixel_are_not_zero() {
        let mut interior = truth(10);
        interior.n = None;
        let truths = vec![interior, interior, truth(10)];
        // Right on the interior pixels, wrong N on the escaped one.
        let values = vec![(INTERIOR, 0.0, 0.0, 0.0), (INTERIOR, 0.0, 0.0, 0.0), (12, 0.5, 0.0, 0.0)];
        let m = Measured { values, iterations: 30, seconds: 1.0, distance: true };
        let row = score("x", &m, &truths, 2.0, Transform::IDENTITY);
        assert_eq!((row.compared, row.nf_scored, row.de_scored), (3, 0, 0), "{row:?}");
        assert!(row.nf_error_p50.is_nan() && row.nf_error_p99.is_nan(), "{row:?}");
        assert!(row.de_error_p50.is_nan() && row.de_error_p99.is_nan(), "{row:?}");
        assert!((row.n_mismatch_fraction - 1.0 / 3.0).abs() < 1e-15, "{row:?}");
    }

    /// Values without a distance estimate or a time of ours (a peer's) are scored on N and
    /// NF alone: no distance error, no rate, where the same values with them have both.
    #[test]
    fn a_peers_values_have_no_distance_error_and_no_rate() {
        let truths = vec![truth(10), truth(10)];
        let nf = true_nf(&truths[0], 2f64.ln()) as f32;
        let values = vec![(10, nf, 0.0, 0.0), (10, nf, 0.0, 0.0)];
        let ours = Measured { values: values.clone(), iterations: 20, seconds: 1.0, distance: true };
        let row = score("ours", &ours, &truths, 2.0, Transform::IDENTITY);
        assert_eq!((row.nf_scored, row.de_scored), (2, 2), "{row:?}");
        assert!(row.de_error_p99.is_finite() && row.iterations_per_second == 20.0, "{row:?}");
        let peer = Measured { values, iterations: 0, seconds: f64::NAN, distance: false };
        let row = score("peer", &peer, &truths, 2.0, Transform::IDENTITY);
        assert_eq!((row.compared, row.nf_scored, row.de_scored), (2, 2, 0), "{row:?}");
        assert!(row.de_error_p50.is_nan() && row.de_error_p99.is_nan(), "{row:?}");
        assert!(row.iterations_per_second.is_nan() && row.nf_error_p99 < 1e-6, "{row:?}");
    }

    /// Pixel (506, 307) of julia-deep-e40 escapes at 702 in big floats and at 713 a
    /// billionth of a pixel to the right (found with `compare --samples 4000`); its
    /// neighbour (100, 100) is an ordinary pixel.
    #[test]
    fn a_pixel_whose_n_changes_within_a_billionth_of_a_pixel_is_ill_conditioned() {
        let text = include_str!("../../scenes/julia-deep-e40.toml");
        let file = Scene::parse_file("julia-deep-e40", text).unwrap();
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
        let scene = Scene::validate(file, "julia-deep-e40", text, &dir, crate::io::load_bitmap).unwrap();
        let pixels = [(506, 307), (100, 100)];
        let cancel = AtomicBool::new(false);
        let formula = scene.formula;
        let mut truths = truths(&scene, formula, &pixels, &cancel, &|_| {}).unwrap();
        assert_eq!(truths[0].n, Some(702));
        mark_ill_conditioned(&scene, formula, &pixels, &mut truths, &[0, 1], &cancel).unwrap();
        assert!(truths[0].ill_conditioned);
        assert!(!truths[1].ill_conditioned, "{:?}", truths[1]);
    }

    /// A generated view of a hybrid's Julia set (the fuzzer's, seed 52 at 1e40): at pixel
    /// (14, 7), whose distance is about 4e-9 of the spacing, the true distance-estimate
    /// vector turns by a third of its length when the pixel moves a billionth of a spacing
    /// while N holds; at (23, 14), a fifth of the spacing from the set, it moves by 4e-9.
    #[test]
    fn a_distance_that_turns_within_a_billionth_of_a_pixel_is_ill_conditioned() {
        let text = r#"version = 1
[formula]
kind = "burning-ship,mandelbrot^3"
c = ["0.04998218799091687565", "-1.00866719623781683399"]
[view]
center = ["-0.32400938307666017526151663656052141687155656723620156970430306016495366625472782557", "-0.22168865617848951279705264988041442196287253114792767178414093401619311851487929484"]
radius = "6.485993187e-41"
width = 32
height = 24
[iteration]
max = 7996
"#;
        let file = Scene::parse_file("hybrid-julia", text).unwrap();
        let dir = std::path::Path::new(".");
        let scene = Scene::validate(file, "hybrid-julia", text, dir, crate::io::load_bitmap).unwrap();
        let pixels = [(14, 7), (23, 14)];
        let cancel = AtomicBool::new(false);
        let mut truths = truths(&scene, scene.formula, &pixels, &cancel, &|_| {}).unwrap();
        assert_eq!(truths.iter().map(|t| t.n).collect::<Vec<_>>(), [Some(1388), Some(1162)]);
        mark_ill_conditioned(&scene, scene.formula, &pixels, &mut truths, &[0, 1], &cancel).unwrap();
        assert!(truths[0].de_ill_conditioned && !truths[0].ill_conditioned, "{:?}", truths[0]);
        assert!(!truths[1].de_ill_conditioned && !truths[1].ill_conditioned, "{:?}", truths[1]);
    }
}
