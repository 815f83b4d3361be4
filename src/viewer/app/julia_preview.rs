//! The Julia preview: while the pointer moves over the Mandelbrot form of a formula, the
//! Julia set of that formula at the point under it (its Julia form), rendered small on a
//! worker of its own and shown in an inset.

use eframe::egui::{self, ColorImage, TextureHandle};

use super::document::Document;
use crate::formula::Formula;
use crate::viewer::nav::Nav;
use crate::viewer::worker::{Job, Report, Worker};

/// The preview's worker, what is wanted and what is shown.
pub(super) struct JuliaPreview {
    worker: Worker,
    /// The texture, the parameter and the formula it shows.
    shown: Option<(TextureHandle, [f64; 2], Formula)>,
    /// The parameter under the pointer this frame.
    wanted: Option<[f64; 2]>,
    /// The parameter and formula last rendered.
    asked: Option<([f64; 2], Formula)>,
    previews: u64,
}

impl JuliaPreview {
    /// No preview yet.
    pub(super) fn new(worker: Worker) -> Self {
        Self { worker, shown: None, wanted: None, asked: None, previews: 0 }
    }

    /// The pointer is over parameter `c`.
    pub(super) fn want(&mut self, c: [f64; 2]) {
        self.wanted = Some(c);
    }

    /// Starts a preview of the parameter wanted, if it (or the formula) is new.
    pub(super) fn request(&mut self, doc: &Document) {
        let Some(c) = self.wanted.take() else { return };
        let asked = (c, doc.formula());
        if self.asked == Some(asked) {
            return;
        }
        // A scene the preview cannot build (the scene as edited is not valid) shows none.
        if let Ok(scene) = doc.julia_preview(c) {
            self.asked = Some(asked);
            self.worker.submit(Job { scene, nav: Nav::home(), passes: vec![1] });
        }
    }

    /// Collects a finished preview.
    pub(super) fn poll(&mut self, ctx: &egui::Context) {
        for r in self.worker.poll() {
            if let Report::Pass(p) = r {
                let image = ColorImage::from_rgb([p.width as usize, p.height as usize], &p.rgb8);
                let (c, f) = self.asked.unwrap_or_default();
                match &mut self.shown {
                    Some((tex, at, formula)) => {
                        tex.set(image, egui::TextureOptions::LINEAR);
                        (*at, *formula) = (c, f);
                    }
                    None => {
                        let tex = ctx.load_texture("deepfield-julia", image, egui::TextureOptions::LINEAR);
                        self.shown = Some((tex, c, f));
                    }
                }
                self.previews += 1;
            }
        }
    }

    /// The preview shown, its parameter and its formula.
    pub(super) fn shown(&self) -> Option<&(TextureHandle, [f64; 2], Formula)> {
        self.shown.as_ref()
    }

    /// Previews rendered so far.
    pub(super) fn previews(&self) -> u64 {
        self.previews
    }
}
