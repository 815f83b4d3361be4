//! The explorer window: image, navigation, panels, progressive rendering, recolouring,
//! Julia preview, export and headless screenshots.
//!
//! The raw scene file is the source of truth for everything but the view, which lives in
//! [`Nav`] (exact decimal centre, zoom) with its history. Any change re-validates the scene;
//! a change that only touches colouring (palettes, layers whose planes are already computed)
//! recolours the last raw planes instead of rendering, so it costs milliseconds. While a new
//! view renders, the last image is drawn where it belongs in the new view, so there is never
//! a blank frame.
//!
//! Split by concern: this file holds the app's state, the render and recolour cycle, the
//! saved session and screenshots; `panels` the toolbar, status bar, controls and files in
//! and out; `input` the keys and Newton zooming; `canvas` the image area and its drawing.
//! They are child modules, so they share the state without widening its visibility.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use eframe::egui::{self, Color32, ColorImage, Key, PointerButton, Pos2, Rect, Sense, TextureHandle, Vec2};
use toml::Spanned;

use super::export::{Export, ExportRequest};
use super::nav::{History, Nav};
use super::palette_editor::PaletteEditor;
use super::worker::{Job, Report, Worker};
use crate::field::{Needs, Planes};
use crate::orbit::saved::SavedReferences;
use crate::palette::{self, Palette};
use crate::render;
use crate::scene::raw::{LayerRaw, cli};
use crate::scene::{Scene, SceneFile};

mod canvas;
mod input;
mod panels;

/// How the image area shows the fractal.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ViewMode {
    /// The CPU render (f64 or perturbation, as the engine choice says).
    Cpu,
    /// The GPU f32 shader, drawn by an egui paint callback.
    GpuF32,
    /// The GPU double-float shader.
    GpuDf,
    /// CPU left half, GPU (f32) right half.
    SideBySide,
    /// Per-pixel difference between the CPU image and the GPU image.
    Difference,
}

/// What the viewer starts with.
#[derive(Debug, Clone, Default)]
pub struct ViewerOptions {
    /// A scene file (TOML, .kfr, or a PNG/EXR written by deepfield).
    pub scene: Option<PathBuf>,
    /// Save a screenshot of the whole window here once the render is complete, then exit.
    pub screenshot: Option<PathBuf>,
    /// Render inline when polled (tests): no background thread.
    pub inline: bool,
    /// Reference orbits from a file (`deepfield reference`), used wherever they serve the
    /// view instead of computing them.
    pub references: Option<Arc<SavedReferences>>,
}

/// Counters a test (or the curious) can read.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counters {
    /// Passes rendered.
    pub renders: u64,
    /// Recolours from raw planes.
    pub recolours: u64,
    /// Julia previews rendered.
    pub julia_previews: u64,
    /// Deep engines built from the reference file's orbits.
    pub references_from_file: u64,
}

/// State saved between runs. Every field has a default, so a session saved by another
/// version (with fields added or gone) still opens: what it lacks takes the default.
#[derive(Debug, Clone, serde::Serialize, serde::Deserialize)]
#[serde(default)]
struct Saved {
    scene: String,
    nav: Nav,
    export_path: String,
    scene_path: String,
}

impl Default for Saved {
    fn default() -> Self {
        Saved {
            scene: "version = 1\n".into(),
            nav: Nav::home(),
            export_path: "deepfield-export.png".into(),
            scene_path: "scene.toml".into(),
        }
    }
}

/// The application.
pub struct ViewerApp {
    file: SceneFile,
    origin: String,
    base_dir: PathBuf,
    /// The current view.
    pub nav: Nav,
    /// Back/forward history.
    pub history: History,
    scene: Option<Scene>,
    error: Option<String>,
    worker: Worker,
    julia_worker: Worker,
    image: Option<(TextureHandle, Nav, [u32; 2])>,
    planes: Option<(Vec<Planes>, Scene)>,
    overrides: BTreeMap<usize, Palette>,
    selected_layer: usize,
    editor: PaletteEditor,
    /// How the image is shown.
    pub mode: ViewMode,
    size_px: [u32; 2],
    job: u64,
    progress: (u64, u64),
    /// Work of the current job that takes seconds before or between its rows (a long
    /// reference orbit, the steps of whole blocks), while it runs: shown instead of rows.
    stage: Option<(&'static str, u64, u64)>,
    last_seconds: f64,
    engine: String,
    julia: Option<(TextureHandle, [f64; 2])>,
    julia_wanted: Option<[f64; 2]>,
    julia_asked: Option<[f64; 2]>,
    box_start: Option<Pos2>,
    recolours: u64,
    julia_previews: u64,
    export: Export,
    scene_path: String,
    screenshot: Option<PathBuf>,
    screenshot_state: Arc<AtomicU64>,
    started: Instant,
    needs_render: bool,
    image_rect: Rect,
    last_wheel: Option<Instant>,
    diff: Option<super::difference::Pending>,
    diff_shown: Option<(TextureHandle, u64, f64)>,
    newton: NewtonState,
}

/// Newton zooming in progress and its settings.
#[derive(Default)]
struct NewtonState {
    /// The search running on its own thread.
    pending: Option<std::sync::mpsc::Receiver<Result<(Nav, String), String>>>,
    /// Zoom by this factor towards what is found (1 or less: frame it).
    factor: f64,
    /// What the last search found (or why it found nothing).
    note: Option<String>,
}

impl ViewerApp {
    /// A viewer on the scene of `options` (or the last session's, or the default).
    pub fn new(cc: &eframe::CreationContext<'_>, options: ViewerOptions) -> Result<Self, String> {
        let saved: Option<Saved> = cc.storage.and_then(|s| eframe::get_value(s, "deepfield"));
        let ctx = cc.egui_ctx.clone();
        let worker = if options.inline {
            Worker::inline(options.references.clone())
        } else {
            let c = ctx.clone();
            Worker::spawn(Arc::new(move || c.request_repaint()), options.references.clone())
        };
        let julia_worker = if options.inline {
            Worker::inline(None)
        } else {
            Worker::spawn(Arc::new(move || ctx.request_repaint()), None)
        };
        let (origin, text, base_dir, nav) = match (&options.scene, &saved) {
            (Some(path), _) => {
                let s = crate::io::read_scene_source(path).map_err(|e| e.to_string())?;
                (s.origin, s.text, s.base_dir, None)
            }
            (None, Some(saved)) => {
                ("last session".to_string(), saved.scene.clone(), PathBuf::from("."), Some(saved.nav.clone()))
            }
            (None, None) => ("default".to_string(), "version = 1\n".to_string(), PathBuf::from("."), None),
        };
        let file = Scene::parse_file(&origin, &text).map_err(|e| e.to_string())?;
        // A saved view keeps its centre and zoom; its rotation and stretch are the scene's.
        let nav = nav.map_or_else(|| nav_of(&file), |n| Nav { transform: file.view.transform(), ..n });
        let mut app = Self {
            file,
            origin,
            base_dir,
            nav,
            history: History::default(),
            scene: None,
            error: None,
            worker,
            julia_worker,
            image: None,
            planes: None,
            overrides: BTreeMap::new(),
            selected_layer: 0,
            editor: PaletteEditor::default(),
            mode: ViewMode::Cpu,
            size_px: [0, 0],
            job: 0,
            progress: (0, 0),
            stage: None,
            last_seconds: 0.0,
            engine: String::new(),
            julia: None,
            julia_wanted: None,
            julia_asked: None,
            box_start: None,
            recolours: 0,
            julia_previews: 0,
            export: Export::new(saved.as_ref().map(|s| s.export_path.clone())),
            scene_path: saved.as_ref().map_or_else(|| "scene.toml".into(), |s| s.scene_path.clone()),
            screenshot: options.screenshot,
            screenshot_state: Arc::new(AtomicU64::new(0)),
            started: Instant::now(),
            needs_render: true,
            image_rect: Rect::NOTHING,
            last_wheel: None,
            diff: None,
            diff_shown: None,
            newton: NewtonState::default(),
        };
        if app.file.layers.is_empty() {
            app.file.layers.push(Spanned::new(0..0, LayerRaw::of_kind("smooth")));
        }
        // Deep views work in the viewer as in `render`; the GPU paint path needs a wgpu
        // render state (eframe's wgpu renderer provides it).
        if let Some(rs) = cc.wgpu_render_state.as_ref()
            && let Err(e) = crate::viewer::paint::register(rs)
        {
            app.error = Some(format!("GPU paint path unavailable: {e}"));
        }
        Ok(app)
    }

    /// The image area (points), as last laid out.
    pub fn image_rect(&self) -> Rect {
        self.image_rect
    }

    /// The image area's size in physical pixels (the render size).
    pub fn image_size_px(&self) -> [u32; 2] {
        self.size_px
    }

    /// Renders, recolours and previews done so far.
    pub fn counters(&self) -> Counters {
        Counters {
            renders: self.worker.renders.load(Ordering::Relaxed),
            recolours: self.recolours,
            julia_previews: self.julia_previews,
            references_from_file: self.worker.engines_from_file(),
        }
    }

    /// The Julia parameter of the scene, if it is a Julia scene.
    pub fn julia_c(&self) -> Option<[String; 2]> {
        (self.file.formula.kind.get_ref() == "julia")
            .then(|| self.file.formula.c.as_ref().map(|c| c.get_ref().clone()))?
    }

    /// The scene as edited so far (its view is [`ViewerApp::nav`]).
    pub fn scene_file(&self) -> &SceneFile {
        &self.file
    }

    /// The palette of layer `k` (the editor's copy when it has one).
    pub fn layer_palette(&self, k: usize) -> Option<String> {
        self.overrides
            .get(&k)
            .map(|p| p.name.clone())
            .or_else(|| self.file.layers.get(k)?.get_ref().palette.as_ref().map(|p| p.get_ref().clone()))
    }

    /// Sets the palette of every layer that takes one (as `--palette` does).
    pub fn set_palette(&mut self, name: &str) {
        for (k, l) in self.file.layers.iter_mut().enumerate() {
            let l = l.get_mut();
            if crate::scene::uses_palette(l) {
                l.palette = Some(cli(name.to_string()));
                self.overrides.remove(&k);
            }
        }
        self.changed();
    }

    /// Opens the Julia set of `c` (decimal strings) as the main view.
    pub fn open_julia(&mut self, c: [String; 2]) {
        self.history.push(self.nav.clone());
        self.file.formula.kind = cli("julia".into());
        self.file.formula.c = Some(cli(c));
        self.nav = Nav { center: ["0".into(), "0".into()], log10_zoom: 1.3f64.log10(), transform: self.nav.transform };
        self.changed();
    }

    /// Goes to `nav`, recording the current view in the history.
    pub fn go(&mut self, nav: Nav) {
        if nav != self.nav {
            self.history.push(self.nav.clone());
            self.nav = nav;
            self.needs_render = true;
        }
    }

    /// Back in the history.
    pub fn back(&mut self) {
        if let Some(n) = self.history.back(self.nav.clone()) {
            self.nav = n;
            self.needs_render = true;
        }
    }

    /// Forward in the history.
    pub fn forward(&mut self) {
        if let Some(n) = self.history.forward(self.nav.clone()) {
            self.nav = n;
            self.needs_render = true;
        }
    }

    fn changed(&mut self) {
        self.needs_render = true;
    }

    /// The scene for the current view at the image area's size.
    fn scene_for_view(&self) -> Result<Scene, String> {
        let mut file = self.file.clone();
        file.view.center = cli(self.nav.center.clone());
        file.view.zoom = Some(cli(self.nav.zoom_text()));
        file.view.radius = None;
        file.view.width = cli(self.size_px[0].max(1) as i64);
        file.view.height = cli(self.size_px[1].max(1) as i64);
        let text = toml::to_string(&file).map_err(|e| e.to_string())?;
        let mut scene = Scene::validate(file, &self.origin, &text, &self.base_dir, crate::io::load_bitmap)
            .map_err(|e| e.to_string())?;
        for (k, p) in &self.overrides {
            if let Some(layer) = scene.stack.layers.get_mut(*k)
                && let Some(slot) = layer.coloring.palette_mut()
            {
                *slot = p.clone();
            }
        }
        Ok(scene)
    }

    /// Starts a render of the current view, or recolours when only colouring changed.
    fn update_render(&mut self) {
        if !self.needs_render || self.size_px[0] == 0 {
            return;
        }
        self.needs_render = false;
        let scene = match self.scene_for_view() {
            Ok(s) => s,
            Err(e) => {
                self.error = Some(e);
                return;
            }
        };
        self.error = None;
        if let Some((strips, old)) = &self.planes
            && recolourable(old, &scene)
            && self.image.as_ref().is_some_and(|(_, n, _)| *n == self.nav)
            // Planes whose traps do not serve the new layers are computed again.
            && let Ok(rgb8) = render::recolor_rgb8(&scene.stack, strips, old.aa)
        {
            let rgb8 = rgb8.concat();
            let (w, h) = (old.width as usize, old.height as usize);
            if let Some((tex, _, _)) = &mut self.image {
                tex.set(ColorImage::from_rgb([w, h], &rgb8), egui::TextureOptions::LINEAR);
            }
            self.recolours += 1;
            // The planes stay; they now belong to the recoloured scene.
            if let Some((_, s)) = &mut self.planes {
                *s = scene.clone();
            }
            self.scene = Some(scene);
            return;
        }
        // Deep views too: the passes share one reference orbit and BLA tables (the worker
        // keeps them between jobs while the centre stays).
        let passes = if scene.width * scene.height > 64 * 64 { vec![8, 2, 1] } else { vec![1] };
        self.job = self.worker.submit(Job { scene: scene.clone(), nav: self.nav.clone(), passes });
        self.progress = (0, scene.height as u64);
        self.stage = None;
        self.scene = Some(scene);
    }

    fn poll(&mut self, ctx: &egui::Context) {
        for r in self.worker.poll() {
            match r {
                Report::Pass(p) if p.id == self.job => {
                    let image = ColorImage::from_rgb([p.width as usize, p.height as usize], &p.rgb8);
                    match &mut self.image {
                        Some((tex, nav, size)) => {
                            tex.set(image, egui::TextureOptions::LINEAR);
                            *nav = p.nav.clone();
                            *size = [p.width, p.height];
                        }
                        None => {
                            let tex = ctx.load_texture("deepfield-image", image, egui::TextureOptions::LINEAR);
                            self.image = Some((tex, p.nav.clone(), [p.width, p.height]));
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
                Report::Failed { id, message } if id == self.job => self.error = Some(message),
                _ => {}
            }
        }
        self.poll_difference(ctx);
        for r in self.julia_worker.poll() {
            if let Report::Pass(p) = r {
                let image = ColorImage::from_rgb([p.width as usize, p.height as usize], &p.rgb8);
                let c = self.julia_asked.unwrap_or_default();
                match &mut self.julia {
                    Some((tex, at)) => {
                        tex.set(image, egui::TextureOptions::LINEAR);
                        *at = c;
                    }
                    None => {
                        self.julia = Some((ctx.load_texture("deepfield-julia", image, egui::TextureOptions::LINEAR), c))
                    }
                }
                self.julia_previews += 1;
            }
        }
    }

    /// The fraction of samples whose N differs between the CPU render and the GPU f32
    /// shader, once the difference mode has compared the current render.
    pub fn difference_mismatch(&self) -> Option<f64> {
        self.diff_shown.as_ref().filter(|(_, job, _)| *job == self.job).map(|(_, _, m)| *m)
    }

    /// Starts or collects the CPU-vs-GPU comparison the difference mode shows.
    fn poll_difference(&mut self, ctx: &egui::Context) {
        if let Some(p) = &self.diff
            && let Some(result) = p.poll()
        {
            self.diff = None;
            match result {
                Ok(d) => {
                    let image = ColorImage::from_rgb([d.size[0] as usize, d.size[1] as usize], &d.rgb8);
                    let tex = ctx.load_texture("deepfield-difference", image, egui::TextureOptions::NEAREST);
                    self.diff_shown = Some((tex, d.job, d.n_mismatch));
                }
                Err(e) => self.error = Some(format!("GPU comparison failed: {e}")),
            }
        }
        let current = self.diff_shown.as_ref().is_some_and(|(_, job, _)| *job == self.job);
        if self.mode == ViewMode::Difference
            && self.diff.is_none()
            && !current
            && self.progress.0 >= self.progress.1
            && let Some((strips, scene)) = &self.planes
        {
            self.diff =
                Some(super::difference::start(self.job, scene.clone(), strips.clone(), crate::gpu::Precision::F32));
        }
    }

    /// Whether the last render is complete (no job in flight).
    pub fn idle(&self) -> bool {
        !self.needs_render && self.progress.0 >= self.progress.1 && self.planes.is_some()
    }

    fn request_julia(&mut self) {
        let Some(c) = self.julia_wanted.take() else { return };
        if self.julia_asked == Some(c) {
            return;
        }
        let mut file = self.file.clone();
        file.formula.kind = cli("julia".into());
        file.formula.c = Some(cli([format!("{:.17e}", c[0]), format!("{:.17e}", c[1])]));
        file.view = Default::default();
        file.view.center = cli(["0".into(), "0".into()]);
        file.view.zoom = Some(cli("1.3".into()));
        file.view.width = cli(200);
        file.view.height = cli(150);
        file.render.aa = cli(1);
        file.render.engine = cli("auto".into());
        file.iteration.max = cli((*file.iteration.max.get_ref()).min(500));
        let Ok(text) = toml::to_string(&file) else { return };
        if let Ok(scene) = Scene::validate(file, "julia preview", &text, &self.base_dir, crate::io::load_bitmap) {
            self.julia_asked = Some(c);
            self.julia_worker.submit(Job { scene, nav: Nav::home(), passes: vec![1] });
        }
    }
}

/// The view of a scene file.
fn nav_of(file: &SceneFile) -> Nav {
    let zoom = match (&file.view.zoom, &file.view.radius) {
        (Some(z), _) => crate::num::Decimal::parse(z.get_ref()).map(|d| d.log10_abs()).unwrap_or(0.0),
        (None, Some(r)) => crate::num::Decimal::parse(r.get_ref()).map(|d| 2f64.log10() - d.log10_abs()).unwrap_or(0.0),
        (None, None) => 1.6f64.log10(),
    };
    Nav { center: file.view.center.get_ref().clone(), log10_zoom: zoom, transform: file.view.transform() }
}

/// True when `new` differs from `old` only in colouring that `old`'s planes can serve.
fn recolourable(old: &Scene, new: &Scene) -> bool {
    let mut a = old.file.clone();
    let mut b = new.file.clone();
    a.layers.clear();
    b.layers.clear();
    a.render.background = cli(String::new());
    b.render.background = cli(String::new());
    a.render.cycle = None;
    b.render.cycle = None;
    if toml::to_string(&a).ok() != toml::to_string(&b).ok() || old.aa != new.aa {
        return false;
    }
    let have: Needs = old.stack.needs(&old.traps);
    let want: Needs = new.stack.needs(&new.traps);
    let traps_same = format!("{:?}", old.traps) == format!("{:?}", new.traps) || new.traps.is_empty();
    (have.nf || !want.nf) && (have.t || !want.t) && (have.de || !want.de) && traps_same
}

impl eframe::App for ViewerApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let ctx = ui.ctx().clone();
        self.poll(&ctx);
        self.poll_newton(&ctx);
        self.dropped_files(&ctx);
        self.keys(&ctx);
        egui::Panel::top("toolbar").show(ui, |ui| self.toolbar(ui));
        egui::Panel::bottom("status").show(ui, |ui| self.status_bar(ui));
        egui::Panel::left("controls").resizable(true).default_size(280.0).show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| self.controls(ui));
        });
        egui::CentralPanel::default().show(ui, |ui| self.image_area(ui));
        self.update_render();
        self.request_julia();
        self.export.poll();
        if self.export.running() || !self.idle() {
            ctx.request_repaint();
        }
        self.screenshot_step(&ctx);
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        let mut file = self.file.clone();
        file.view.center = cli(self.nav.center.clone());
        file.view.zoom = Some(cli(self.nav.zoom_text()));
        file.view.radius = None;
        if let Ok(scene) = toml::to_string(&file) {
            let saved = Saved {
                scene,
                nav: self.nav.clone(),
                export_path: self.export.path.clone(),
                scene_path: self.scene_path.clone(),
            };
            eframe::set_value(storage, "deepfield", &saved);
        }
    }
}

impl ViewerApp {
    fn screenshot_step(&mut self, ctx: &egui::Context) {
        let Some(path) = self.screenshot.clone() else { return };
        match self.screenshot_state.load(Ordering::Relaxed) {
            // Wait for the final pass (and a couple of frames to draw it).
            0 if self.idle() && self.started.elapsed().as_secs_f64() > 0.5 => {
                self.screenshot_state.store(1, Ordering::Relaxed);
                let state = self.screenshot_state.clone();
                let c = ctx.clone();
                ctx.request_screenshot(move |image| {
                    let (w, h) = (image.size[0] as u32, image.size[1] as u32);
                    let rgba: Vec<u8> = image.pixels.iter().flat_map(|p| p.to_array()).collect();
                    let ok = image::save_buffer(&path, &rgba, w, h, image::ColorType::Rgba8).is_ok();
                    state.store(if ok { 2 } else { 3 }, Ordering::Relaxed);
                    c.request_repaint();
                });
            }
            2 | 3 => ctx.send_viewport_cmd(egui::ViewportCommand::Close),
            _ => ctx.request_repaint(),
        }
    }

    /// True once a requested screenshot was written (or failed: false).
    pub fn screenshot_written(&self) -> Option<bool> {
        match self.screenshot_state.load(Ordering::Relaxed) {
            2 => Some(true),
            3 => Some(false),
            _ => None,
        }
    }
}

/// A labelled number field (drag or type); true when the value changed.
#[cfg(test)]
mod saved_tests {
    use super::*;

    /// A session saved with fields this version lacks, and without fields it has, opens.
    #[test]
    fn saved_sessions_survive_added_and_removed_fields() {
        let old = r#"{"scene": "version = 1\n", "nav": {"center": ["-1", "0"], "log10_zoom": 2.0}, "retired": 3}"#;
        let s: Saved = serde_json::from_str(old).expect("opens");
        assert_eq!(s.nav.center, ["-1", "0"]);
        assert_eq!(s.export_path, Saved::default().export_path);
    }
}
