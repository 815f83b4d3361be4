//! Export from the viewer: PNG (and optionally EXR) at a chosen size and supersampling,
//! through the same render path and writers as `deepfield render`, on a background thread
//! with progress and cancel.

use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use eframe::egui;

use crate::field::ChannelSet;
use crate::render::{self, Options};
use crate::scene::Scene;
use crate::source::SourceError;

/// What the user requested.
#[derive(Debug, Clone)]
pub struct ExportRequest {
    /// PNG path.
    pub png: PathBuf,
    /// Optional EXR path.
    pub exr: Option<PathBuf>,
    /// Size in pixels.
    pub size: [u32; 2],
    /// Supersampling.
    pub aa: u32,
}

/// The export panel's state and the running export.
pub struct Export {
    /// PNG path typed by the user.
    pub path: String,
    exr: bool,
    size: [u32; 2],
    aa: u32,
    running: Option<Running>,
    message: Option<String>,
}

struct Running {
    cancel: Arc<AtomicBool>,
    rows: Arc<AtomicU64>,
    total: u64,
    thread: JoinHandle<Result<f64, String>>,
}

impl Export {
    /// An idle export panel (with the last session's path, if any).
    pub fn new(path: Option<String>) -> Self {
        Self {
            path: path.unwrap_or_else(|| "deepfield-export.png".into()),
            exr: false,
            size: [1920, 1080],
            aa: 2,
            running: None,
            message: None,
        }
    }

    /// True while an export runs.
    pub fn running(&self) -> bool {
        self.running.is_some()
    }

    /// Draws the panel; returns a request when the user starts an export.
    pub fn show(&mut self, ui: &mut egui::Ui) -> Option<ExportRequest> {
        ui.horizontal(|ui| {
            let label = ui.label("PNG");
            ui.text_edit_singleline(&mut self.path).labelled_by(label.id);
        });
        ui.horizontal(|ui| {
            ui.add(egui::DragValue::new(&mut self.size[0]).range(1..=65536).prefix("w "));
            ui.add(egui::DragValue::new(&mut self.size[1]).range(1..=65536).prefix("h "));
            ui.add(egui::DragValue::new(&mut self.aa).range(1..=8).prefix("aa "));
            ui.checkbox(&mut self.exr, "EXR too");
        });
        let mut request = None;
        match &self.running {
            Some(r) => {
                ui.horizontal(|ui| {
                    let done = r.rows.load(Ordering::Relaxed);
                    ui.add(egui::ProgressBar::new(done as f32 / r.total.max(1) as f32).show_percentage());
                    if ui.button("Cancel").clicked() {
                        r.cancel.store(true, Ordering::Relaxed);
                    }
                });
            }
            None => {
                if ui.button("Export").clicked() {
                    let png = PathBuf::from(&self.path);
                    request = Some(ExportRequest {
                        exr: self.exr.then(|| png.with_extension("exr")),
                        png,
                        size: self.size,
                        aa: self.aa,
                    });
                }
            }
        }
        if let Some(m) = &self.message {
            ui.label(m);
        }
        request
    }

    /// Starts rendering `scene` (the current view) at the requested size, or says why the
    /// scene cannot have it (too many samples).
    pub fn start(&mut self, scene: Scene, req: ExportRequest) -> Result<(), SourceError> {
        let scene = scene.with_size(req.size[0], req.size[1], req.aa)?;
        let cancel = Arc::new(AtomicBool::new(false));
        let rows = Arc::new(AtomicU64::new(0));
        let (c, r) = (cancel.clone(), rows.clone());
        let total = scene.height as u64;
        let thread = std::thread::spawn(move || export(&scene, &req, &c, &r));
        self.message = None;
        self.running = Some(Running { cancel, rows, total, thread });
        Ok(())
    }

    /// Collects a finished export.
    pub fn poll(&mut self) {
        if self.running.as_ref().is_some_and(|r| r.thread.is_finished())
            && let Some(r) = self.running.take()
        {
            self.message = Some(match r.thread.join() {
                Ok(Ok(s)) => format!("exported in {s:.2} s"),
                Ok(Err(e)) => e,
                Err(_) => "the export thread panicked".into(),
            });
        }
    }
}

/// Renders and writes; the files appear only when complete (atomic writers).
fn export(scene: &Scene, req: &ExportRequest, cancel: &AtomicBool, rows: &AtomicU64) -> Result<f64, String> {
    let channels = if req.exr.is_some() { scene.channels } else { ChannelSet::default() };
    let targets = crate::io::output::Targets {
        png: Some(&req.png),
        exr: req.exr.as_deref(),
        tile: None,
        engine: "viewer export",
    };
    let (writers, encoders) = crate::io::output::open(scene, targets).map_err(|e| e.to_string())?;
    let writers = Mutex::new(Some(writers));
    let prepare = |strip: &render::RenderedStrip| {
        Ok(encoders.encode(strip.row, &strip.rgb, &strip.planes, strip.samples.as_deref())?)
    };
    let progress = |p: render::Progress| {
        if let render::Progress::Rows(r) = p {
            rows.store(r, Ordering::Relaxed);
        }
    };
    let plan = render::engine::plan(scene).map_err(|e| e.to_string())?;
    let stats = render::render(
        scene,
        &plan,
        Options { threads: 0, exr_channels: channels, ..Options::default() },
        cancel,
        &progress,
        &prepare,
        |_, encoded| match writers.lock().unwrap_or_else(|e| e.into_inner()).as_mut() {
            Some(w) => Ok(w.write(encoded)?),
            None => Err("the export's files are already closed".into()),
        },
    )
    .map_err(|e| e.to_string())?;
    if let Some(w) = writers.lock().unwrap_or_else(|e| e.into_inner()).take() {
        w.finish().map_err(|e| e.to_string())?;
    }
    Ok(stats.wall_seconds)
}
