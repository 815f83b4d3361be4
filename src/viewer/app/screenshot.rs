//! Headless screenshots (`view --screenshot`): once the render is complete, the whole
//! window is written to a PNG and the window closes.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Instant;

use eframe::egui;

/// Where the screenshot goes and how far it has got.
pub(super) struct Screenshot {
    path: Option<PathBuf>,
    /// 0: waiting for the render, 1: requested, 2: written, 3: failed.
    state: Arc<AtomicU64>,
    started: Instant,
}

impl Screenshot {
    /// A screenshot to `path` (None: none is taken).
    pub(super) fn new(path: Option<PathBuf>) -> Self {
        Self { path, state: Arc::new(AtomicU64::new(0)), started: Instant::now() }
    }

    /// Takes the screenshot once the render is complete (`idle`), then closes the window.
    pub(super) fn step(&mut self, ctx: &egui::Context, idle: bool) {
        let Some(path) = self.path.clone() else { return };
        match self.state.load(Ordering::Relaxed) {
            // Wait for the final pass (and a couple of frames to draw it).
            0 if idle && self.started.elapsed().as_secs_f64() > 0.5 => {
                self.state.store(1, Ordering::Relaxed);
                let state = self.state.clone();
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

    /// True once the screenshot was written (false: it failed), None before.
    pub(super) fn written(&self) -> Option<bool> {
        match self.state.load(Ordering::Relaxed) {
            2 => Some(true),
            3 => Some(false),
            _ => None,
        }
    }
}
