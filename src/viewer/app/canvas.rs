//! The image area: pointer navigation, and drawing the last image where it belongs in the
//! current view (CPU texture or the GPU paint callback) while a new one renders.

use super::*;

impl ViewerApp {
    pub(super) fn image_area(&mut self, ui: &mut egui::Ui) {
        let rect = ui.available_rect_before_wrap();
        let ppp = ui.ctx().pixels_per_point();
        let size = [(rect.width() * ppp).round().max(1.0) as u32, (rect.height() * ppp).round().max(1.0) as u32];
        if self.view.lay_out(rect, size) {
            self.render.invalidate();
        }
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let painter = ui.painter_at(rect);
        painter.rect_filled(rect, 0.0, Color32::from_gray(12));
        let h = self.view.height();
        // Pointer position in physical pixels from the image centre (y down).
        let to_px = |p: Pos2| [((p.x - rect.center().x) * ppp) as f64, ((p.y - rect.center().y) * ppp) as f64];
        self.draw_image(ui, rect, ppp);

        // Wheel: zoom about the cursor.
        if let Some(pos) = response.hover_pos() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll.abs() > 0.0 {
                self.view.wheel_zoom(2f64.powf(scroll as f64 / 120.0), to_px(pos));
                self.render.invalidate();
            }
            if self.doc.is_mandelbrot() {
                self.julia.want(self.view.nav().point_at(to_px(pos), h));
            }
        }
        // Drag: pan (the image follows the pointer); right-drag or shift-drag: box zoom.
        let boxing = ui.input(|i| i.modifiers.shift) || response.dragged_by(PointerButton::Secondary);
        if response.drag_started() && boxing {
            self.view.set_box_start(response.interact_pointer_pos());
        }
        if response.dragged() && self.view.box_start().is_none() {
            let d = response.drag_delta();
            if d != Vec2::ZERO {
                self.view.drag_pan(-(d.x * ppp) as f64, -(d.y * ppp) as f64, response.drag_started());
                self.render.invalidate();
            }
        }
        if let (Some(a), Some(b)) = (self.view.box_start(), response.interact_pointer_pos()) {
            painter.rect_stroke(
                Rect::from_two_pos(a, b),
                0.0,
                egui::Stroke::new(1.5, Color32::WHITE),
                egui::StrokeKind::Middle,
            );
            if response.drag_stopped() {
                let n = self.view.nav().zoom_box(to_px(a), to_px(b), self.view.size_px()[0] as f64, h);
                self.view.set_box_start(None);
                self.go(n);
            }
        }
        if !response.dragged() && !response.drag_stopped() {
            self.view.set_box_start(None);
        }
        // Ctrl-click on a Mandelbrot view: open the Julia set of the point.
        if response.clicked()
            && ui.input(|i| i.modifiers.command || i.modifiers.ctrl)
            && self.doc.is_mandelbrot()
            && let Some(pos) = response.interact_pointer_pos()
        {
            let c = self.view.nav().point_at(to_px(pos), h);
            self.open_julia([format!("{:.17e}", c[0]), format!("{:.17e}", c[1])]);
        }
        // Julia preview inset.
        if let Some((tex, c, formula)) = self.julia.shown()
            && self.doc.is_mandelbrot()
        {
            let inset = Rect::from_min_size(rect.right_bottom() - Vec2::new(210.0, 160.0), Vec2::new(200.0, 150.0));
            painter.image(tex.id(), inset, Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)), Color32::WHITE);
            painter.rect_stroke(inset, 0.0, egui::Stroke::new(1.0, Color32::from_gray(200)), egui::StrokeKind::Outside);
            painter.text(
                inset.left_top() + Vec2::new(4.0, 2.0),
                egui::Align2::LEFT_TOP,
                format!("{formula} Julia c = {:.5} {:+.5}i (ctrl-click)", c[0], c[1]),
                egui::FontId::proportional(11.0),
                Color32::WHITE,
            );
        }
    }

    /// Draws the last image where it belongs in the current view, or the GPU image.
    pub(super) fn draw_image(&mut self, ui: &mut egui::Ui, rect: Rect, ppp: f32) {
        let painter = ui.painter_at(rect);
        let gpu_rect = match self.mode {
            ViewMode::Cpu => None,
            ViewMode::GpuF32 | ViewMode::GpuDf => Some(rect),
            ViewMode::Difference => None,
            ViewMode::SideBySide => Some(Rect::from_min_max(Pos2::new(rect.center().x, rect.min.y), rect.max)),
        };
        if let Some(shown) = self.render.image() {
            // Where the image's own view lies in the current one.
            let (nav, size, h) = (self.view.nav(), shown.size, self.view.height());
            let scale = 10f64.powf(nav.log10_zoom - shown.nav.log10_zoom) as f32;
            let off = nav.offset_px_of(&shown.nav, h);
            let centre = rect.center() + Vec2::new(off[0] as f32 / ppp, -off[1] as f32 / ppp);
            let img_size = Vec2::new(size[0] as f32, size[1] as f32)
                * (self.view.size_px()[1] as f32 / size[1].max(1) as f32)
                * scale
                / ppp;
            let at = Rect::from_center_size(centre, img_size);
            let clip = match gpu_rect {
                Some(g) if self.mode == ViewMode::SideBySide => {
                    Rect::from_min_max(rect.min, Pos2::new(g.min.x, rect.max.y))
                }
                _ => rect,
            };
            if matches!(self.mode, ViewMode::Cpu | ViewMode::SideBySide) {
                ui.painter_at(clip).image(
                    shown.texture.id(),
                    at,
                    Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)),
                    Color32::WHITE,
                );
            }
        }
        match self.mode {
            ViewMode::Difference => match self.diff.shown_for(self.render.job()) {
                Some((tex, mismatch)) => {
                    painter.image(tex.id(), rect, Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0)), Color32::WHITE);
                    let text = format!("|CPU - GPU f32| x 4; N differs on {:.3}% of samples", mismatch * 100.0);
                    painter.text(
                        rect.left_top() + Vec2::new(6.0, 6.0),
                        egui::Align2::LEFT_TOP,
                        text,
                        egui::FontId::proportional(13.0),
                        Color32::WHITE,
                    );
                }
                _ => {
                    painter.text(
                        rect.center(),
                        egui::Align2::CENTER_CENTER,
                        "comparing with the GPU…",
                        egui::FontId::proportional(16.0),
                        Color32::WHITE,
                    );
                }
            },
            _ => {
                if let Some(g) = gpu_rect
                    && let Some(params) = self.gpu_params(rect, g, ppp)
                {
                    ui.painter_at(g).add(crate::viewer::paint::paint_callback(g, params));
                }
            }
        }
    }

    /// The paint callback's parameters for drawing the part `rect` of the image area `full`.
    pub(super) fn gpu_params(&self, full: Rect, rect: Rect, ppp: f32) -> Option<crate::viewer::paint::PaintParams> {
        let scene = self.render.scene()?;
        // The paint shader draws z² + c in unrotated, unstretched views only.
        if !scene.transform.is_identity() || !scene.formula.is_quadratic() {
            return None;
        }
        let (nav, h) = (self.view.nav(), self.view.height());
        let spacing = nav.spacing(h);
        // The GPU half of a side-by-side view shows the right half of the same view.
        let dx = ((rect.center().x - full.center().x) * ppp) as f64;
        let centre = nav.point_at([dx, 0.0], h);
        let interior = scene
            .stack
            .layers
            .iter()
            .find_map(|l| match &l.coloring {
                crate::coloring::Coloring::Smooth { interior, .. } => Some(*interior),
                _ => None,
            })
            .unwrap_or([0.0, 0.0, 0.0, 1.0]);
        let (palette, density, offset) = scene
            .stack
            .layers
            .iter()
            .find_map(|l| match &l.coloring {
                crate::coloring::Coloring::Smooth { palette, density, offset, .. } => {
                    Some((palette.clone(), *density, *offset))
                }
                _ => None,
            })
            .unwrap_or_else(|| {
                (
                    palette::builtin("classic").unwrap_or_else(|| {
                        Palette::new("grey", palette::Space::Linear, palette::Mode::Repeat, Vec::new())
                    }),
                    0.05,
                    0.0,
                )
            });
        let distance_k = scene.stack.layers.iter().find_map(|l| match &l.coloring {
            crate::coloring::Coloring::Distance { style: crate::coloring::DistanceStyle::Soft { k }, .. } => {
                Some(*k as f32)
            }
            _ => None,
        });
        // One period of the layer's palette position (the palette's own density, offset and
        // mode applied); the shader wraps position = nu * density + offset into it.
        let lut = crate::viewer::paint::palette_table(&palette, 1024);
        Some(crate::viewer::paint::PaintParams {
            center: centre,
            spacing,
            size_px: [(rect.width() * ppp) as u32, (rect.height() * ppp) as u32],
            julia: match &scene.family {
                crate::scene::FamilySpec::Julia { c } => Some([c[0].to_f64(), c[1].to_f64()]),
                crate::scene::FamilySpec::Mandelbrot => None,
            },
            max_iter: scene.max_iter,
            escape_radius: scene.escape_radius,
            precision: if self.mode == ViewMode::GpuDf {
                crate::gpu::Precision::DoubleFloat
            } else {
                crate::gpu::Precision::F32
            },
            palette: lut,
            density: density as f32,
            offset: offset as f32,
            distance_k,
            interior,
        })
    }
}
