//! The window's panels: the toolbar, the status bar and the controls side panel, and
//! files in and out (saving the scene, exports, opening or dropping a file).

use super::*;

/// The colour of error messages.
const ERROR_COLOUR: Color32 = Color32::from_rgb(255, 90, 90);

impl ViewerApp {
    pub(super) fn toolbar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let (b, f) = self.view.history_lens();
            if ui.add_enabled(b > 0, egui::Button::new("< Back")).on_hover_text("Backspace").clicked() {
                self.back();
            }
            if ui.add_enabled(f > 0, egui::Button::new("Forward >")).clicked() {
                self.forward();
            }
            if ui.button("Home").on_hover_text("Home: the whole set").clicked() {
                self.go(self.default_view());
            }
            ui.separator();
            let minibrot = ui
                .button("Minibrot")
                .on_hover_text("N: Newton zoom to the minibrot under the pointer (here: the centre)");
            if minibrot.clicked() {
                self.start_newton(crate::viewer::newton::Target::Minibrot, [0.0, 0.0]);
            }
            let point =
                ui.button("Misiurewicz").on_hover_text("M: Newton zoom to the Misiurewicz point under the pointer");
            if point.clicked() {
                self.start_newton(crate::viewer::newton::Target::Misiurewicz, [0.0, 0.0]);
            }
            let label = ui.label("step");
            ui.add(egui::DragValue::new(self.newton.factor_mut()).range(0.0..=1e6).speed(0.5).max_decimals(1))
                .labelled_by(label.id)
                .on_hover_text("zoom by this factor towards what is found; 0: frame it at once");
            if self.newton.pending() {
                ui.spinner();
            }
            ui.separator();
            ui.label("Show:");
            // The GPU shaders draw z² + c only.
            let gpu = self.doc.formula().is_quadratic();
            for (m, name) in [
                (ViewMode::Cpu, "CPU"),
                (ViewMode::GpuF32, "GPU f32"),
                (ViewMode::GpuDf, "GPU double-float"),
                (ViewMode::SideBySide, "CPU | GPU"),
                (ViewMode::Difference, "Difference"),
            ] {
                ui.add_enabled_ui(gpu || m == ViewMode::Cpu, |ui| ui.selectable_value(&mut self.mode, m, name))
                    .response
                    .on_disabled_hover_text("the GPU shaders draw z² + c only");
            }
        });
    }

    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let short = |t: &String| if t.len() > 24 { format!("{}…", &t[..24]) } else { t.clone() };
            ui.label(self.formula_title());
            ui.separator();
            let nav = self.view.nav();
            ui.label(format!("centre {} {:+}i", short(&nav.center[0]), short(&nav.center[1]).trim_start_matches('+')));
            ui.separator();
            ui.label(format!("zoom {}", fmt_zoom(nav.log10_zoom)));
            ui.separator();
            ui.label(format!("max iter {}", self.doc.max_iter()));
            ui.separator();
            let engine = self.render.engine();
            ui.label(format!("engine {}", if engine.is_empty() { "-" } else { engine }));
            if let Some(note) = self.newton.note() {
                ui.separator();
                ui.label(note);
            }
            ui.separator();
            let (done, total) = self.render.progress();
            if let (true, Some((name, d, t))) = (done < total, self.render.stage()) {
                ui.add(egui::ProgressBar::new(fraction(d, t)).desired_width(160.0).text(stage_text(name, d, t)));
            } else if done < total {
                ui.add(egui::ProgressBar::new(fraction(done, total)).desired_width(120.0).show_percentage());
            } else {
                ui.label(format!("{:.2} s", self.render.last_seconds()));
            }
            if let Some(warning) = self.gpu_warning() {
                ui.separator();
                ui.colored_label(Color32::from_rgb(255, 170, 40), warning);
            }
            let scene_error = self.doc.error().map(ToString::to_string);
            if let Some(e) = self.error.as_ref().or(scene_error.as_ref()) {
                ui.separator();
                ui.colored_label(ERROR_COLOUR, e);
            }
        });
    }

    /// A warning when the GPU mode shown cannot resolve the current depth.
    pub(super) fn gpu_warning(&self) -> Option<String> {
        let precision = match self.mode {
            ViewMode::Cpu => return None,
            ViewMode::GpuDf => crate::gpu::Precision::DoubleFloat,
            _ => crate::gpu::Precision::F32,
        };
        let spacing = self.view.nav().spacing(self.view.height());
        let c = self.view.nav().point_at([0.0, 0.0], 1.0);
        precision
            .exhausted(spacing, c)
            .then(|| format!("GPU {precision:?} precision exhausted at this depth: pixels are wrong"))
    }

    pub(super) fn controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Formula");
        if let Some(f) = self.chooser.show(ui, self.doc.formula())
            && let Err(e) = self.set_formula(f)
        {
            self.chooser.refused(e);
        }
        let c = self.doc.julia_c();
        let mut julia = !self.doc.is_mandelbrot();
        ui.horizontal(|ui| {
            let m = ui.radio_value(&mut julia, false, "Mandelbrot").on_hover_text("c is the pixel, z starts at 0");
            let j = ui.radio_value(&mut julia, true, "Julia").on_hover_text("c is fixed, z starts at the pixel");
            if m.changed() || j.changed() {
                let c = c.clone().unwrap_or_else(|| ["-0.8".into(), "0.156".into()]);
                self.doc.set_julia(julia.then_some(c));
                self.render.invalidate();
            }
            if ui.button("Reset view").on_hover_text("the whole set of this formula in this form").clicked() {
                self.go(self.default_view());
            }
        });
        if let Some(mut v) = self.doc.julia_c() {
            let field = |ui: &mut egui::Ui, name: &str, text: &mut String| {
                let label = ui.label(name);
                ui.text_edit_singleline(text).labelled_by(label.id)
            };
            let a = ui.horizontal(|ui| field(ui, "c re", &mut v[0])).inner;
            let b = ui.horizontal(|ui| field(ui, "c im", &mut v[1])).inner;
            if a.changed() || b.changed() {
                self.doc.set_julia(Some(v));
                self.render.invalidate();
            }
            // A value the scene refuses: said here; the image keeps the last valid one.
            if let Some(e) = self.doc.error_at("formula.c") {
                ui.colored_label(ERROR_COLOUR, &e.message);
            }
        }
        let mut max = self.doc.max_iter();
        let edited = ui
            .horizontal(|ui| {
                let label = ui.label("max iterations");
                ui.add(egui::DragValue::new(&mut max).range(1..=100_000_000).speed(10.0)).labelled_by(label.id)
            })
            .inner;
        if edited.changed() {
            self.doc.set_max_iter(max);
            self.render.invalidate();
        }
        ui.separator();
        ui.heading("Layers");
        if self.doc.layers_ui(ui) {
            self.render.invalidate();
        }
        ui.separator();
        ui.heading("Palette editor");
        match self.doc.selected_palette() {
            Some(p) => {
                if let Some(edited) = self.editor.show(ui, &p) {
                    self.doc.override_selected(edited);
                    self.render.invalidate();
                }
            }
            None => {
                ui.label("(the selected layer has no palette)");
            }
        }
        ui.label(
            "Drop a palette file (.map .ggr .ugr .kfp .cpt .toml) to use it here; drop a scene or image to open it.",
        );
        ui.separator();
        ui.heading("Save and export");
        ui.horizontal(|ui| {
            let label = ui.label("scene");
            ui.text_edit_singleline(&mut self.scene_path).labelled_by(label.id);
            if ui.button("Save scene").clicked() {
                self.error = self.save_scene().err();
            }
        });
        let request = self.export.show(ui);
        if let Some(req) = request {
            self.start_export(req);
        }
    }

    pub(super) fn save_scene(&self) -> Result<(), String> {
        let nav = self.view.nav();
        self.doc.save(Path::new(&self.scene_path), nav.center.clone(), nav.zoom_text())
    }

    pub(super) fn start_export(&mut self, req: ExportRequest) {
        match self.scene_for_view() {
            Ok(scene) => self.error = self.export.start(scene, req).err().map(|e| e.to_string()),
            Err(e) => self.error = Some(e),
        }
    }

    pub(super) fn dropped_files(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw.dropped_files.iter().map(|f| f.path().to_path_buf()).filter(|p| !p.as_os_str().is_empty()).collect()
        });
        for path in dropped {
            self.error = self.open_path(&path).err();
        }
    }

    /// Opens a dropped or named file: a palette (for the selected layer) or a scene.
    pub fn open_path(&mut self, path: &Path) -> Result<(), String> {
        let is_palette_file = palette::import::Format::from_path(path).is_some()
            || (path.extension().is_some_and(|e| e == "toml")
                && std::fs::read_to_string(path).is_ok_and(|t| !t.contains("version") && t.contains("name")));
        if is_palette_file {
            let p = if palette::import::Format::from_path(path).is_some() {
                palette::import::import_file(path).map_err(|e| e.to_string())?.remove(0)
            } else {
                palette::load(&path.display().to_string(), None).map_err(|e| e.to_string())?
            };
            self.doc.override_selected(p);
            self.render.invalidate();
            return Ok(());
        }
        let s = crate::io::read_scene_source(path).map_err(|e| e.to_string())?;
        // A scene that does not validate is refused with its line and column; the one shown
        // stays.
        let doc = Document::from_text(s.origin, &s.text, s.base_dir).map_err(|e| e.to_string())?;
        let nav = Nav::of_scene(&doc.scene());
        self.doc = doc;
        self.go(nav);
        self.render.invalidate();
        Ok(())
    }
}

/// `done` of `total` as a progress bar's fraction.
fn fraction(done: u64, total: u64) -> f32 {
    (done as f64 / total.max(1) as f64) as f32
}

/// The status bar's text for a stage in progress (`name`: [`render::Progress::name`]):
/// "steps of blocks 45%".
fn stage_text(name: &str, done: u64, total: u64) -> String {
    format!("{name} {:.0}%", 100.0 * f64::from(fraction(done, total)))
}

/// Formats a zoom given as log10.
fn fmt_zoom(log10: f64) -> String {
    if log10.abs() < 6.0 {
        format!("{:.3}", 10f64.powf(log10))
    } else {
        let e = log10.floor();
        format!("{:.3}e{}", 10f64.powf(log10 - e), e)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render;

    #[test]
    fn stages_are_named_with_their_share_done() {
        let (blocks, reference) = (
            render::Progress::Blocks { done: 0, total: 0 }.name(),
            render::Progress::Reference { done: 0, total: 0 }.name(),
        );
        assert_eq!(stage_text(blocks, 45, 100), "steps of blocks 45%");
        assert_eq!(stage_text(reference, 1, 3), "reference orbit 33%");
        assert_eq!(stage_text(reference, 0, 0), "reference orbit 0%");
    }
}
