//! The explorer's "Layers" panel: the scene's layers, each with a control for every key its
//! kind takes ([`LAYER_KINDS`]), and a menu that adds a layer.
//!
//! A key the scene leaves out shows the value validation uses for it ([`default_value`], the
//! one table of layer defaults) and is written into the layer only when the user edits it,
//! so a scene saved without edits keeps exactly the keys it had. The control is chosen by
//! the key's type ([`LayerRaw::fields_mut`]), not from lists of key names. Numbers are number
//! fields, not sliders: a scene's value shows as it is, however large (bench-e1086's density
//! is 5000), and drags scale with the value.

use std::collections::BTreeMap;

use eframe::egui;
use toml::Spanned;

use crate::coloring::{MASK_FEATHER, MaskQuantity, Transfer};
use crate::compose::BlendMode;
use crate::palette::{self, Palette};
use crate::scene::raw::{KeyValueMut, LayerRaw, MaskRaw, cli};
use crate::scene::{DefaultValue, LAYER_KINDS, default_value, kind_keys, layer_key};
use crate::source::SourceError;

/// Shows the layers, the controls of each and the add-a-layer menu. `overrides` are the
/// palette editor's palettes by layer index and `selected` the layer it edits; both follow a
/// removal. Returns true when the scene changed.
pub(super) fn show(
    ui: &mut egui::Ui,
    layers: &mut Vec<Spanned<LayerRaw>>,
    overrides: &mut BTreeMap<usize, Palette>,
    selected: &mut usize,
    error: Option<&SourceError>,
) -> bool {
    let mut remove = None;
    let mut changed = false;
    for k in 0..layers.len() {
        let l = layers[k].get_mut();
        ui.horizontal(|ui| {
            if ui.selectable_label(*selected == k, format!("{k}: {}", l.kind.get_ref())).clicked() {
                *selected = k;
            }
            if ui.small_button("x").on_hover_text("remove this layer").clicked() {
                remove = Some(k);
            }
        });
        changed |= layer_controls(ui, k, l, overrides, error);
    }
    if let Some(k) = remove
        && layers.len() > 1
    {
        layers.remove(k);
        *overrides = std::mem::take(overrides)
            .into_iter()
            .filter(|(i, _)| *i != k)
            .map(|(i, p)| (if i > k { i - 1 } else { i }, p))
            .collect();
        *selected = 0;
        changed = true;
    }
    ui.horizontal(|ui| {
        egui::ComboBox::new("add-layer", "add a layer").selected_text("kind…").show_ui(ui, |ui| {
            for (kind, _) in LAYER_KINDS {
                // A bitmap layer needs an image file, which this menu cannot choose.
                if kind == "bitmap" {
                    continue;
                }
                if ui.selectable_label(false, kind).clicked() {
                    let mut l = LayerRaw::of_kind(kind);
                    if !layers.is_empty() && kind != "interior" {
                        l.blend = Some(cli(BlendMode::Multiply));
                    }
                    layers.push(Spanned::new(0..0, l));
                    changed = true;
                }
            }
        });
    });
    changed
}

/// The controls of layer `k`: one per key its kind takes, in [`LAYER_KINDS`] order, then
/// its opacity (above the bottom layer). Returns true when the scene changed.
fn layer_controls(
    ui: &mut egui::Ui,
    k: usize,
    l: &mut LayerRaw,
    overrides: &mut BTreeMap<usize, Palette>,
    error: Option<&SourceError>,
) -> bool {
    // The scene's error, under the control of the key it is in.
    let note = |ui: &mut egui::Ui, key: &str| {
        if let Some(e) = error.filter(|e| e.key.as_ref().is_some_and(|at| at.starts_with(&layer_key(k, key)))) {
            ui.colored_label(egui::Color32::from_rgb(255, 90, 90), &e.message);
        }
    };
    // An unknown kind has no keys to show; validation's message names the kinds.
    let Some(keys) = kind_keys(l.kind.get_ref()) else { return false };
    // Read before the fields are borrowed for editing (a distance layer's defaults follow
    // its style).
    let defaults: Vec<Option<DefaultValue>> = keys.iter().map(|key| default_value(l, key)).collect();
    let opacity_default = default_value(l, "opacity").and_then(DefaultValue::number);
    let mut changed = false;
    let mut fields = l.fields_mut();
    for (&key, default) in keys.iter().zip(defaults) {
        let (Some((_, field)), Some(default)) = (fields.iter_mut().find(|(name, _)| *name == key), default) else {
            continue;
        };
        changed |= match field {
            KeyValueMut::Text(v) if key == "palette" => palette_control(ui, k, v, default, overrides),
            KeyValueMut::Text(v) => text_control(ui, key, v, default),
            KeyValueMut::Number(v) => number_control(ui, key, v, default),
            KeyValueMut::Integer(v) => integer_control(ui, key, v, default),
            KeyValueMut::Colors(v) => colors_control(ui, key, v, default),
            KeyValueMut::Point(v) => numbers_control(ui, key, v, default, default.point()),
            KeyValueMut::Triple(v) => numbers_control(ui, key, v, default, default.triple()),
            KeyValueMut::Transfer(v) => transfer_control(ui, k, key, v, default),
            // Every kind takes these; no kind lists them among its own keys.
            KeyValueMut::Blend(_) | KeyValueMut::Mask(_) => false,
        };
        note(ui, key);
    }
    if let Some((_, KeyValueMut::Mask(m))) = fields.iter_mut().find(|(name, _)| *name == "mask") {
        changed |= mask_control(ui, k, m);
    }
    note(ui, "mask");
    drop(fields);
    // How it combines with the layers below (the bottom layer has nothing below it).
    if k > 0 {
        let current = l.blend.as_ref().map_or(BlendMode::default(), |b| *b.get_ref());
        egui::ComboBox::new(("blend", k), "blend").selected_text(current.name()).show_ui(ui, |ui| {
            for mode in BlendMode::ALL {
                if ui.selectable_label(mode == current, mode.name()).clicked() && mode != current {
                    l.blend = Some(cli(mode));
                    changed = true;
                }
            }
        });
    }
    if k > 0
        && let Some(default) = opacity_default
    {
        let mut opacity = l.opacity.as_ref().map_or(default, |o| *o.get_ref());
        if ui.add(egui::Slider::new(&mut opacity, 0.0..=1.0).text("opacity")).changed() {
            l.opacity = Some(cli(opacity));
            changed = true;
        }
    }
    note(ui, "opacity");
    changed
}

/// The layer's mask: which quantity it reads (or none), then its range, each end open until
/// ticked, its feather and whether it is inverted. A value typed that validation refuses
/// (an empty range) is reported as any other invalid edit is.
fn mask_control(ui: &mut egui::Ui, k: usize, m: &mut Option<Spanned<MaskRaw>>) -> bool {
    let current = m.as_ref().map(|m| m.get_ref().quantity.get_ref().clone());
    let mut changed = false;
    egui::ComboBox::new(("mask", k), "mask").selected_text(current.as_deref().unwrap_or("none")).show_ui(ui, |ui| {
        if ui.selectable_label(current.is_none(), "none").clicked() && current.is_some() {
            *m = None;
            changed = true;
        }
        for (_, name) in MaskQuantity::ALL {
            if ui.selectable_label(current.as_deref() == Some(name), name).clicked() && current.as_deref() != Some(name)
            {
                match m {
                    Some(raw) => raw.get_mut().quantity = cli(name.to_string()),
                    None => *m = Some(cli(MaskRaw::new(name))),
                }
                changed = true;
            }
        }
    });
    let Some(raw) = m.as_mut().map(Spanned::get_mut) else { return changed };
    changed |= bound_control(ui, "mask above", &mut raw.above);
    changed |= bound_control(ui, "mask below", &mut raw.below);
    let mut feather = raw.feather.as_ref().map_or(MASK_FEATHER, |f| *f.get_ref());
    let speed = (feather * 0.01).max(1e-3);
    if number_field(ui, "mask feather", &mut feather, speed) && feather.is_finite() && feather >= 0.0 {
        raw.feather = Some(cli(feather));
        changed = true;
    }
    let mut invert = raw.invert.as_ref().is_some_and(|v| *v.get_ref());
    if ui.checkbox(&mut invert, "mask invert").changed() {
        raw.invert = Some(cli(invert));
        changed = true;
    }
    changed
}

/// One end of a mask's range: open (unticked) or a number.
fn bound_control(ui: &mut egui::Ui, key: &str, v: &mut Option<Spanned<f64>>) -> bool {
    ui.horizontal(|ui| {
        let mut on = v.is_some();
        let mut changed = false;
        if ui.checkbox(&mut on, "").on_hover_text("tick to close this end of the range").changed() {
            *v = on.then(|| cli(0.0));
            changed = true;
        }
        match v {
            Some(bound) => {
                let mut x = *bound.get_ref();
                let speed = (x.abs() * 0.01).max(1e-3);
                let r = ui.add(egui::DragValue::new(&mut x).speed(speed).max_decimals(6));
                let label = ui.label(key);
                if r.labelled_by(label.id).changed() && x.is_finite() {
                    *v = Some(cli(x));
                    changed = true;
                }
            }
            None => {
                ui.weak("open");
                ui.label(key);
            }
        }
        changed
    })
    .inner
}

/// A key left out whose absence no value stands for: what leaving it out means, beside its
/// name (set in the scene file; or, for a style's key, by choosing that style).
fn unset_row(ui: &mut egui::Ui, key: &str, default: DefaultValue) -> bool {
    let note = if let DefaultValue::Unset(note) = default { note } else { "" };
    ui.horizontal(|ui| {
        ui.weak(note);
        ui.label(key);
    });
    false
}

fn number_control(ui: &mut egui::Ui, key: &str, v: &mut Option<Spanned<f64>>, default: DefaultValue) -> bool {
    let Some(mut x) = v.as_ref().map(|s| *s.get_ref()).or(default.number()) else {
        return unset_row(ui, key, default);
    };
    let speed = (x.abs() * 0.01).max(1e-3);
    let edited = number_field(ui, key, &mut x, speed) && x.is_finite() && (key != "density" || x > 0.0);
    if edited {
        *v = Some(cli(x));
    }
    edited
}

fn integer_control(ui: &mut egui::Ui, key: &str, v: &mut Option<Spanned<i64>>, default: DefaultValue) -> bool {
    let Some(mut x) = v.as_ref().map(|s| *s.get_ref()).or(default.integer()) else {
        return unset_row(ui, key, default);
    };
    let edited = number_field(ui, key, &mut x, 0.2);
    if edited {
        *v = Some(cli(x));
    }
    edited
}

/// A number field labelled `key`; true when the user changed the value.
fn number_field<N: egui::emath::Numeric>(ui: &mut egui::Ui, key: &str, x: &mut N, speed: f64) -> bool {
    ui.horizontal(|ui| {
        let r = ui.add(egui::DragValue::new(x).speed(speed).max_decimals(6));
        let label = ui.label(key);
        r.labelled_by(label.id).changed()
    })
    .inner
}

/// Two or three numbers in a row (a centre, the IFS fold offset).
fn numbers_control<const N: usize>(
    ui: &mut egui::Ui,
    key: &str,
    v: &mut Option<Spanned<[f64; N]>>,
    default: DefaultValue,
    shown: Option<[f64; N]>,
) -> bool {
    let Some(mut xs) = v.as_ref().map(|s| *s.get_ref()).or(shown) else {
        return unset_row(ui, key, default);
    };
    let edited = ui
        .horizontal(|ui| {
            let fields: Vec<egui::Response> = xs
                .iter_mut()
                .map(|x| {
                    let speed = (x.abs() * 0.01).max(1e-3);
                    ui.add(egui::DragValue::new(x).speed(speed).max_decimals(6))
                })
                .collect();
            let label = ui.label(key);
            // Every field is labelled, whichever changed.
            let mut edited = false;
            for r in fields {
                edited |= r.labelled_by(label.id).changed();
            }
            edited
        })
        .inner;
    let edited = edited && xs.iter().all(|x| x.is_finite());
    if edited {
        *v = Some(cli(xs));
    }
    edited
}

/// Words (style, shape, colours as "#rrggbb", paths) are edited as text and checked by the
/// scene's validation: the text is kept as typed, and the view renders once editing ends.
fn text_control(ui: &mut egui::Ui, key: &str, v: &mut Option<Spanned<String>>, default: DefaultValue) -> bool {
    let mut text = v.as_ref().map_or_else(|| default.text().unwrap_or_default().to_string(), |s| s.get_ref().clone());
    let hint = if let DefaultValue::Unset(note) = default { note } else { "" };
    let (edited, done) = ui
        .horizontal(|ui| {
            let r = ui.add(egui::TextEdit::singleline(&mut text).hint_text(hint).desired_width(90.0));
            let label = ui.label(key);
            let r = r.labelled_by(label.id);
            (r.changed(), r.lost_focus())
        })
        .inner;
    if edited {
        *v = Some(cli(text));
    }
    done
}

/// The binary decomposition's two colours, as text like [`text_control`].
fn colors_control(ui: &mut egui::Ui, key: &str, v: &mut Option<Spanned<[String; 2]>>, default: DefaultValue) -> bool {
    let Some(mut pair) = v.as_ref().map(|s| s.get_ref().clone()).or(default.colors().map(|c| c.map(str::to_string)))
    else {
        return unset_row(ui, key, default);
    };
    let (edited, done) = ui
        .horizontal(|ui| {
            let [a, b] = &mut pair;
            let a = ui.add(egui::TextEdit::singleline(a).desired_width(60.0));
            let b = ui.add(egui::TextEdit::singleline(b).desired_width(60.0));
            let label = ui.label(key);
            let (a, b) = (a.labelled_by(label.id), b.labelled_by(label.id));
            (a.changed() || b.changed(), a.lost_focus() || b.lost_focus())
        })
        .inner;
    if edited {
        *v = Some(cli(pair));
    }
    done
}

/// The built-in palettes; the palette editor's copy, when layer `k` has one, is shown as
/// edited until another palette is chosen.
fn palette_control(
    ui: &mut egui::Ui,
    k: usize,
    v: &mut Option<Spanned<String>>,
    default: DefaultValue,
    overrides: &mut BTreeMap<usize, Palette>,
) -> bool {
    let current = v.as_ref().map(|p| p.get_ref().clone()).or(default.text().map(str::to_string));
    let shown = match (overrides.get(&k), &current, default) {
        (Some(edited), _, _) => format!("{} (edited)", edited.name),
        (None, Some(name), _) => name.clone(),
        (None, None, DefaultValue::Unset(note)) => note.to_string(),
        (None, None, _) => String::new(),
    };
    let mut changed = false;
    egui::ComboBox::new(("palette", k), "palette").selected_text(shown).show_ui(ui, |ui| {
        for name in palette::builtin_names() {
            if ui.selectable_label(current.as_deref() == Some(name), name).clicked() {
                *v = Some(cli(name.to_string()));
                overrides.remove(&k);
                changed = true;
            }
        }
    });
    changed
}

fn transfer_control(
    ui: &mut egui::Ui,
    k: usize,
    key: &str,
    v: &mut Option<Spanned<Transfer>>,
    default: DefaultValue,
) -> bool {
    let Some(mut t) = v.as_ref().map(|t| *t.get_ref()).or(default.transfer()) else {
        return unset_row(ui, key, default);
    };
    let name = |t: Transfer| Transfer::ALL.iter().find(|(x, _)| *x == t).map_or("", |(_, n)| *n);
    let mut changed = false;
    egui::ComboBox::new((key, k), key).selected_text(name(t)).show_ui(ui, |ui| {
        for (x, n) in Transfer::ALL {
            if ui.selectable_value(&mut t, x, n).clicked() {
                *v = Some(cli(t));
                changed = true;
            }
        }
    });
    changed
}
