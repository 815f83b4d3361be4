//! Rendering: a scene into ordered strips of pixels and raw planes, on a thread pool.
//!
//! The image is cut into strips of whole rows (tiles of full width, so that PNG and EXR
//! writers can stream them). Strips are computed in parallel a window at a time and handed
//! to the sink strictly in order, so memory grows with the window, not the image, and the
//! bytes written never depend on the thread count: every sample is computed by the same
//! code from the same inputs whichever thread runs it. The sink runs on its own thread so
//! encoding overlaps computing. No I/O happens here; cancellation and progress come in as
//! an atomic flag and a callback.

pub mod engine;
pub mod frames;
mod recolor;

pub use recolor::{context, recolor, recolor_rgb8, strip_linear, strip_rgb8};

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc;
use std::time::Instant;

use rayon::prelude::*;

use crate::coloring::Context;
use crate::compose;
use std::sync::{Arc, Mutex};

use crate::cancel::Cancelled;
use crate::field::{self, Channel, ChannelSet, FieldParams, Needs, Planes, SampleGrid};
use crate::formula::Family;
use crate::gpu;
use crate::orbit::{self, Counters, DeepSpec, Perturbation};
use crate::scene::{FamilySpec, Scene};
use crate::simd_level::SimdLevel;
use engine::{EngineKind, EnginePlan};

/// What the caller's `prepare` and `sink` report when they fail: their own error, kept
/// whole so that the caller can look at it again (an [`crate::io::IoError`] for a full
/// disk, say).
pub type SinkError = Box<dyn std::error::Error + Send + Sync>;

/// Why a render did not complete.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Cancelled by the user.
    #[error("cancelled")]
    Cancelled,
    /// A reference file does not serve the view.
    #[error(transparent)]
    Reference(#[from] orbit::saved::SavedError),
    /// A reference file was given to a view that needs none.
    #[error("the scene runs the {0} engine, which uses no reference orbit; leave out the reference file")]
    NoReferenceNeeded(&'static str),
    /// A reference file was given to a formula whose references it cannot hold.
    #[error(
        "reference files hold z^2 + c's reference orbits; this scene's formula is {0}: leave out the reference file"
    )]
    NoReferenceFile(String),
    /// The requested rows are not the image's.
    #[error("rows {start}..{end} are not within the image's {height} rows")]
    Rows {
        /// First requested row.
        start: u32,
        /// One past the last.
        end: u32,
        /// The image's height.
        height: u32,
    },
    /// The GPU failed or is missing.
    #[error(transparent)]
    Gpu(#[from] gpu::GpuError),
    /// The caller's `prepare` or `sink` (its encoders and output writers) failed.
    #[error(transparent)]
    Sink(SinkError),
    /// The thread running the caller's sink panicked.
    #[error("the output writer panicked")]
    SinkPanicked,
    /// The thread pool could not be built.
    #[error("cannot start {0} worker threads")]
    Threads(usize),
}

impl RenderError {
    /// True for errors in what was requested (a reference file, the rows, a GPU engine
    /// without a device), as opposed to failures while working. (A view no engine
    /// addresses is refused before a render, by [`engine::plan`].)
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            RenderError::Reference(_)
                | RenderError::NoReferenceNeeded(_)
                | RenderError::Rows { .. }
                | RenderError::Gpu(_)
        )
    }
}

impl From<Cancelled> for RenderError {
    fn from(_: Cancelled) -> Self {
        RenderError::Cancelled
    }
}

/// A band of finished output rows.
#[derive(Debug)]
pub struct RenderedStrip {
    /// First output row.
    pub row: u32,
    /// Output rows in the strip.
    pub rows: u32,
    /// Output pixels, linear RGB, `width * rows` of them.
    pub rgb: Vec<[f32; 3]>,
    /// Raw planes of the strip's sample rows (`rows * aa` rows of `width * aa` samples).
    pub planes: Planes,
    /// The composited colour of every sample (linear RGB), when an EXR asks for `RGB`.
    pub samples: Option<Vec<[f32; 3]>>,
}

/// Progress of a render.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Progress {
    /// Reference orbit iterations done, of at most `total`.
    Reference {
        /// Done so far.
        done: u64,
        /// At most this many.
        total: u64,
    },
    /// Output rows finished.
    Rows(u64),
    /// Iterations of a long reference orbit folded into steps of whole blocks, of `total`:
    /// built when a sample first gets past BLA's tree, while no row finishes (seconds, for
    /// 10^8 iterations).
    Blocks {
        /// Done so far.
        done: u64,
        /// Of this many.
        total: u64,
    },
}

impl Progress {
    /// What it counts, as progress displays name it: "reference orbit", "rows", "steps of
    /// blocks".
    pub fn name(self) -> &'static str {
        match self {
            Progress::Reference { .. } => "reference orbit",
            Progress::Rows(_) => "rows",
            Progress::Blocks { .. } => "steps of blocks",
        }
    }
}

/// How often a render looks at the blocks' build for [`Progress::Blocks`].
const BLOCKS_LOOK: std::time::Duration = std::time::Duration::from_millis(200);

/// Raises its flag and wakes its thread when dropped: stops a watching thread however the
/// work it watches ends.
struct Stop<'a>(&'a AtomicBool, Option<std::thread::Thread>);

impl Drop for Stop<'_> {
    fn drop(&mut self) {
        self.0.store(true, Ordering::Relaxed);
        if let Some(t) = &self.1 {
            t.unpark();
        }
    }
}

/// What the deep engine did (absent for the direct kernels).
#[derive(Debug, Clone, serde::Serialize)]
pub struct DeepStats {
    /// Precision of the reference orbit in bits.
    pub reference_bits: u64,
    /// Iterations in the primary reference orbit.
    pub reference_iterations: u32,
    /// Of those, iterations stored densely (16 bytes each, read by index, with BLA); the
    /// rest are packed (`orbit::reference::packed`: about 1.0–1.4 bytes each, read in order by single
    /// steps).
    pub reference_dense: u32,
    /// The primary reference escaped before the iteration limit.
    pub reference_escaped: bool,
    /// The period of the primary reference when it is one period of a nucleus's orbit
    /// (then only that period is stored, whatever the iteration limit).
    pub reference_period: Option<u32>,
    /// Where the primary reference repeats itself exactly: how far back a sample at its
    /// end continues (`orbit::Reference::cycle`); None otherwise.
    pub reference_cycle: Option<u32>,
    /// Seconds spent on reference orbits and BLA tables.
    pub reference_seconds: f64,
    /// Of those, seconds the reference orbit(s) took.
    pub orbit_seconds: f64,
    /// And seconds the BLA tables took.
    pub tables_seconds: f64,
    /// Bytes of the reference orbit(s).
    pub reference_bytes: usize,
    /// Bytes of the BLA tables.
    pub bla_bytes: usize,
    /// Period-aligned BLA steps in the primary reference's table (0 without BLA).
    pub aligned_steps: usize,
    /// The stages of near-periods they reach.
    pub aligned_stages: usize,
    /// Steps of whole blocks in the primary reference's table, past the part its tree of
    /// steps covers (the first 2^20 iterations): through the rest of a dense orbit and
    /// through a packed tail (0 without BLA or a longer orbit, or where no sample went past
    /// the tree, so that they were never built).
    pub block_steps: usize,
    /// The first of those blocks' length in iterations (0 without).
    pub block_length: u32,
    /// The iteration where the blocks begin (0 without).
    pub blocks_from: u32,
    /// Seconds the blocks' steps took, built during the render when a sample first needed
    /// them (not in `tables_seconds`; 0 where none did).
    pub blocks_seconds: f64,
    /// Perturbation steps performed one at a time.
    pub steps: u64,
    /// Of those, steps in FloatExp.
    pub floatexp_steps: u64,
    /// BLA steps applied.
    pub bla_steps: u64,
    /// Iterations skipped by BLA steps.
    pub bla_iterations: u64,
    /// Of the BLA steps, those over blocks of a packed tail.
    pub tail_bla_steps: u64,
    /// Rebases.
    pub rebases: u64,
    /// The view's series (degree, the iteration it reaches), where it reaches past the BLA
    /// skip.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub series: Option<(usize, u32)>,
    /// Samples that started from the series, and the iterations they skipped by it.
    pub series_samples: u64,
    /// Iterations skipped by the series.
    pub series_iterations: u64,
    /// Whether interior detection ran, and why (`on`, `auto-on`, `off`,
    /// `auto-exterior-centre`, `auto-minibrot-below-sample`, `auto-few-periods`,
    /// `julia-no-interior`).
    pub interior_detection: orbit::interior::Decision,
    /// Its threshold on |dz/dz|^2 (see `orbit::interior`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub interior_threshold: Option<f64>,
    /// Samples it stopped before the iteration limit.
    pub interior_samples: u64,
    /// Of those, the samples Newton's test found (in views centred on a nucleus).
    pub interior_newton_samples: u64,
    /// Of those, the samples in disks of parameters certified at once, not iterated.
    pub interior_disk_samples: u64,
}

/// What a render did.
#[derive(Debug, Clone, serde::Serialize)]
pub struct Stats {
    /// The formula and its form, as users write it (`burning-ship^3, Julia form`).
    pub formula: String,
    /// Engine that ran.
    pub engine: String,
    /// Why it was chosen.
    pub engine_reason: String,
    /// Arithmetic precision of the orbit loop.
    pub precision: String,
    /// Samples Pauldelbrot's glitch criterion flagged (each was fixed by rebasing; always 0
    /// for the direct kernels, which have no reference to glitch against).
    pub glitched_pixels: u64,
    /// The deep engine's figures.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub deep: Option<DeepStats>,
    /// Instruction set the kernels ran with (for the GPU engines: "GPU: " and the adapter).
    pub simd: String,
    /// Output pixels.
    pub pixels: u64,
    /// Samples computed (pixels times aa^2).
    pub samples: u64,
    /// Iterations the orbit loops performed (skipped samples count zero; the GPU engines
    /// estimate them from N, counting interior samples at the full limit).
    pub iterations: u64,
    /// Wall-clock seconds.
    pub wall_seconds: f64,
    /// iterations / wall_seconds.
    pub iterations_per_second: f64,
    /// Worker threads.
    pub threads: usize,
}

/// Options that are not part of the scene.
#[derive(Debug, Clone, Default)]
pub struct Options {
    /// Worker threads (0: one per core).
    pub threads: usize,
    /// Raw channels wanted by an EXR output (empty: none).
    pub exr_channels: ChannelSet,
    /// The instruction set the kernels run with (default: the widest this CPU has; every
    /// level gives the same bits).
    pub simd: SimdLevel,
    /// Only these output rows (a work unit of a larger render; default: all). Every sample
    /// depends only on the scene, so a band's rows are the whole render's rows, bit for bit.
    pub rows: Option<std::ops::Range<u32>>,
    /// A deep engine prepared for this view (see [`prepare_deep`]), reused when it covers
    /// this raster: a viewer's coarse passes share the final pass's reference orbit and
    /// BLA tables instead of computing their own.
    pub deep: Option<Arc<Perturbation>>,
    /// A deep engine computed here is built for offsets this many times the raster's own
    /// (None: 1), so that later rasters panned or zoomed out by up to that much reuse it.
    pub deep_reach: Option<f64>,
    /// Reference orbits read from a file (`render --reference`), used instead of computing
    /// them when they serve the view.
    pub references: Option<Arc<orbit::saved::SavedReferences>>,
    /// Store at most this many reference iterations densely, the rest packed (None: the
    /// engine's rule, [`orbit::dense_split`]): `render --dense-orbit`, which reaches the
    /// packed tail's path on short orbits.
    pub dense_orbit: Option<u32>,
}

impl Options {
    /// The defaults, with these EXR channels.
    pub fn with_channels(exr_channels: ChannelSet) -> Options {
        Options { exr_channels, ..Options::default() }
    }
}

/// Output rows per strip: sample rows a multiple of 16 (the EXR block height) and about
/// 2^16 samples per strip (small enough to balance two threads on small images).
fn strip_rows(scene: &Scene) -> u32 {
    let aa = scene.aa;
    let unit = 16 / gcd(16, aa);
    let per_row = (scene.width * aa * aa) as u64;
    let want = ((1u64 << 16) / per_row.max(1)).max(1) as u32;
    (want.div_ceil(unit) * unit).min(scene.height.div_ceil(unit) * unit)
}

fn gcd(a: u32, b: u32) -> u32 {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// The scene's formula and form as `--stats` and reports name it.
pub fn describe_formula(scene: &Scene) -> String {
    let form = match &scene.family {
        FamilySpec::Mandelbrot => "Mandelbrot form".to_string(),
        FamilySpec::Julia { c } => format!("Julia form, c = {}, {}", c[0].text(), c[1].text()),
    };
    match scene.formula.a() {
        Some([re, im]) => format!("{} with a = {re:?}{im:+?}i ({form})", scene.formula),
        None => format!("{} ({form})", scene.formula),
    }
}

/// The field parameters of a scene.
pub fn field_params(scene: &Scene, exr_channels: ChannelSet) -> FieldParams {
    let mut needs: Needs = scene.stack.needs(&scene.traps);
    needs.merge(&exr_channels.needs());
    let family = match &scene.family {
        FamilySpec::Mandelbrot => Family::Mandelbrot,
        FamilySpec::Julia { c } => Family::Julia { c: [c[0].to_f64(), c[1].to_f64()] },
    };
    let grid = SampleGrid {
        center: scene.center_f64(),
        radius: scene.radius_f64(),
        width: scene.width * scene.aa,
        height: scene.height * scene.aa,
        transform: scene.transform,
        projection: scene.projection,
    };
    let mut params = FieldParams::new(family, scene.max_iter, scene.escape_radius, needs, grid);
    params.orbit.formula = scene.formula;
    params
}

/// What the deep engine needs to know about `scene` under `plan` (None unless the plan
/// perturbs), with the field parameters it is derived from.
pub fn deep_spec(scene: &Scene, plan: &EnginePlan, options: &Options) -> (FieldParams, Option<DeepSpec>) {
    let mut params = field_params(scene, options.exr_channels);
    params.orbit.simd = options.simd;
    let EngineKind::Perturb { numbers, bla } = plan.kind else { return (params, None) };
    let spec = DeepSpec {
        center: scene.center.clone(),
        julia: match &scene.family {
            FamilySpec::Mandelbrot => None,
            FamilySpec::Julia { c } => Some(c.clone()),
        },
        spacing: scene.scale.spacing(params.grid.height),
        max_offset: params.grid.max_offset() * options.deep_reach.unwrap_or(1.0).max(1.0),
        max_iter: scene.max_iter,
        escape_radius: scene.escape_radius,
        derivative: params.needs.de,
        bla,
        interior: scene.interior_detection,
        numbers,
        simd: params.orbit.simd,
        references: None,
        dense_orbit: options.dense_orbit,
    };
    (params, Some(spec))
}

/// The field parameters for `plan`, with the deep engine's reference orbits and BLA tables
/// computed (once, shared by every strip) when the plan perturbs; the orbits come from
/// `options.references` when given (refused, with the reason, if they do not serve the
/// view). Returns the seconds the shared work took.
pub fn prepare_field(
    scene: &Scene,
    plan: &EnginePlan,
    options: Options,
    cancel: &AtomicBool,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<(FieldParams, f64), RenderError> {
    let start = Instant::now();
    let (mut params, spec) = deep_spec(scene, plan, &options);
    if let Some(mut spec) = spec {
        if let Some(saved) = &options.references {
            saved.serves(&spec)?;
            spec.references = Some(saved.refs.clone());
        }
        if !scene.formula.is_quadratic() {
            if options.references.is_some() {
                return Err(RenderError::NoReferenceFile(scene.formula.to_string()));
            }
            let report = |done, total| progress(Progress::Reference { done, total });
            let engine = orbit::generic::prepare(&spec, scene.formula, cancel, Some(&report))?;
            params.deep_generic = Some(Arc::new(engine));
            return Ok((params, start.elapsed().as_secs_f64()));
        }
        let shared = options.deep.as_ref().filter(|d| d.built_for(&spec));
        if let Some(q) = shared.and_then(|d| d.with_spacing(spec.spacing, params.grid.max_offset())) {
            params.deep = Some(Arc::new(q));
        } else {
            let report = |done, total| progress(Progress::Reference { done, total });
            params.deep = Some(Arc::new(orbit::prepare(&spec, &report, cancel)?));
        }
    } else if options.references.is_some() {
        return Err(RenderError::NoReferenceNeeded(plan.name));
    }
    Ok((params, start.elapsed().as_secs_f64()))
}

/// The deep engine of `scene` (reference orbits and BLA tables), or None when the scene
/// does not run the perturbation engine: computed once and given to several renders
/// through [`Options::deep`]. `options.deep`, when it serves this scene, is reused (moved
/// to this raster's spacing). The caller keeps an engine only for renders of the same
/// formula, iteration limit and centre (or sets its origin); a render checks the rest.
pub fn prepare_deep(
    scene: &Scene,
    plan: &EnginePlan,
    options: &Options,
    cancel: &AtomicBool,
    progress: &(dyn Fn(Progress) + Sync),
) -> Result<Option<Arc<Perturbation>>, RenderError> {
    if !matches!(plan.kind, EngineKind::Perturb { .. }) {
        return Ok(None);
    }
    let (params, _) = prepare_field(scene, plan, options.clone(), cancel, progress)?;
    Ok(params.deep)
}

/// Renders `scene`. Each strip goes through `prepare` on the worker that computed it (in
/// parallel: encoding, compression), then, strictly in order, to `sink` on a writer thread.
/// `progress` receives the number of output rows done.
pub fn render<P: Send>(
    scene: &Scene,
    plan: &EnginePlan,
    options: Options,
    cancel: &AtomicBool,
    progress: &(dyn Fn(Progress) + Sync),
    prepare: &(dyn Fn(&RenderedStrip) -> Result<P, SinkError> + Sync),
    mut sink: impl FnMut(RenderedStrip, P) -> Result<(), SinkError> + Send,
) -> Result<Stats, RenderError> {
    let start = Instant::now();
    // The GPU engines iterate on the process-wide device; its absence is an engine error.
    let gpu = match plan.kind {
        EngineKind::Gpu(precision) => Some((gpu::GpuContext::shared()?, precision)),
        _ => None,
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(options.threads)
        .build()
        .map_err(|_| RenderError::Threads(options.threads))?;
    // In the pool, so that the shared work (BLA tables, a reference's helper thread) keeps
    // to the requested threads.
    let (params, reference_seconds) = pool.install(|| prepare_field(scene, plan, options.clone(), cancel, progress))?;
    let counters = Mutex::new(Counters::default());
    let threads = pool.current_num_threads();
    let rows_per = strip_rows(scene);
    let band = options.rows.clone().unwrap_or(0..scene.height);
    if band.start >= band.end || band.end > scene.height {
        return Err(RenderError::Rows { start: band.start, end: band.end, height: scene.height });
    }
    let strips: Vec<(u32, u32)> =
        band.clone().step_by(rows_per as usize).map(|r| (r, rows_per.min(band.end - r))).collect();
    let strip_samples = (rows_per * scene.aa) as u64 * (scene.width * scene.aa) as u64;
    // Strips in flight: ~4M samples, at least two per thread, at most 64 unless threads need more.
    let lo = threads as u64 * 2;
    let window = ((1u64 << 22) / strip_samples.max(1)).max(lo).min(lo.max(64)) as usize;
    let iterations = AtomicU64::new(0);
    let rows_done = AtomicU64::new(0);
    let aa = scene.aa;

    // The field of a strip: its raw planes. The GPU engines report iterations estimated
    // from N (see `gpu::field::estimated_iterations`): they count none themselves.
    let field_of = |&(row, rows): &(u32, u32)| -> Result<(u32, u32, Planes), RenderError> {
        let sample_rows = row * aa..(row + rows) * aa;
        let planes = match &gpu {
            Some((ctx, precision)) => {
                if cancel.load(Ordering::Relaxed) {
                    return Err(RenderError::Cancelled);
                }
                let planes = gpu::field::compute_planes(ctx, &params, *precision, sample_rows.clone())?;
                let its = gpu::field::estimated_iterations(&params, sample_rows, &planes);
                iterations.fetch_add(its, Ordering::Relaxed);
                planes
            }
            None => {
                let strip = field::compute_strip(&params, sample_rows, cancel)?;
                iterations.fetch_add(strip.iterations, Ordering::Relaxed);
                if params.deep.is_some() || params.deep_generic.is_some() {
                    counters.lock().unwrap_or_else(|e| e.into_inner()).add(&strip.counters);
                }
                strip.planes
            }
        };
        progress(Progress::Rows(rows_done.fetch_add(rows as u64, Ordering::Relaxed) + rows as u64));
        Ok((row, rows, planes))
    };
    // Colours, downsamples and prepares a computed strip.
    let finish = |(row, rows, planes): (u32, u32, Planes), ctx: &Context| -> Result<(RenderedStrip, P), RenderError> {
        let samples = scene.stack.composite(&planes, aa, ctx);
        let kept = options.exr_channels.contains(Channel::Rgb).then(|| samples.clone());
        let rgb = compose::downsample(samples, planes.width, aa as usize);
        let samples = kept;
        let done = RenderedStrip { row, rows, rgb, planes, samples };
        let prepared = prepare(&done).map_err(RenderError::Sink)?;
        Ok((done, prepared))
    };
    let local = Context { simd: options.simd, ..Context::default() };

    let (tx, rx) = mpsc::sync_channel::<(RenderedStrip, P)>(threads);
    let finished = AtomicBool::new(false);
    let result = std::thread::scope(|s| {
        // While samples may wait on the blocks' build, a look at it every BLOCKS_LOOK.
        let watcher = params.deep.as_ref().filter(|d| d.builds_blocks()).map(|deep| {
            s.spawn(|| {
                while !finished.load(Ordering::Relaxed) {
                    std::thread::park_timeout(BLOCKS_LOOK);
                    if let Some((done, total)) = deep.blocks_progress() {
                        progress(Progress::Blocks { done, total });
                    }
                }
            })
        });
        // Stops it when the strips are done, or when they unwind (the scope would wait
        // for it forever).
        let stop = Stop(&finished, watcher.as_ref().map(|w| w.thread().clone()));
        let writer = s.spawn(move || -> Result<(), RenderError> {
            for (strip, prepared) in rx {
                sink(strip, prepared).map_err(RenderError::Sink)?;
            }
            Ok(())
        });
        let computed = pool.install(|| -> Result<(), RenderError> {
            let send = |done: Vec<Result<(RenderedStrip, P), RenderError>>| -> Result<bool, RenderError> {
                for strip in done {
                    if tx.send(strip?).is_err() {
                        // The writer stopped early: its error is reported below.
                        return Ok(false);
                    }
                }
                Ok(true)
            };
            if scene.stack.is_global() {
                // Colourings that read the whole image (histograms) wait for every strip.
                let mut fields = Vec::with_capacity(strips.len());
                for chunk in strips.chunks(window) {
                    if cancel.load(Ordering::Relaxed) {
                        return Err(RenderError::Cancelled);
                    }
                    let done: Result<Vec<_>, RenderError> = chunk.par_iter().map(field_of).collect();
                    fields.extend(done?);
                }
                let ctx = Context { simd: options.simd, ..scene.stack.context(fields.iter().map(|(_, _, p)| p)) };
                let mut fields = fields.into_iter();
                loop {
                    let chunk: Vec<_> = fields.by_ref().take(window).collect();
                    if chunk.is_empty() {
                        return Ok(());
                    }
                    if !send(chunk.into_par_iter().map(|f| finish(f, &ctx)).collect())? {
                        return Ok(());
                    }
                }
            }
            for chunk in strips.chunks(window) {
                if cancel.load(Ordering::Relaxed) {
                    return Err(RenderError::Cancelled);
                }
                let done = chunk.par_iter().map(|s| field_of(s).and_then(|f| finish(f, &local))).collect();
                if !send(done)? {
                    return Ok(());
                }
            }
            Ok(())
        });
        drop(tx);
        drop(stop);
        let written = writer.join().unwrap_or(Err(RenderError::SinkPanicked));
        computed.and(written)
    });
    result?;
    let wall = start.elapsed().as_secs_f64();
    let its = iterations.load(Ordering::Relaxed);
    let pixels = scene.width as u64 * scene.height as u64;
    let c = counters.into_inner().unwrap_or_else(|e| e.into_inner());
    let generic = params.deep_generic.as_ref().map(|d| {
        let (aligned_steps, aligned_stages) = d.dip_steps();
        DeepStats {
            reference_bits: d.bits(),
            reference_iterations: d.reference_len(),
            reference_dense: d.reference_len(),
            reference_escaped: d.reference_escaped(),
            reference_period: None,
            reference_cycle: None,
            reference_seconds,
            orbit_seconds: d.orbit_seconds(),
            tables_seconds: d.tables_seconds(),
            reference_bytes: 0,
            bla_bytes: 0,
            aligned_steps,
            aligned_stages,
            block_steps: 0,
            block_length: 0,
            blocks_from: 0,
            blocks_seconds: 0.0,
            steps: c.steps,
            floatexp_steps: c.floatexp_steps,
            bla_steps: c.bla_steps,
            bla_iterations: c.bla_iterations,
            tail_bla_steps: c.tail_steps,
            rebases: c.rebases,
            series: None,
            series_samples: c.series,
            series_iterations: c.series_iterations,
            interior_detection: orbit::interior::Decision::Off,
            interior_threshold: None,
            interior_samples: 0,
            interior_newton_samples: 0,
            interior_disk_samples: 0,
        }
    });
    let deep = params.deep.as_ref().map(|d| {
        let (reference_bytes, bla_bytes) = d.bytes();
        let blocks = || d.primary_table().into_iter().flat_map(|t| t.built().into_iter().flatten().flatten());
        DeepStats {
            reference_bits: d.bits(),
            reference_iterations: d.reference_length(),
            reference_dense: d.reference_dense(),
            reference_escaped: d.reference_escaped(),
            reference_period: d.references()[0].period(),
            reference_cycle: d.references()[0].cycle(),
            reference_seconds,
            orbit_seconds: d.orbit_seconds(),
            tables_seconds: d.tables_seconds(),
            reference_bytes,
            bla_bytes,
            aligned_steps: d.primary_table().map_or(0, |t| t.aligned_steps()),
            aligned_stages: d.primary_table().map_or(0, |t| t.stage_count()),
            block_steps: blocks().map(|t| t.steps()).sum(),
            block_length: blocks().next().map_or(0, |t| t.block()),
            blocks_from: blocks().next().map_or(0, |t| t.first()),
            blocks_seconds: d.primary_table().map_or(0.0, |t| t.blocks_seconds()),
            steps: c.steps,
            floatexp_steps: c.floatexp_steps,
            bla_steps: c.bla_steps,
            bla_iterations: c.bla_iterations,
            tail_bla_steps: c.tail_steps,
            rebases: c.rebases,
            series: d.series_reach(),
            series_samples: c.series,
            series_iterations: c.series_iterations,
            interior_detection: d.interior_decision(),
            interior_threshold: d.interior_check().map(|c| c.below2.to_f64()),
            interior_samples: c.interior,
            interior_newton_samples: c.newton,
            interior_disk_samples: c.disks,
        }
    });
    let deep = deep.or(generic);
    let precision = match plan.kind {
        EngineKind::Direct => "f64 (53-bit mantissa)".to_string(),
        EngineKind::Perturb { numbers: orbit::Numbers::F64, .. } => {
            format!("reference {} bits; deltas f64", deep.as_ref().map_or(0, |d| d.reference_bits))
        }
        EngineKind::Perturb { .. } => format!(
            "reference {} bits; deltas FloatExp (53-bit mantissa, 32-bit exponent) below 2^-480, f64 above",
            deep.as_ref().map_or(0, |d| d.reference_bits)
        ),
        EngineKind::Gpu(p) => p.describe().to_string(),
    };
    Ok(Stats {
        formula: describe_formula(scene),
        engine: plan.name.to_string(),
        engine_reason: plan.reason.clone(),
        precision,
        glitched_pixels: c.glitches,
        deep,
        simd: match &gpu {
            Some((ctx, _)) => format!("GPU: {}", ctx.adapter_name()),
            None => options.simd.describe().to_string(),
        },
        pixels,
        samples: pixels * (aa as u64).pow(2),
        iterations: its,
        wall_seconds: wall,
        iterations_per_second: if wall > 0.0 { its as f64 / wall } else { 0.0 },
        threads,
    })
}
