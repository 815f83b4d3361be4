//! Background rendering for the viewer: progressive passes of a scene through the library's
//! render path, on a thread of its own, cancelled as soon as a newer job arrives.
//!
//! A job is rendered coarse first (1/8 of the resolution, one sample per pixel: within
//! ~100 ms for shallow views) and then finer, each pass replacing the last on screen; the
//! final pass keeps its raw planes so colouring changes recolour without recomputing.
//! In tests the worker runs inline ([`Worker::inline`]): jobs run when polled, so a test
//! sees exactly which renders happened.

use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::mpsc::{self, Receiver, Sender};
use std::sync::{Arc, Mutex};
use std::time::Instant;

use crate::field::{ChannelSet, Planes};
use crate::formula::Formula;
use crate::num::{Decimal, FloatExp};
use crate::orbit::Perturbation;
use crate::orbit::saved::SavedReferences;
use crate::palette::color::linear_to_srgb8;
use crate::render::engine::EnginePlan;
use crate::render::{self, Options, RenderError};
use crate::scene::{FamilySpec, Scene};

use super::nav::Nav;

/// Something to render.
#[derive(Debug, Clone)]
pub struct Job {
    /// The scene (its size is the final pass's).
    pub scene: Scene,
    /// The view it shows.
    pub nav: Nav,
    /// Resolution divisors of the passes, coarse to fine (the last is usually 1).
    pub passes: Vec<u32>,
}

/// A finished pass.
#[derive(Debug, Clone)]
pub struct Pass {
    /// The job's serial number.
    pub id: u64,
    /// The view it shows.
    pub nav: Nav,
    /// Pixels.
    pub width: u32,
    /// Pixels.
    pub height: u32,
    /// 8-bit sRGB, RGB.
    pub rgb8: Vec<u8>,
    /// This was the job's last pass.
    pub last: bool,
    /// Raw planes of the last pass (strips, sample raster) and the scene that made them.
    pub planes: Option<(Vec<Planes>, Scene)>,
    /// Seconds since the job started.
    pub seconds: f64,
    /// The engine that ran.
    pub engine: String,
}

/// What the worker reports.
#[derive(Debug, Clone)]
pub enum Report {
    /// A pass is done.
    Pass(Box<Pass>),
    /// Rows done in the current pass, of `total`.
    Progress {
        /// The job.
        id: u64,
        /// Rows done.
        rows: u64,
        /// Rows in the pass.
        total: u64,
    },
    /// Work before a pass's rows, or between them, that takes seconds on long orbits while
    /// no row finishes (the reference orbit, the steps of whole blocks): `done` of `total`.
    Stage {
        /// The job.
        id: u64,
        /// What is being computed ([`render::Progress::name`]).
        name: &'static str,
        /// Done so far.
        done: u64,
        /// Of this many.
        total: u64,
    },
    /// The job failed (a view no engine can address, ...).
    Failed {
        /// The job.
        id: u64,
        /// Why.
        message: String,
    },
}

type Wake = Arc<dyn Fn() + Send + Sync>;

/// A render thread (or, for tests, an inline runner).
pub struct Worker {
    jobs: Option<Sender<(u64, Job)>>,
    reports: Receiver<Report>,
    report_tx: Sender<Report>,
    cancel: Arc<Mutex<Arc<AtomicBool>>>,
    next_id: u64,
    pending: Option<(u64, Job)>,
    inline: bool,
    /// Renders started (passes), for tests and the status bar.
    pub renders: Arc<AtomicU64>,
    /// The deep engine kept between jobs.
    deep: Arc<DeepCache>,
}

impl Worker {
    /// A worker thread; `wake` is called after each report (to request a repaint).
    pub fn spawn(wake: Wake, saved: Option<Arc<SavedReferences>>) -> Self {
        let (jobs, job_rx) = mpsc::channel::<(u64, Job)>();
        let (report_tx, reports) = mpsc::channel();
        let cancel = Arc::new(Mutex::new(Arc::new(AtomicBool::new(false))));
        let renders = Arc::new(AtomicU64::new(0));
        let (tx, flag, count) = (report_tx.clone(), cancel.clone(), renders.clone());
        let deep = Arc::new(DeepCache::new(saved));
        let kept = deep.clone();
        std::thread::Builder::new()
            .name("deepfield-render".into())
            .spawn(move || {
                while let Ok(mut job) = job_rx.recv() {
                    // Only the newest job matters.
                    while let Ok(newer) = job_rx.try_recv() {
                        job = newer;
                    }
                    let cancel = flag.lock().unwrap_or_else(|e| e.into_inner()).clone();
                    run_job(job.0, &job.1, &cancel, &count, &kept, &|r| {
                        let _ = tx.send(r);
                        wake();
                    });
                }
            })
            .expect("spawn the render thread");
        Self { jobs: Some(jobs), reports, report_tx, cancel, next_id: 0, pending: None, inline: false, renders, deep }
    }

    /// A worker that renders only when [`Worker::poll`] is called, on the caller's thread.
    pub fn inline(saved: Option<Arc<SavedReferences>>) -> Self {
        let (report_tx, reports) = mpsc::channel();
        Self {
            jobs: None,
            reports,
            report_tx,
            cancel: Arc::new(Mutex::new(Arc::new(AtomicBool::new(false)))),
            next_id: 0,
            pending: None,
            inline: true,
            renders: Arc::new(AtomicU64::new(0)),
            deep: Arc::new(DeepCache::new(saved)),
        }
    }

    /// Deep engines built from the reference file's orbits so far.
    pub fn engines_from_file(&self) -> u64 {
        self.deep.from_file.load(Ordering::Relaxed)
    }

    /// Starts `job`, cancelling whatever is in flight; returns its serial number.
    pub fn submit(&mut self, job: Job) -> u64 {
        self.next_id += 1;
        let id = self.next_id;
        {
            let mut flag = self.cancel.lock().unwrap_or_else(|e| e.into_inner());
            flag.store(true, Ordering::Relaxed);
            *flag = Arc::new(AtomicBool::new(false));
        }
        match &self.jobs {
            Some(tx) => {
                let _ = tx.send((id, job));
            }
            None => self.pending = Some((id, job)),
        }
        id
    }

    /// Cancels the job in flight.
    pub fn cancel(&mut self) {
        self.cancel.lock().unwrap_or_else(|e| e.into_inner()).store(true, Ordering::Relaxed);
        self.pending = None;
    }

    /// Reports since the last poll (an inline worker first runs its pending job).
    pub fn poll(&mut self) -> Vec<Report> {
        if self.inline
            && let Some((id, job)) = self.pending.take()
        {
            let cancel = Arc::new(AtomicBool::new(false));
            let tx = self.report_tx.clone();
            run_job(id, &job, &cancel, &self.renders, &self.deep, &|r| {
                let _ = tx.send(r);
            });
        }
        self.reports.try_iter().collect()
    }
}

/// A deep engine kept from the last job: its key (what besides the centre, extent and
/// spacing decides it), the reference point, and the engine.
type Kept = (DeepKey, [Decimal; 2], Arc<Perturbation>);

/// The deep engine kept between jobs, and the reference orbits a file brought.
#[derive(Debug, Default)]
pub struct DeepCache {
    /// The engine kept.
    engine: Mutex<Option<Kept>>,
    /// Reference orbits read from a file (`deepfield view --reference`): a new engine is
    /// built from them instead of computing its orbits wherever they serve the view (its
    /// centre, limit, escape radius, and no deeper than the file's precision).
    saved: Option<Arc<SavedReferences>>,
    /// Engines built from the reference file's orbits.
    pub from_file: AtomicU64,
}

impl DeepCache {
    /// A cache with no engine yet, and the reference orbits of a file if given.
    pub fn new(saved: Option<Arc<SavedReferences>>) -> Self {
        DeepCache { saved, ..DeepCache::default() }
    }
}

/// How far, in views, a deep engine reaches: one built for a view serves pans of up to a
/// view's size either way and zooms out by up to this factor (its BLA tables are built for
/// the larger offsets, a little slower per sample than a view's own).
const DEEP_REACH: f64 = 3.0;

/// What decides a deep engine besides its reference point, extent and spacing (which
/// [`Perturbation::with_origin`] and [`Perturbation::with_spacing`] check): formula,
/// iteration limit, escape radius, BLA tolerance and the quantities computed. An engine is
/// kept for a new job when the keys compare equal.
#[derive(Debug, Clone, PartialEq)]
struct DeepKey {
    family: FamilySpec,
    formula: Formula,
    max_iter: u32,
    escape_radius: f64,
    bla: Option<f64>,
    channels: ChannelSet,
}

impl DeepKey {
    fn of(scene: &Scene) -> Self {
        DeepKey {
            family: scene.family.clone(),
            formula: scene.formula,
            max_iter: scene.max_iter,
            escape_radius: scene.escape_radius,
            bla: scene.bla,
            channels: scene.channels,
        }
    }
}

/// `a - b` in plane units, exact up to the final rounding to `FloatExp`.
fn difference(a: &[Decimal; 2], b: &[Decimal; 2]) -> [FloatExp; 2] {
    std::array::from_fn(|k| {
        let d = a[k].to_rational() - b[k].to_rational();
        crate::num::bigfloat::to_floatexp(&malachite_float::Float::from_rational_prec(d, 64).0)
    })
}

/// The deep engine for `scene` (None for views that do not perturb): the cached one, moved
/// to this view's centre, when it still serves (same key, the view inside its reach,
/// precision enough); else a new one centred here, which is then cached.
fn deep_engine(
    scene: &Scene,
    plan: &EnginePlan,
    cache: &DeepCache,
    cancel: &AtomicBool,
    progress: &(dyn Fn(render::Progress) + Sync),
) -> Result<Option<Arc<Perturbation>>, RenderError> {
    let key = DeepKey::of(scene);
    let cached = cache.engine.lock().unwrap_or_else(|e| e.into_inner()).clone().filter(|(k, _, _)| *k == key);
    // An engine built for a much wider view would serve a deep zoom-in with short BLA
    // steps: past a few reaches narrower, a new one is cheaper.
    let view = scene.log10_radius + 0.5 * (1.0 + (scene.width as f64 / scene.height as f64).powi(2)).log10();
    let moved = cached
        .filter(|(_, _, d)| d.extent().log2() * std::f64::consts::LOG10_2 - view < (4.0 * DEEP_REACH).log10())
        .and_then(|(_, at, d)| d.with_origin(difference(&scene.center, &at)).map(Arc::new));
    let mut options = Options { deep: moved.clone(), deep_reach: Some(DEEP_REACH), ..Options::default() };
    // The file's orbits, where they serve this view.
    if let (Some(saved), Some(spec)) = (&cache.saved, render::deep_spec(scene, plan, &options).1) {
        options.references = saved.serves(&spec).is_ok().then(|| saved.clone());
    }
    let Some(engine) = render::prepare_deep(scene, plan, &options, cancel, progress)? else { return Ok(None) };
    let reused = moved.as_ref().is_some_and(|c| c.shares_references(&engine));
    if !reused {
        if cache.saved.as_ref().is_some_and(|s| Arc::ptr_eq(&s.refs, engine.references())) {
            cache.from_file.fetch_add(1, Ordering::Relaxed);
        }
        *cache.engine.lock().unwrap_or_else(|e| e.into_inner()) = Some((key, scene.center.clone(), engine.clone()));
    }
    Ok(Some(engine))
}

fn run_job(
    id: u64,
    job: &Job,
    cancel: &AtomicBool,
    renders: &AtomicU64,
    cache: &DeepCache,
    report: &(dyn Fn(Report) + Sync),
) {
    let start = Instant::now();
    // Deep views: one reference orbit and one set of BLA tables, for the final pass's
    // raster, serve every pass (a coarse pass covers the same extent at a larger spacing).
    let rows = u64::from(job.scene.height);
    let progress = |p| report(progress_report(id, rows, p));
    // The engine is chosen once, for the final pass's raster; the coarse passes run the same.
    let plan = match render::engine::plan(&job.scene) {
        Ok(plan) => plan,
        Err(e) => {
            report(Report::Failed { id, message: e.to_string() });
            return;
        }
    };
    let deep = match deep_engine(&job.scene, &plan, cache, cancel, &progress) {
        Ok(d) => d,
        Err(RenderError::Cancelled) => return,
        Err(e) => {
            report(Report::Failed { id, message: e.to_string() });
            return;
        }
    };
    for (k, &div) in job.passes.iter().enumerate() {
        if cancel.load(Ordering::Relaxed) {
            return;
        }
        let last = k + 1 == job.passes.len();
        let mut scene = job.scene.clone();
        if div > 1 {
            scene.width = (scene.width / div).max(1);
            scene.height = (scene.height / div).max(1);
            scene.aa = 1;
        }
        renders.fetch_add(1, Ordering::Relaxed);
        match render_pass(id, &scene, &plan, last, deep.clone(), cancel, report) {
            Ok((rgb8, planes, engine)) => report(Report::Pass(Box::new(Pass {
                id,
                nav: job.nav.clone(),
                width: scene.width,
                height: scene.height,
                rgb8,
                last,
                planes: planes.map(|p| (p, scene.clone())),
                seconds: start.elapsed().as_secs_f64(),
                engine,
            }))),
            Err(RenderError::Cancelled) => return,
            Err(e) => {
                report(Report::Failed { id, message: e.to_string() });
                return;
            }
        }
    }
}

type PassOutput = (Vec<u8>, Option<Vec<Planes>>, String);

/// The report of a render's progress (`rows`: the pass's rows): rows done, the reference
/// orbit's iterations, and the build of the steps of whole blocks.
fn progress_report(id: u64, rows: u64, p: render::Progress) -> Report {
    match p {
        render::Progress::Rows(done) => Report::Progress { id, rows: done, total: rows },
        render::Progress::Reference { done, total } | render::Progress::Blocks { done, total } => {
            Report::Stage { id, name: p.name(), done, total }
        }
    }
}

fn render_pass(
    id: u64,
    scene: &Scene,
    plan: &EnginePlan,
    keep_planes: bool,
    deep: Option<Arc<Perturbation>>,
    cancel: &AtomicBool,
    report: &(dyn Fn(Report) + Sync),
) -> Result<PassOutput, RenderError> {
    let rows = Mutex::new(Vec::new());
    let planes = Mutex::new(Vec::new());
    let total = scene.height as u64;
    let progress = |p: render::Progress| report(progress_report(id, total, p));
    let prepare = |strip: &render::RenderedStrip| -> Result<Vec<u8>, render::SinkError> {
        Ok(strip.rgb.iter().flat_map(|p| p.map(linear_to_srgb8)).collect())
    };
    let stats = render::render(
        scene,
        plan,
        Options { threads: 0, exr_channels: ChannelSet::default(), deep, ..Options::default() },
        cancel,
        &progress,
        &prepare,
        |strip, bytes| {
            rows.lock().unwrap_or_else(|e| e.into_inner()).extend_from_slice(&bytes);
            if keep_planes {
                planes.lock().unwrap_or_else(|e| e.into_inner()).push(strip.planes);
            }
            Ok(())
        },
    )?;
    let planes = planes.into_inner().unwrap_or_else(|e| e.into_inner());
    Ok((rows.into_inner().unwrap_or_else(|e| e.into_inner()), keep_planes.then_some(planes), stats.engine))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn each_kind_of_progress_is_reported() {
        let stage = |p| match progress_report(7, 600, p) {
            Report::Stage { id: 7, name, done, total } => Some((name, done, total)),
            _ => None,
        };
        assert_eq!(stage(render::Progress::Blocks { done: 3, total: 9 }), Some(("steps of blocks", 3, 9)));
        assert_eq!(stage(render::Progress::Reference { done: 4, total: 8 }), Some(("reference orbit", 4, 8)));
        assert!(matches!(
            progress_report(7, 600, render::Progress::Rows(5)),
            Report::Progress { id: 7, rows: 5, total: 600 }
        ));
    }

    /// A deep view's job reports its reference orbit's progress before its passes (the
    /// reference here runs to the limit: its centre lies just past the cusp, where the
    /// orbit crawls past 1/2 for about 10^9 iterations without ever repeating).
    #[test]
    fn a_deep_job_reports_its_reference_orbit() {
        let text = "version = 1\n[formula]\nkind = \"mandelbrot\"\n[view]\ncenter = [\"0.25000000000000001\", \"0\"]\n\
                    zoom = \"1e30\"\nwidth = 16\nheight = 12\n[iteration]\nmax = 20000\n\
                    [[layer]]\nkind = \"smooth\"\npalette = \"twilight\"\n";
        let file = Scene::parse_file("deep", text).unwrap();
        let scene = Scene::validate(file, "deep", text, std::path::Path::new("."), crate::io::load_bitmap).unwrap();
        let mut worker = Worker::inline(None);
        let id = worker.submit(Job { scene, nav: Nav::home(), passes: vec![1] });
        let reports = worker.poll();
        let reference: Vec<u64> = reports
            .iter()
            .filter_map(|r| match r {
                Report::Stage { id: i, name: "reference orbit", done, total: 20000 } if *i == id => Some(*done),
                _ => None,
            })
            .collect();
        assert!(reference.len() >= 4 && reference.windows(2).all(|w| w[0] < w[1]), "{reference:?}");
        assert!(reports.iter().any(|r| matches!(r, Report::Pass(p) if p.id == id && p.last)), "the pass");
    }
}
