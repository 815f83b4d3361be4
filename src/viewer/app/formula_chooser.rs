//! The formula chooser: a family from [`KINDS`] (by the name users write, Kalles Fraktaler's
//! as hover text), its power within the powers the family comes in, or any formula typed as
//! text (a hybrid: `burning-ship,mandelbrot^3`) and read by [`Formula::parse`], and the
//! coefficient a of a formula that takes one. What is
//! chosen is a [`Formula`] for the app to give the document; text the parser refuses is
//! said under the field and changes nothing.

use eframe::egui::{self, Color32};

use crate::formula::kind::{KINDS, KindInfo};
use crate::formula::{Formula, Phase};

/// The colour of the chooser's error line.
const ERROR_COLOUR: Color32 = Color32::from_rgb(255, 90, 90);

/// The formula field's text and why it was refused.
#[derive(Default)]
pub(super) struct FormulaChooser {
    /// The text of the formula field.
    text: String,
    /// The formula the text was last written from: the field follows the scene's formula,
    /// and keeps what was typed while that formula stays.
    synced: Option<Formula>,
    /// Why the formula typed (or chosen) was refused.
    error: Option<String>,
}

impl FormulaChooser {
    /// Draws the chooser for the scene's formula `current`; returns the formula chosen, if
    /// one was.
    pub(super) fn show(&mut self, ui: &mut egui::Ui, current: Formula) -> Option<Formula> {
        if self.synced != Some(current) {
            self.text = current.to_string();
            self.synced = Some(current);
            self.error = None;
        }
        let mut chosen = None;
        let single = match current.phases() {
            [p] => Some(*p),
            _ => None,
        };
        let shown = single.map_or("hybrid", |p| p.kind.name());
        ui.horizontal(|ui| {
            let label = ui.label("family");
            let mut kind = single.map(|p| p.kind);
            egui::ComboBox::new("formula-family", "")
                .selected_text(shown)
                .width(125.0)
                .show_ui(ui, |ui| {
                    for info in &KINDS {
                        let r = ui.selectable_value(&mut kind, Some(info.kind), info.name).on_hover_text(hover(info));
                        if r.clicked() && single.map(|p| p.kind) != Some(info.kind) {
                            let power = single.map_or(info.min_power, |p| p.power);
                            let power = if info.kind.has_power(power) { power } else { info.kind.default_power() };
                            chosen = Some(keep_a(Formula::single(Phase::new(info.kind, power)), current));
                        }
                    }
                })
                .response
                .labelled_by(label.id)
                .on_hover_text(
                    single.map_or_else(
                        || "a hybrid: its phases are in the formula field".into(),
                        |p| hover(p.kind.info()),
                    ),
                );
            // The powers the family comes in (one: nothing to choose).
            if let Some(p) = single {
                let info = p.kind.info();
                let label = ui.label("power");
                ui.add_enabled_ui(info.min_power < info.max_power, |ui| {
                    egui::ComboBox::new("formula-power", "")
                        .selected_text(p.power.to_string())
                        .width(36.0)
                        .show_ui(ui, |ui| {
                            for power in info.min_power..=info.max_power {
                                if ui.selectable_label(power == p.power, power.to_string()).clicked()
                                    && power != p.power
                                {
                                    chosen = Some(keep_a(Formula::single(Phase::new(p.kind, power)), current));
                                }
                            }
                        })
                        .response
                        .labelled_by(label.id)
                })
                .response
                .on_disabled_hover_text(format!("{} comes in power {} only", info.name, info.min_power));
            }
        });
        // The coefficient a of the families that take one (a z² ± z^p).
        if let Some([re, im]) = current.a() {
            ui.horizontal(|ui| {
                let label = ui.label("a");
                let (mut r, mut i) = (re, im);
                let hover = "the coefficient a of a z^2 ± z^p + c (Kalles Fraktaler's FactorAR, FactorAI)";
                let a = ui.add(egui::DragValue::new(&mut r).speed(0.001).prefix("re ")).labelled_by(label.id);
                let b = ui.add(egui::DragValue::new(&mut i).speed(0.001).prefix("im ")).labelled_by(label.id);
                a.on_hover_text(hover);
                b.on_hover_text(hover);
                if (r, i) != (re, im) && r.is_finite() && i.is_finite() {
                    chosen = Some(current.with_a([r, i]));
                }
            });
        }
        let r = ui
            .horizontal(|ui| {
                let label = ui.label("formula");
                ui.text_edit_singleline(&mut self.text).labelled_by(label.id).on_hover_text(
                    "a family, NAME^POWER, or a hybrid: phases joined by `,` (burning-ship,mandelbrot^3)",
                )
            })
            .inner;
        // The text takes effect when the field is left (Enter or a click elsewhere).
        if r.lost_focus() {
            chosen = chosen.or(self.commit_text(current));
        }
        if let Some(e) = &self.error {
            ui.colored_label(ERROR_COLOUR, e);
        }
        if chosen.is_some() {
            self.error = None;
        }
        chosen
    }

    /// The formula the field's text says, when it is another than `current`; text the
    /// parser refuses keeps its error for the field and chooses nothing.
    fn commit_text(&mut self, current: Formula) -> Option<Formula> {
        match Formula::parse(&self.text, None) {
            Ok(f) => {
                self.error = None;
                let f = keep_a(f, current);
                (f != current).then_some(f)
            }
            Err(e) => {
                self.error = Some(e.to_string());
                None
            }
        }
    }

    /// The formula chosen was refused by the scene: says why under the field.
    pub(super) fn refused(&mut self, why: String) {
        self.error = Some(why);
    }
}

/// `formula` with the coefficient a of `current`, where both take one.
fn keep_a(formula: Formula, current: Formula) -> Formula {
    match current.a() {
        Some(a) => formula.with_a(a),
        None => formula,
    }
}

/// A family's hover text: Kalles Fraktaler's name and type, and the map at its smallest power.
fn hover(info: &KindInfo) -> String {
    format!("{} (Kalles Fraktaler type {}): {}", info.kf_name, info.kf_type, info.kind.definition(info.min_power))
}

/// The formula and its form as the window title and status bar name them:
/// `burning-ship^3 (Julia form)`.
pub(super) fn formula_title(formula: &Formula, julia: bool) -> String {
    if julia { format!("{formula} (Julia form)") } else { formula.to_string() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn titles_name_the_formula_and_its_form() {
        let f = Formula::parse("burning-ship^3", None).unwrap();
        assert_eq!(formula_title(&f, true), "burning-ship^3 (Julia form)");
        assert_eq!(formula_title(&f, false), "burning-ship^3");
        let hybrid = Formula::parse("burning-ship,mandelbrot^3", None).unwrap();
        assert_eq!(formula_title(&hybrid, false), "burning-ship,mandelbrot^3");
        assert!(hover(&KINDS[1]).starts_with("Burning Ship (Kalles Fraktaler type 1)"));
    }

    /// Text the parser refuses chooses nothing and says why; good text chooses its formula.
    #[test]
    fn typed_text_is_parsed_and_refusals_kept() {
        let current = Formula::default();
        let mut c = FormulaChooser { text: "burning-ship,mandelbrot^11".into(), ..Default::default() };
        assert_eq!(c.commit_text(current), None);
        assert!(c.error.as_deref().is_some_and(|e| e.contains("mandelbrot")), "{:?}", c.error);
        c.text = "no-such-family".into();
        assert_eq!(c.commit_text(current), None);
        assert!(c.error.as_deref().is_some_and(|e| e.contains("unknown formula")), "{:?}", c.error);
        c.text = " burning-ship , mandelbrot^3 ".into();
        let hybrid = c.commit_text(current).expect("a hybrid");
        assert_eq!(hybrid.to_string(), "burning-ship,mandelbrot^3");
        assert_eq!(c.error, None);
        c.text = "mandelbrot".into();
        assert_eq!(c.commit_text(current), None, "the formula shown chooses nothing");
    }
}
