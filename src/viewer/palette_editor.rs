//! The palette editor: stops you drag along a gradient strip, add by clicking it, delete and
//! recolour; the interpolation space, offset and density. Every change hands back a new
//! palette, which the viewer applies by recolouring (never by re-rendering).

use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke, Vec2};

use crate::palette::{Definition, Mode, Palette, Space, Stop, color};

/// Editor state between frames.
#[derive(Debug, Default)]
pub struct PaletteEditor {
    working: Option<Working>,
    selected: Option<usize>,
}

#[derive(Debug, Clone)]
struct Working {
    source: String,
    stops: Vec<Stop>,
    space: Space,
    mode: Mode,
    offset: f64,
    density: f64,
}

impl Working {
    fn palette(&self) -> Palette {
        Palette::with(
            self.source.clone(),
            "edited in the viewer",
            self.space,
            self.mode,
            Definition::Stops(self.stops.clone()),
        )
        .adjusted(self.offset, self.density)
    }
}

impl PaletteEditor {
    /// Shows the editor for `current`; returns the edited palette when something changed.
    pub fn show(&mut self, ui: &mut egui::Ui, current: &Palette) -> Option<Palette> {
        if self.working.as_ref().is_none_or(|w| w.source != current.name) {
            self.working = Some(Working {
                source: current.name.clone(),
                stops: current.stops(),
                space: current.space,
                mode: current.mode,
                offset: current.offset,
                density: current.density,
            });
            self.selected = None;
        }
        let w = self.working.as_mut()?;
        let mut changed = false;

        // The strip: one period of the palette; click to add a stop.
        let width = ui.available_width().max(100.0);
        let (strip, response) = ui.allocate_exact_size(Vec2::new(width, 26.0), Sense::click());
        let preview = w.palette().adjusted(0.0, 1.0);
        let painter = ui.painter_at(strip);
        let steps = (width / 2.0) as usize;
        for i in 0..steps {
            let t = i as f64 / steps as f64;
            let c = preview.at(t);
            let x0 = strip.min.x + width * i as f32 / steps as f32;
            let r =
                Rect::from_min_max(Pos2::new(x0, strip.min.y), Pos2::new(x0 + width / steps as f32 + 0.5, strip.max.y));
            painter.rect_filled(r, 0.0, to_color32(c));
        }
        if response.clicked()
            && let Some(p) = response.interact_pointer_pos()
        {
            let pos = ((p.x - strip.min.x) / width) as f64;
            if let Some(k) = w.stops.iter().rposition(|s| s.pos < pos)
                && w.stops.get(k + 1).is_none_or(|n| n.pos > pos)
            {
                let c = preview.at(pos);
                let srgb = [color::linear_to_srgb(c[0]), color::linear_to_srgb(c[1]), color::linear_to_srgb(c[2])];
                w.stops.insert(k + 1, Stop { pos, srgb, opacity: c[3] });
                self.selected = Some(k + 1);
                changed = true;
            }
        }

        // Handles: drag along the strip (the first stop stays at 0); click to select.
        let (handles, _) = ui.allocate_exact_size(Vec2::new(width, 14.0), Sense::hover());
        let n = w.stops.len();
        for k in 0..n {
            let x = handles.min.x + width * w.stops[k].pos as f32;
            let hit = Rect::from_center_size(Pos2::new(x, handles.center().y), Vec2::new(12.0, 14.0));
            let r = ui.interact(hit, ui.scope_id().with(("stop", k)), Sense::click_and_drag());
            if r.clicked() || r.drag_started() {
                self.selected = Some(k);
            }
            if r.dragged() && k > 0 {
                let lo = w.stops[k - 1].pos + 1e-3;
                let hi = w.stops.get(k + 1).map_or(1.0, |s| s.pos - 1e-3);
                let pos = (w.stops[k].pos + (r.drag_delta().x / width) as f64).clamp(lo, hi);
                if pos != w.stops[k].pos {
                    w.stops[k].pos = pos;
                    changed = true;
                }
            }
            let fill = to_color32([
                color::srgb_to_linear(w.stops[k].srgb[0]),
                color::srgb_to_linear(w.stops[k].srgb[1]),
                color::srgb_to_linear(w.stops[k].srgb[2]),
                1.0,
            ]);
            let tip = Pos2::new(x, handles.min.y);
            let pts = vec![tip, Pos2::new(x - 5.0, handles.max.y), Pos2::new(x + 5.0, handles.max.y)];
            let stroke = if self.selected == Some(k) {
                Stroke::new(2.0, Color32::WHITE)
            } else {
                Stroke::new(1.0, Color32::GRAY)
            };
            ui.painter().add(egui::Shape::convex_polygon(pts, fill, stroke));
        }

        // The selected stop: colour, opacity, delete.
        if let Some(k) = self.selected.filter(|&k| k < w.stops.len()) {
            ui.horizontal(|ui| {
                ui.label(format!("stop {k} at {:.3}", w.stops[k].pos));
                let s = w.stops[k].srgb;
                let mut rgb =
                    [(s[0] * 255.0).round() as u8, (s[1] * 255.0).round() as u8, (s[2] * 255.0).round() as u8];
                if ui.color_edit_button_srgb(&mut rgb).changed() {
                    w.stops[k].srgb = rgb.map(|v| v as f32 / 255.0);
                    changed = true;
                }
                if ui.add(egui::Slider::new(&mut w.stops[k].opacity, 0.0..=1.0).text("opacity")).changed() {
                    changed = true;
                }
                if k > 0 && w.stops.len() > 2 && ui.button("delete").clicked() {
                    w.stops.remove(k);
                    self.selected = None;
                    changed = true;
                }
            });
        }
        ui.horizontal(|ui| {
            egui::ComboBox::new("space", "space").selected_text(w.space.name()).show_ui(ui, |ui| {
                for s in [Space::Oklab, Space::Oklch, Space::Srgb, Space::Linear] {
                    changed |= ui.selectable_value(&mut w.space, s, s.name()).changed();
                }
            });
            egui::ComboBox::new("mode", "mode").selected_text(w.mode.name()).show_ui(ui, |ui| {
                for m in [Mode::Repeat, Mode::Mirror, Mode::Clamp] {
                    changed |= ui.selectable_value(&mut w.mode, m, m.name()).changed();
                }
            });
        });
        changed |= ui.add(egui::Slider::new(&mut w.offset, -1.0..=1.0).text("offset")).changed();
        changed |= ui.add(egui::Slider::new(&mut w.density, 0.05..=20.0).logarithmic(true).text("density")).changed();
        changed.then(|| w.palette())
    }
}

fn to_color32(c: [f32; 4]) -> Color32 {
    let [r, g, b] = [color::linear_to_srgb8(c[0]), color::linear_to_srgb8(c[1]), color::linear_to_srgb8(c[2])];
    Color32::from_rgb(r, g, b)
}
