//! The difference mode's state: the CPU-vs-GPU comparison of the current render in flight
//! ([`crate::viewer::difference`]) and the last one finished, as a texture.

use eframe::egui::{self, ColorImage, TextureHandle};

use super::render_state::RenderState;
use crate::viewer::difference::{self, Pending};

/// The comparison in flight and the last one shown.
#[derive(Default)]
pub(super) struct DifferenceView {
    pending: Option<Pending>,
    /// The difference image, the job it compares and the fraction of samples whose N
    /// differs.
    shown: Option<(TextureHandle, u64, f64)>,
}

impl DifferenceView {
    /// Collects a finished comparison, and starts one of the current render once it is
    /// complete (when `wanted`: the difference mode is shown). Returns why a comparison
    /// failed, if one did.
    pub(super) fn poll(&mut self, ctx: &egui::Context, wanted: bool, render: &RenderState) -> Option<String> {
        let mut failed = None;
        if let Some(p) = &self.pending
            && let Some(result) = p.poll()
        {
            self.pending = None;
            match result {
                Ok(d) => {
                    let image = ColorImage::from_rgb([d.size[0] as usize, d.size[1] as usize], &d.rgb8);
                    let tex = ctx.load_texture("deepfield-difference", image, egui::TextureOptions::NEAREST);
                    self.shown = Some((tex, d.job, d.n_mismatch));
                }
                Err(e) => failed = Some(format!("GPU comparison failed: {e}")),
            }
        }
        if wanted
            && self.pending.is_none()
            && self.shown_for(render.job()).is_none()
            && render.complete()
            && let Some((strips, scene)) = render.planes()
        {
            self.pending =
                Some(difference::start(render.job(), scene.clone(), strips.clone(), crate::gpu::Precision::F32));
        }
        failed
    }

    /// The difference image of job `job` and its N mismatch, once compared.
    pub(super) fn shown_for(&self, job: u64) -> Option<(&TextureHandle, f64)> {
        self.shown.as_ref().filter(|(_, j, _)| *j == job).map(|(t, _, m)| (t, *m))
    }
}
