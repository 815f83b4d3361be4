//! The window's panels: the toolbar, the status bar and the controls side panel, and
//! files in and out (saving the scene, exports, opening or dropping a file).

use super::*;

impl ViewerApp {
    pub(super) fn toolbar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let (b, f) = self.history.lens();
            if ui.add_enabled(b > 0, egui::Button::new("< Back")).on_hover_text("Backspace").clicked() {
                self.back();
            }
            if ui.add_enabled(f > 0, egui::Button::new("Forward >")).clicked() {
                self.forward();
            }
            if ui.button("Home").on_hover_text("Home: the whole set").clicked() {
                self.go(Nav::home());
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
            ui.add(egui::DragValue::new(&mut self.newton.factor).range(0.0..=1e6).speed(0.5).max_decimals(1))
                .labelled_by(label.id)
                .on_hover_text("zoom by this factor towards what is found; 0: frame it at once");
            if self.newton.pending.is_some() {
                ui.spinner();
            }
            ui.separator();
            ui.label("Show:");
            for (m, name) in [
                (ViewMode::Cpu, "CPU"),
                (ViewMode::GpuF32, "GPU f32"),
                (ViewMode::GpuDf, "GPU double-float"),
                (ViewMode::SideBySide, "CPU | GPU"),
                (ViewMode::Difference, "Difference"),
            ] {
                ui.selectable_value(&mut self.mode, m, name);
            }
        });
    }

    pub(super) fn status_bar(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let short = |t: &String| if t.len() > 24 { format!("{}…", &t[..24]) } else { t.clone() };
            ui.label(format!(
                "centre {} {:+}i",
                short(&self.nav.center[0]),
                short(&self.nav.center[1]).trim_start_matches('+')
            ));
            ui.separator();
            ui.label(format!("zoom {}", fmt_zoom(self.nav.log10_zoom)));
            ui.separator();
            ui.label(format!("max iter {}", self.file.iteration.max.get_ref()));
            ui.separator();
            ui.label(format!("engine {}", if self.engine.is_empty() { "-" } else { &self.engine }));
            if let Some(note) = &self.newton.note {
                ui.separator();
                ui.label(note);
            }
            ui.separator();
            let (done, total) = self.progress;
            if let (true, Some((name, d, t))) = (done < total, self.stage) {
                ui.add(egui::ProgressBar::new(fraction(d, t)).desired_width(160.0).text(stage_text(name, d, t)));
            } else if done < total {
                ui.add(egui::ProgressBar::new(fraction(done, total)).desired_width(120.0).show_percentage());
            } else {
                ui.label(format!("{:.2} s", self.last_seconds));
            }
            if let Some(warning) = self.gpu_warning() {
                ui.separator();
                ui.colored_label(Color32::from_rgb(255, 170, 40), warning);
            }
            if let Some(e) = &self.error {
                ui.separator();
                ui.colored_label(Color32::from_rgb(255, 90, 90), e);
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
        let spacing = self.nav.spacing(self.size_px[1].max(1) as f64);
        let c = self.nav.point_at([0.0, 0.0], 1.0);
        precision
            .exhausted(spacing, c)
            .then(|| format!("GPU {precision:?} precision exhausted at this depth: pixels are wrong"))
    }

    pub(super) fn controls(&mut self, ui: &mut egui::Ui) {
        ui.heading("Formula");
        let mut julia = self.file.formula.kind.get_ref() == "julia";
        ui.horizontal(|ui| {
            let m = ui.radio_value(&mut julia, false, "Mandelbrot").changed();
            let j = ui.radio_value(&mut julia, true, "Julia").changed();
            if m || j {
                self.file.formula.kind = cli(if julia { "julia" } else { "mandelbrot" }.into());
                if julia && self.file.formula.c.is_none() {
                    self.file.formula.c = Some(cli(["-0.8".into(), "0.156".into()]));
                }
                if !julia {
                    self.file.formula.c = None;
                }
                self.changed();
            }
        });
        if let Some(c) = &mut self.file.formula.c {
            let mut v = c.get_ref().clone();
            let field = |ui: &mut egui::Ui, name: &str, text: &mut String| {
                let label = ui.label(name);
                ui.text_edit_singleline(text).labelled_by(label.id)
            };
            let a = ui.horizontal(|ui| field(ui, "c re", &mut v[0])).inner;
            let b = ui.horizontal(|ui| field(ui, "c im", &mut v[1])).inner;
            if a.changed() || b.changed() {
                *c = cli(v);
                self.needs_render = true;
            }
        }
        let mut max = *self.file.iteration.max.get_ref();
        let edited = ui
            .horizontal(|ui| {
                let label = ui.label("max iterations");
                ui.add(egui::DragValue::new(&mut max).range(1..=100_000_000).speed(10.0)).labelled_by(label.id)
            })
            .inner;
        if edited.changed() {
            self.file.iteration.max = cli(max);
            self.changed();
        }
        ui.separator();
        ui.heading("Layers");
        if crate::viewer::layers_panel::show(ui, &mut self.file.layers, &mut self.overrides, &mut self.selected_layer) {
            self.changed();
        }
        ui.separator();
        ui.heading("Palette editor");
        let current = self
            .scene
            .as_ref()
            .and_then(|s| s.stack.layers.get(self.selected_layer))
            .and_then(|l| l.coloring.palette().cloned());
        match current {
            Some(p) => {
                if let Some(edited) = self.editor.show(ui, &p) {
                    self.overrides.insert(self.selected_layer, edited);
                    self.changed();
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
        let path = PathBuf::from(&self.scene_path);
        let mut file = self.file.clone();
        file.view.center = cli(self.nav.center.clone());
        file.view.zoom = Some(cli(self.nav.zoom_text()));
        file.view.radius = None;
        // Edited palettes are saved beside the scene and referred to by file name.
        for (k, p) in &self.overrides {
            let stem = path.file_stem().map_or("scene".into(), |s| s.to_string_lossy().into_owned());
            let name = format!("{stem}-layer{k}.toml");
            let dir = path.parent().unwrap_or(Path::new("."));
            std::fs::write(dir.join(&name), palette::to_toml(p)).map_err(|e| format!("{name}: {e}"))?;
            if let Some(l) = file.layers.get_mut(*k) {
                l.get_mut().palette = Some(cli(name));
            }
        }
        let text = toml::to_string(&file).map_err(|e| e.to_string())?;
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
    }

    pub(super) fn start_export(&mut self, req: ExportRequest) {
        match self.scene_for_view() {
            Ok(scene) => self.export.start(scene, req),
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
            self.overrides.insert(self.selected_layer, p);
            self.changed();
            return Ok(());
        }
        let s = crate::io::read_scene_source(path).map_err(|e| e.to_string())?;
        let file = Scene::parse_file(&s.origin, &s.text).map_err(|e| e.to_string())?;
        self.history.push(self.nav.clone());
        self.nav = nav_of(&file);
        self.file = file;
        self.origin = s.origin;
        self.base_dir = s.base_dir;
        self.overrides.clear();
        self.selected_layer = 0;
        if self.file.layers.is_empty() {
            self.file.layers.push(Spanned::new(0..0, LayerRaw::of_kind("smooth")));
        }
        self.changed();
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
