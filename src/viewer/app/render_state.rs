//! The main image: the render worker, the image on screen with the view it shows, the raw
//! planes of the last complete render, and what was last requested.
//!
//! What a new request costs is decided by comparing typed values: the same scene at the
//! same view costs nothing; a scene whose planes the last render computed
//! ([`Scene::planes_serve`]: the same render inputs, a colouring that reads nothing more)
//! is recoloured in milliseconds; anything else is rendered.

use eframe::egui::{self, ColorImage, TextureHandle};

use crate::field::Planes;
use crate::render;
use crate::scene::Scene;
use crate::viewer::nav::Nav;
use crate::viewer::worker::{Job, Report, Worker};

/// The image on screen: its texture, the view it shows and its size in pixels.
pub(super) struct Shown {
    pub(super) texture: TextureHandle,
    pub(super) nav: Nav,
    pub(super) size: [u32; 2],
}

/// The render worker and what it has shown.
pub(super) struct RenderState {
    worker: Worker,
    image: Option<Shown>,
    /// Raw planes of the last complete render, and the scene they now colour.
    planes: Option<(Vec<Planes>, Scene)>,
    /// The scene and view last requested.
    requested: Option<(Scene, Nav)>,
    /// Something changed since the last request.
    stale: bool,
    /// The current job's serial number.
    job: u64,
    /// Rows done of the current pass.
    progress: (u64, u64),
    /// Work of the current job that takes seconds before or between its rows (a long
    /// reference orbit, the steps of whole blocks), while it runs: shown instead of rows.
    stage: Option<(&'static str, u64, u64)>,
    last_seconds: f64,
    engine: String,
    recolours: u64,
}

impl RenderState {
    /// Nothing rendered yet.
    pub(super) fn new(worker: Worker) -> Self {
        Self {
            worker,
            image: None,
            planes: None,
            requested: None,
            stale: true,
            job: 0,
            progress: (0, 0),
            stage: None,
            last_seconds: 0.0,
            engine: String::new(),
            recolours: 0,
        }
    }

    /// Something the image depends on may have changed: the next frame asks again.
    pub(super) fn invalidate(&mut self) {
        self.stale = true;
    }

    /// True when something may have changed since the last request.
    pub(super) fn stale(&self) -> bool {
        self.stale
    }

    /// Shows `scene` at `nav`: nothing to do when that is what was last requested, a
    /// recolour of the last planes when they serve it at the view on screen, else a render.
    pub(super) fn request(&mut self, scene: Scene, nav: &Nav) {
        self.stale = false;
        if self.requested.as_ref().is_some_and(|(s, n)| n == nav && same_picture(s, &scene)) {
            return;
        }
        if let Some((strips, old)) = &mut self.planes
            && planes_serve(old, &scene)
            && let Some(shown) = self.image.as_mut().filter(|i| i.nav == *nav)
            // Planes whose traps do not serve the new layers are computed again.
            && let Ok(rgb8) = render::recolor_rgb8(&scene.stack, strips, old.aa)
        {
            let rgb8 = rgb8.concat();
            let (w, h) = (old.width as usize, old.height as usize);
            shown.texture.set(ColorImage::from_rgb([w, h], &rgb8), egui::TextureOptions::LINEAR);
            self.recolours += 1;
            // The planes stay; they now belong to the recoloured scene.
            *old = scene.clone();
            self.requested = Some((scene, nav.clone()));
            return;
        }
        // Deep views too: the passes share one reference orbit and BLA tables (the worker
        // keeps them between jobs while the centre stays).
        let passes = if scene.width * scene.height > 64 * 64 { vec![8, 2, 1] } else { vec![1] };
        self.job = self.worker.submit(Job { scene: scene.clone(), nav: nav.clone(), passes });
        self.progress = (0, scene.height as u64);
        self.stage = None;
        self.requested = Some((scene, nav.clone()));
    }

    /// The view's scene could not be built: nothing is requested until something changes.
    pub(super) fn request_failed(&mut self) {
        self.stale = false;
    }

    /// Collects the worker's reports; returns why the current job failed, if it did.
    pub(super) fn poll(&mut self, ctx: &egui::Context) -> Option<String> {
        let mut failed = None;
        for r in self.worker.poll() {
            match r {
                Report::Pass(p) if p.id == self.job => {
                    let image = ColorImage::from_rgb([p.width as usize, p.height as usize], &p.rgb8);
                    let size = [p.width, p.height];
                    match &mut self.image {
                        Some(shown) => {
                            shown.texture.set(image, egui::TextureOptions::LINEAR);
                            shown.nav = p.nav.clone();
                            shown.size = size;
                        }
                        None => {
                            let texture = ctx.load_texture("deepfield-image", image, egui::TextureOptions::LINEAR);
                            self.image = Some(Shown { texture, nav: p.nav.clone(), size });
                        }
                    }
                    if p.last {
                        self.planes = p.planes;
                        self.progress = (self.progress.1, self.progress.1);
                    }
                    self.stage = None;
                    self.last_seconds = p.seconds;
                    self.engine = p.engine;
                }
                Report::Progress { id, rows, total } if id == self.job => {
                    self.progress = (rows, total);
                    self.stage = None;
                }
                Report::Stage { id, name, done, total } if id == self.job => {
                    self.stage = (done < total).then_some((name, done, total));
                }
                Report::Failed { id, message } if id == self.job => failed = Some(message),
                _ => {}
            }
        }
        failed
    }

    /// The image on screen.
    pub(super) fn image(&self) -> Option<&Shown> {
        self.image.as_ref()
    }

    /// The scene last requested (the view on screen, or soon).
    pub(super) fn scene(&self) -> Option<&Scene> {
        self.requested.as_ref().map(|(s, _)| s)
    }

    /// The last complete render's planes and the scene they colour.
    pub(super) fn planes(&self) -> Option<&(Vec<Planes>, Scene)> {
        self.planes.as_ref()
    }

    /// The current job's serial number.
    pub(super) fn job(&self) -> u64 {
        self.job
    }

    /// Rows done of the current pass, of how many.
    pub(super) fn progress(&self) -> (u64, u64) {
        self.progress
    }

    /// True when the current job has finished.
    pub(super) fn complete(&self) -> bool {
        self.progress.0 >= self.progress.1
    }

    /// The stage in progress, if any: name, done, total.
    pub(super) fn stage(&self) -> Option<(&'static str, u64, u64)> {
        self.stage
    }

    /// Seconds the last pass took since its job started.
    pub(super) fn last_seconds(&self) -> f64 {
        self.last_seconds
    }

    /// The engine that ran the last pass ("" before any).
    pub(super) fn engine(&self) -> &str {
        &self.engine
    }

    /// Whether the last render is complete (no job in flight, nothing changed since).
    pub(super) fn idle(&self) -> bool {
        !self.stale && self.complete() && self.planes.is_some()
    }

    /// Passes rendered, recolours and deep engines built from a reference file so far.
    pub(super) fn counts(&self) -> (u64, u64, u64) {
        (
            self.worker.renders.load(std::sync::atomic::Ordering::Relaxed),
            self.recolours,
            self.worker.engines_from_file(),
        )
    }
}

/// True when `a` and `b` draw the same picture: the same render inputs (the formula among
/// them), layers and traps.
fn same_picture(a: &Scene, b: &Scene) -> bool {
    a.render_inputs() == b.render_inputs() && a.stack == b.stack && a.traps == b.traps
}

/// Whether the planes `old` computed serve `new` ([`Scene::planes_serve`]: planes of one
/// formula never colour another's picture).
fn planes_serve(old: &Scene, new: &Scene) -> bool {
    old.planes_serve(new)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Another formula is another picture, whose planes the last ones do not serve.
    #[test]
    fn another_formula_is_another_picture() {
        let file = Scene::parse_file("test", "version = 1\n").unwrap();
        let a = Scene::from_file(file, "test", std::path::Path::new("."), crate::io::load_bitmap).unwrap();
        let b = a.clone().with_formula(crate::formula::Formula::parse("buffalo", None).unwrap()).unwrap();
        assert!(same_picture(&a, &a.clone()) && planes_serve(&a, &a.clone()));
        assert!(!same_picture(&a, &b) && !planes_serve(&a, &b));
    }
}
