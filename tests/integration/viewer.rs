//! The viewer, driven through egui_kittest on a software wgpu adapter (lavapipe): the
//! interactions (zoom about the cursor, pan, history, recolouring instead of rendering,
//! Julia pick), snapshot images of the main states, and a real window under Xvfb.
//!
//! The render worker runs inline in these tests, so each test knows exactly which renders
//! happened. Snapshots: `UPDATE_SNAPSHOTS=1 cargo test viewer` rewrites
//! `tests/snapshots/*.png`; the tolerance is in `tests/snapshots/tolerance.toml`.

use std::path::{Path, PathBuf};

use deepfield::viewer::{ViewMode, ViewerApp, ViewerOptions};
use eframe::egui::{self, Event, Modifiers, MouseWheelUnit, PointerButton, Pos2, Vec2};
use egui_kittest::kittest::{NodeT, Queryable};
use egui_kittest::{Harness, SnapshotOptions};

use super::util::scratch;

fn scene_file(dir: &Path, text: &str) -> PathBuf {
    let p = dir.join("scene.toml");
    std::fs::write(&p, text).unwrap();
    p
}

const SCENE: &str = "version = 1\n[view]\ncenter = [\"-0.74515\", \"0.11255\"]\nzoom = \"900\"\n[iteration]\nmax = 400\n[[layer]]\nkind = \"smooth\"\npalette = \"classic\"\ntransfer = \"log\"\ndensity = 0.5\n[[layer]]\nkind = \"distance\"\nk = 0.5\nblend = \"multiply\"\nopacity = 0.6\n";

fn harness(dir: &Path, text: &str) -> Harness<'static, ViewerApp> {
    let path = scene_file(dir, text);
    let mut h =
        Harness::builder().with_size(Vec2::new(900.0, 560.0)).with_max_steps(200).wgpu().build_eframe(move |cc| {
            ViewerApp::new(
                cc,
                ViewerOptions { scene: Some(path.clone()), screenshot: None, inline: true, references: None },
            )
            .expect("viewer starts")
        });
    settle(&mut h);
    h
}

/// Steps until the render is complete.
fn settle(h: &mut Harness<'static, ViewerApp>) {
    for _ in 0..50 {
        h.run_steps(2);
        if h.state().idle() {
            h.run_steps(1);
            return;
        }
    }
    panic!("the viewer never finished rendering");
}

fn wheel(h: &Harness<'static, ViewerApp>, at: Pos2, dy: f32) {
    h.hover_at(at);
    h.event(Event::MouseWheel {
        unit: MouseWheelUnit::Point,
        delta: Vec2::new(0.0, dy),
        phase: egui::TouchPhase::Move,
        source: egui::MouseWheelSource::Wheel,
        modifiers: Modifiers::NONE,
    });
}

/// Physical pixels from the image centre, as the viewer's navigation counts them.
fn px(h: &Harness<'static, ViewerApp>, p: Pos2) -> [f64; 2] {
    let r = h.state().image_rect();
    [(p.x - r.center().x) as f64, (p.y - r.center().y) as f64]
}

#[test]
fn wheel_zoom_keeps_the_point_under_the_cursor_fixed() {
    let dir = scratch("viewer-zoom");
    let mut h = harness(&dir, SCENE);
    let r = h.state().image_rect();
    let at = r.center() + Vec2::new(140.0, -70.0);
    let height = h.state().image_size_px()[1] as f64;
    let before = h.state().nav().point_at(px(&h, at), height);
    let zoom0 = h.state().nav().log10_zoom;
    wheel(&h, at, 240.0);
    settle(&mut h);
    let nav = h.state().nav().clone();
    assert!(nav.log10_zoom > zoom0 + 0.3, "zoomed in: {} -> {}", zoom0, nav.log10_zoom);
    let after = nav.point_at(px(&h, at), height);
    let s = nav.spacing(height);
    assert!((before[0] - after[0]).abs() < s && (before[1] - after[1]).abs() < s, "{before:?} -> {after:?}");
}

#[test]
fn drag_pans_and_history_goes_back_and_forward() {
    let dir = scratch("viewer-pan");
    let mut h = harness(&dir, SCENE);
    let start = h.state().nav().clone();
    let height = h.state().image_size_px()[1] as f64;
    let r = h.state().image_rect();
    let (a, b) = (r.center(), r.center() + Vec2::new(-100.0, 40.0));
    h.drag_at(a);
    h.run_steps(1);
    h.hover_at(b);
    h.run_steps(1);
    h.event(Event::PointerButton {
        pos: b,
        button: PointerButton::Primary,
        pressed: false,
        modifiers: Modifiers::NONE,
    });
    settle(&mut h);
    let moved = h.state().nav().clone();
    // Dragging left by 100 px moves the view right by 100 pixel spacings (y: up is +).
    let d = start.offset_px_of(&moved, height);
    assert!((d[0] - 100.0).abs() < 1.0 && (d[1] - 40.0).abs() < 1.0, "{d:?}");
    h.key_press(egui::Key::Backspace);
    settle(&mut h);
    assert_eq!(h.state().nav(), &start, "Backspace goes back");
    h.get_by_label("Forward >").click();
    settle(&mut h);
    assert_eq!(h.state().nav(), &moved, "Forward returns");
    h.key_press(egui::Key::Home);
    settle(&mut h);
    assert!((h.state().nav().log10_zoom - 1.6f64.log10()).abs() < 1e-12, "Home shows the whole set");
}

#[test]
fn palette_change_recolours_without_rendering() {
    let dir = scratch("viewer-recolour");
    let mut h = harness(&dir, SCENE);
    let before = h.state().counters();
    assert!(before.renders >= 1);
    h.state_mut().set_palette("fire");
    settle(&mut h);
    let after = h.state().counters();
    assert_eq!(after.renders, before.renders, "a palette change must not render");
    assert_eq!(after.recolours, before.recolours + 1);
    assert_eq!(h.state().layer_palette(0).as_deref(), Some("fire"));
    // A change of view does render.
    h.key_press(egui::Key::Plus);
    settle(&mut h);
    assert!(h.state().counters().renders > after.renders);
}

#[test]
fn ctrl_click_opens_the_julia_set_of_the_point() {
    let dir = scratch("viewer-julia");
    let mut h = harness(&dir, SCENE);
    let r = h.state().image_rect();
    let at = r.center() + Vec2::new(-60.0, 30.0);
    let height = h.state().image_size_px()[1] as f64;
    let want = h.state().nav().point_at(px(&h, at), height);
    h.hover_at(at);
    h.run_steps(2);
    assert!(h.state().counters().julia_previews >= 1, "hovering previews the Julia set");
    ctrl_click(&mut h, at);
    settle(&mut h);
    let c = h.state().julia_c().expect("a Julia scene now");
    let got = [c[0].parse::<f64>().unwrap(), c[1].parse::<f64>().unwrap()];
    let s = 4.0 / height / 900.0;
    assert!((got[0] - want[0]).abs() < s && (got[1] - want[1]).abs() < s, "{got:?} vs {want:?}");
}

/// A click with Ctrl held (pressed a frame before, released a frame after).
fn ctrl_click(h: &mut Harness<'static, ViewerApp>, at: Pos2) {
    h.event(Event::ModifiersChanged(Modifiers::CTRL));
    h.run_steps(1);
    h.event(Event::PointerButton {
        pos: at,
        button: PointerButton::Primary,
        pressed: true,
        modifiers: Modifiers::CTRL,
    });
    h.run_steps(1);
    h.event(Event::PointerButton {
        pos: at,
        button: PointerButton::Primary,
        pressed: false,
        modifiers: Modifiers::CTRL,
    });
    h.run_steps(1);
    h.event(Event::ModifiersChanged(Modifiers::NONE));
}

fn tolerance() -> SnapshotOptions {
    let text =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots/tolerance.toml")).unwrap();
    let t: toml::Table = toml::from_str(&text).unwrap();
    SnapshotOptions::new()
        .threshold(t["threshold"].as_float().unwrap() as f32)
        .max_failed_pixels(t["failed_pixels"].as_integer().unwrap() as usize)
}

#[test]
fn snapshots_of_the_main_states() {
    let dir = scratch("viewer-snapshots");
    let mut h = harness(&dir, SCENE);
    h.snapshot_options("viewer-mandelbrot", &tolerance());
    let r = h.state().image_rect();
    let at = r.center() + Vec2::new(-60.0, 30.0);
    h.hover_at(at);
    h.run_steps(2);
    ctrl_click(&mut h, at);
    settle(&mut h);
    h.snapshot_options("viewer-julia", &tolerance());
}

/// The GPU modes: side by side through the paint callback, and the per-pixel difference,
/// whose N agreement on the whole set is the f32 shader's (>= 99%).
#[test]
fn gpu_side_by_side_and_difference() {
    let dir = scratch("viewer-gpu");
    let full =
        "version = 1\n[iteration]\nmax = 300\n[[layer]]\nkind = \"smooth\"\npalette = \"classic\"\ndensity = 0.1\n";
    let mut h = harness(&dir, full);
    h.state_mut().set_mode(ViewMode::SideBySide);
    settle(&mut h);
    h.snapshot_options("viewer-side-by-side", &tolerance());
    h.state_mut().set_mode(ViewMode::Difference);
    let mut mismatch = None;
    for _ in 0..200 {
        h.run_steps(1);
        mismatch = h.state().difference_mismatch();
        if mismatch.is_some() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(50));
    }
    let m = mismatch.expect("the GPU comparison finished");
    assert!(m < 0.01, "N differs on {:.3}% of samples", m * 100.0);
    h.run_steps(2);
    h.snapshot_options("viewer-difference", &tolerance());
}

/// A real window under Xvfb: start, render, screenshot, exit 0.
#[test]
fn real_window_under_xvfb() {
    if std::env::var_os("DEEPFIELD_NO_DISPLAY").is_some() {
        return;
    }
    let dir = scratch("viewer-xvfb");
    let scene = scene_file(&dir, SCENE);
    let shot = dir.join("shot.png");
    let out = std::process::Command::new("xvfb-run")
        .args(["-a", "-s", "-screen 0 1024x768x24"])
        .arg(env!("CARGO_BIN_EXE_deepfield"))
        .args(["view", scene.to_str().unwrap(), "--screenshot", shot.to_str().unwrap(), "--size", "800x500"])
        .env("XDG_CONFIG_HOME", &dir)
        .env("XDG_DATA_HOME", &dir)
        .output()
        .expect("xvfb-run is needed (apt-get install xvfb xauth); DEEPFIELD_NO_DISPLAY=1 skips this test");
    assert!(out.status.success(), "exit {:?}: {}", out.status.code(), String::from_utf8_lossy(&out.stderr));
    let img = image::open(&shot).expect("a screenshot");
    assert!(img.width() >= 800 && img.height() >= 500, "{}x{}", img.width(), img.height());
}

/// A bad scene is refused before any window opens: exit 2, file:line:column.
#[test]
fn bad_scenes_are_refused_before_a_window_opens() {
    let dir = scratch("viewer-bad");
    let bad = scene_file(&dir, "version = 1\n[view]\nzoom = \"x\"\n");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_deepfield"))
        .args(["view", bad.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(err.contains("scene.toml:3:8"), "{err}");
}

/// What a dropped file does: a palette file goes to the selected layer and only recolours; a
/// scene (here a PNG written by deepfield) opens it, with the view it holds.
#[test]
fn dropped_palettes_recolour_and_dropped_scenes_open() {
    let dir = scratch("viewer-drop");
    let mut h = harness(&dir, SCENE);
    let before = h.state().counters();
    let ggr = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/palettes/sample.ggr");
    h.state_mut().open_path(&ggr).expect("palette opens");
    settle(&mut h);
    let after = h.state().counters();
    assert_eq!((after.renders, after.recolours), (before.renders, before.recolours + 1));
    assert_eq!(h.state().layer_palette(0).as_deref(), Some("sample"));

    let scene = scene_file(
        &dir,
        "version = 1\n[view]\ncenter = [\"-1.25\", \"0.02\"]\nzoom = \"40\"\nwidth = 64\nheight = 48\n",
    );
    let png = dir.join("dropped.png");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_deepfield"))
        .args(["render", scene.to_str().unwrap(), "-o", png.to_str().unwrap(), "-q"])
        .output()
        .unwrap();
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    h.state_mut().open_path(&png).expect("scene opens");
    settle(&mut h);
    assert_eq!(h.state().nav().center, ["-1.25".to_string(), "0.02".to_string()]);
    assert!((h.state().nav().log10_zoom - 40f64.log10()).abs() < 1e-12);
    assert!(h.state().counters().renders > after.renders);
}

/// A scene shipped in `scenes/`, with `edit` applied to its text.
fn shipped(name: &str, edit: impl Fn(String) -> String) -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name);
    edit(std::fs::read_to_string(path).unwrap())
}

/// The viewer's image area against `deepfield render` of the same view at the same size:
/// the texture is drawn 1:1, so pixels agree up to the texture's sRGB round trip.
fn image_matches_render(name: &str, text: &str) {
    let dir = scratch(&format!("viewer-deep-{name}"));
    let mut h = harness(&dir, text);
    let shot = h.render().expect("a frame");
    let rect = h.state().image_rect();
    let [w, hgt] = h.state().image_size_px();
    // The same view, rendered by the command line at the image area's size.
    let scene = scene_file(&dir, text);
    let out = dir.join("render.png");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_deepfield"))
        .args(["render", scene.to_str().unwrap(), "--size", &format!("{w}x{hgt}"), "-o", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let want = image::open(&out).unwrap().to_rgb8();
    let (x0, y0) = (rect.min.x.round() as u32, rect.min.y.round() as u32);
    let (mut far, mut total, mut spread) = (0usize, 0usize, [255u8, 0u8]);
    for y in 0..hgt.min(want.height()) {
        for x in 0..w.min(want.width()) {
            let (Some(a), b) = (shot.get_pixel_checked(x0 + x, y0 + y), want.get_pixel(x, y)) else { continue };
            let d = (0..3).map(|c| a[c].abs_diff(b[c])).max().unwrap_or(0);
            far += (d > 12) as usize;
            total += 1;
            spread = [spread[0].min(a[1]), spread[1].max(a[1])];
        }
    }
    assert!(total > 10_000, "{name}: compared {total} pixels");
    // Not the empty background: the image has structure.
    assert!(spread[1] - spread[0] > 64, "{name}: green only spans {spread:?}");
    assert!((far as f64) < 0.01 * total as f64, "{name}: {far} of {total} pixels differ by more than 12 levels");
}

/// Deep views show their image: at 1e50 (f64 deltas) and at 1e321 (FloatExp deltas, where
/// an f64 pixel spacing is zero and once left the image area empty).
#[test]
fn deep_views_show_the_image_render_draws() {
    let e50 = shipped("floral-fantasy.toml", |t| t.replace("zoom = \"1.55413511378E85\"", "zoom = \"1e50\""));
    assert!(e50.contains("zoom = \"1e50\""));
    image_matches_render("e50", &e50);
    image_matches_render("e321", &shipped("liiiines.toml", |t| t));
}

/// Newton zooming: N with the pointer near the airplane goes to its nucleus (period 3,
/// -1.7548776662466927..., published), framed at its size; Back returns.
#[test]
fn newton_zoom_goes_to_the_minibrot_under_the_pointer() {
    let dir = scratch("viewer-newton");
    let scene = "version = 1\n[view]\ncenter = [\"-1.7\", \"0\"]\nzoom = \"10\"\n[iteration]\nmax = 300\n";
    let mut h = harness(&dir, scene);
    let start = h.state().nav().clone();
    let r = h.state().image_rect();
    let [_, height] = h.state().image_size_px();
    // -1.755 is 0.055 left of the centre: 0.055 / (0.4 / height) pixels.
    let at = r.center() + Vec2::new(-(0.055 / (0.4 / height as f64)) as f32, 0.0);
    h.hover_at(at);
    h.run_steps(1);
    h.key_press(egui::Key::N);
    for _ in 0..200 {
        h.run_steps(1);
        if !h.state().newton_pending() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    settle(&mut h);
    let nav = h.state().nav().clone();
    assert!(h.state().newton_note().is_some_and(|n| n.contains("period 3")), "{:?}", h.state().newton_note());
    assert!(nav.center[0].starts_with("-1.754877666246692760049508896358"), "{:?}", nav.center);
    assert!((nav.log10_zoom - 48f64.log10()).abs() < 0.15, "zoom 1e{}", nav.log10_zoom);
    h.key_press(egui::Key::Backspace);
    settle(&mut h);
    assert_eq!(h.state().nav(), &start);
}

/// Layer numbers show the scene's own values, however large (a density of 5000 once showed
/// as 10, the end of a slider's range), and words show as text.
#[test]
fn layer_controls_show_the_scene_values() {
    let dir = scratch("viewer-layer-values");
    let scene = "version = 1\n[iteration]\nmax = 200\n[[layer]]\nkind = \"smooth\"\npalette = \"classic\"\ndensity = 5000\n[[layer]]\nkind = \"distance\"\nstyle = \"log\"\ndensity = 0.125\nblend = \"multiply\"\n";
    let h = harness(&dir, scene);
    let values: Vec<f64> = h.get_all_by_label("density").filter_map(|n| n.accesskit_node().numeric_value()).collect();
    // The layers' two, then the palette editor's own density.
    assert_eq!(values[..2], [5000.0, 0.125]);
    assert_eq!(h.get_by_label("style").value().as_deref(), Some("log"));
}

/// Every key a layer's kind takes has a control, a key the scene leaves out showing the value
/// validation uses (a smooth layer's density is 0.05) without being written into the scene,
/// and a value the scene sets shows as it is (5000, not clamped to a slider's range).
#[test]
fn layer_controls_show_defaults_for_keys_left_out() {
    let dir = scratch("viewer-layer-defaults");
    let scene = "version = 1\n[iteration]\nmax = 200\n[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"smooth\"\ndensity = 5000\nblend = \"multiply\"\n";
    let mut h = harness(&dir, scene);
    let values: Vec<f64> = h.get_all_by_label("density").filter_map(|n| n.accesskit_node().numeric_value()).collect();
    // The layers' two, then the palette editor's own density.
    assert_eq!(values[..2], [0.05, 5000.0]);
    let offsets: Vec<f64> = h.get_all_by_label("offset").filter_map(|n| n.accesskit_node().numeric_value()).collect();
    assert_eq!(offsets[..2], [0.0, 0.0], "keys no layer sets have controls too");
    assert_eq!(h.get_all_by_label("interior").filter_map(|n| n.value()).collect::<Vec<_>>(), ["#000000"; 2]);
    let layers = &h.state().scene_file().layers;
    let bottom = layers[0].get_ref();
    assert!(bottom.density.is_none() && bottom.offset.is_none() && bottom.interior.is_none(), "showing writes nothing");
    assert_eq!(layers[1].get_ref().density.as_ref().map(|d| *d.get_ref()), Some(5000.0));
    // An edit writes the key, and only that one.
    let before = h.state().counters();
    h.get_all_by_label("density")
        .find(|n| n.accesskit_node().numeric_value() == Some(0.05))
        .unwrap()
        .set_value_accesskit(0.2);
    settle(&mut h);
    let bottom = h.state().scene_file().layers[0].get_ref().clone();
    assert_eq!(bottom.density.as_ref().map(|d| *d.get_ref()), Some(0.2));
    assert!(bottom.offset.is_none() && bottom.interior.is_none() && bottom.palette.is_none());
    assert_eq!(h.state().counters().renders, before.renders, "a density edit recolours without rendering");
    // The upper layer's blend mode has a menu (the bottom layer has nothing below it).
    assert_eq!(h.get_all_by_label("blend").count(), 1);
    h.get_by_label("blend").click();
    h.run_steps(2);
    h.get_by_label("screen").click();
    settle(&mut h);
    let top = h.state().scene_file().layers[1].get_ref().clone();
    assert_eq!(top.blend.as_ref().map(|b| *b.get_ref()), Some(deepfield::compose::BlendMode::Screen));
}

/// A layer's mask has controls: the quantity's menu, each end of the range (open until
/// ticked), the feather and the inversion, showing the scene's values; an edit writes the
/// key, and the menu adds a mask to a layer without one.
#[test]
fn layer_masks_have_controls() {
    let dir = scratch("viewer-layer-mask");
    let scene = "version = 1\n[iteration]\nmax = 200\n[[layer]]\nkind = \"smooth\"\n[[layer]]\nkind = \"slope\"\nblend = \"multiply\"\n[layer.mask]\nquantity = \"distance\"\nbelow = 8.0\nfeather = 3.0\n";
    let mut h = harness(&dir, scene);
    let value = |h: &Harness<'static, ViewerApp>, label: &str| {
        h.get_all_by_label(label).filter_map(|n| n.accesskit_node().numeric_value()).collect::<Vec<_>>()
    };
    assert_eq!(value(&h, "mask below"), [8.0]);
    assert_eq!(value(&h, "mask feather"), [3.0]);
    assert!(value(&h, "mask above").is_empty(), "an end the scene leaves open shows as open");
    assert_eq!(h.get_all_by_label("mask").count(), 2, "one menu per layer");
    h.get_all_by_label("mask feather").next().unwrap().set_value_accesskit(0.5);
    settle(&mut h);
    let mask = |h: &Harness<'static, ViewerApp>, k: usize| h.state().scene_file().layers[k].get_ref().mask.clone();
    let top = mask(&h, 1).expect("kept").into_inner();
    assert_eq!(top.feather.map(|f| f.into_inner()), Some(0.5));
    assert_eq!(top.below.map(|f| f.into_inner()), Some(8.0));
    assert!(top.above.is_none() && top.invert.is_none(), "an edit writes only its key");
    // The bottom layer has none; its menu adds one.
    assert!(mask(&h, 0).is_none());
    h.get_all_by_label("mask").next().unwrap().click();
    h.run_steps(2);
    h.get_by_label("phase").click();
    settle(&mut h);
    assert_eq!(mask(&h, 0).map(|m| m.into_inner().quantity.into_inner()).as_deref(), Some("phase"));
}

/// `view --reference`: a deep view's engine is built from the file's orbits (none computed)
/// and shows the image it shows without the file; a file that does not serve the scene is
/// refused before any window opens, with the reason, and so is `--reference` without a
/// scene.
#[test]
fn a_reference_file_serves_the_viewer() {
    let dir = scratch("viewer-reference");
    let text = shipped("liiiines.toml", |t| t);
    let scene = scene_file(&dir, &text);
    let bin = env!("CARGO_BIN_EXE_deepfield");
    // Made for a finer raster than the viewer's, so its precision is enough.
    let file = dir.join("liiiines.dfr");
    let o = std::process::Command::new(bin)
        .args(["reference", scene.to_str().unwrap(), "--size", "3200x2400", "-o", file.to_str().unwrap()])
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let saved = deepfield::orbit::saved::SavedReferences::decode(&std::fs::read(&file).unwrap()).expect("decodes");
    let path = scene.clone();
    let mut with =
        Harness::builder().with_size(Vec2::new(900.0, 560.0)).with_max_steps(200).wgpu().build_eframe(move |cc| {
            let options = ViewerOptions {
                scene: Some(path.clone()),
                screenshot: None,
                inline: true,
                references: Some(std::sync::Arc::new(saved.clone())),
            };
            ViewerApp::new(cc, options).expect("viewer starts")
        });
    settle(&mut with);
    assert_eq!(with.state().counters().references_from_file, 1);
    let mut without = harness(&dir, &text);
    assert_eq!(without.state().counters().references_from_file, 0);
    let (a, b) = (with.render().expect("a frame"), without.render().expect("a frame"));
    let far = a.pixels().zip(b.pixels()).filter(|(p, q)| (0..3).any(|c| p[c].abs_diff(q[c]) > 12)).count();
    assert!(far * 1000 < (a.width() * a.height()) as usize, "{far} pixels differ");
    // Refusals, exit 2 with the reason: another iteration limit, no scene.
    let other = scene_file(&dir, &text.replace("max = 12500", "max = 12000"));
    assert!(text.contains("max = 12500"));
    let o = std::process::Command::new(bin)
        .args(["view", other.to_str().unwrap(), "--reference", file.to_str().unwrap()])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(err.contains("does not serve") && err.contains("max_iter"), "{err}");
    let o = std::process::Command::new(bin).args(["view", "--reference", file.to_str().unwrap()]).output().unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", String::from_utf8_lossy(&o.stderr));
}

/// A Julia parameter typed that is not a number is said next to its field, by the typed
/// scene's key path, and nothing renders: the image keeps the last valid scene. Once the
/// text is a number again the error goes and the new parameter renders.
#[test]
fn a_bad_value_typed_is_shown_by_its_field_and_the_view_keeps_the_last_good_one() {
    let dir = scratch("viewer-bad-typed");
    let scene = "version = 1\n[formula]\nkind = \"julia\"\nc = [\"-0.8\", \"0.156\"]\n[iteration]\nmax = 200\n";
    let mut h = harness(&dir, scene);
    let before = h.state().counters();
    let field = h.get_by_label("c re");
    field.focus();
    h.run_steps(1);
    h.get_by_label("c re").type_text("x");
    settle(&mut h);
    let typed = h.state().julia_c().expect("a Julia scene");
    assert!(typed[0].contains('x'), "the field keeps what was typed: {typed:?}");
    // The status bar names the scene and the key ("scene.toml: formula.c: ..."); the line by
    // the field is the message.
    let by_field = |h: &Harness<'static, ViewerApp>| {
        h.query_all_by_label_contains("Julia parameter c")
            .filter(|n| n.value().is_some_and(|l| l.starts_with("Julia parameter c")))
            .count()
    };
    assert_eq!(by_field(&h), 1, "the error shows by the field");
    assert_eq!(h.state().counters().renders, before.renders, "nothing renders from a bad value");
    // The number it was: the error goes, and the picture is the one shown (no render).
    h.key_press(egui::Key::Backspace);
    settle(&mut h);
    assert_eq!(h.state().julia_c().map(|c| c[0].clone()).as_deref(), Some("-0.8"));
    assert!(h.query_by_label_contains("Julia parameter c").is_none(), "the error is gone");
    assert_eq!(h.state().counters().renders, before.renders, "the same scene renders nothing");
    // Another number renders.
    h.get_by_label("c re").type_text("5");
    settle(&mut h);
    assert_eq!(h.state().julia_c().map(|c| c[0].clone()).as_deref(), Some("-0.85"));
    assert!(h.state().counters().renders > before.renders);
}

/// A layer value typed that the scene refuses is said under that key's control, and
/// nothing renders or recolours until it is valid.
#[test]
fn a_bad_layer_value_is_shown_under_its_control() {
    let dir = scratch("viewer-bad-layer");
    let scene = "version = 1\n[iteration]\nmax = 200\n[[layer]]\nkind = \"smooth\"\n";
    let mut h = harness(&dir, scene);
    let before = h.state().counters();
    h.get_by_label("interior").focus();
    h.run_steps(1);
    h.get_by_label("interior").type_text("x");
    // Text takes effect when the field is left.
    h.key_press(egui::Key::Enter);
    settle(&mut h);
    let interior = h.state().scene_file().layers[0].get_ref().interior.clone().map(|c| c.into_inner());
    assert_eq!(interior.as_deref(), Some("#000000x"));
    let under =
        h.query_all_by_label_contains("#000000x").filter(|n| n.value().is_some_and(|v| v.starts_with("colour")));
    assert_eq!(under.count(), 1, "the error shows under the control");
    let after = h.state().counters();
    assert_eq!((after.renders, after.recolours), (before.renders, before.recolours));
}

/// The formula chooser: a family and a power chosen in the side panel render that formula at
/// the same view; the Julia pick there opens that family's Julia form, and the Mandelbrot
/// form again keeps it; a formula typed that the parser refuses is said under the field and
/// changes nothing.
#[test]
fn the_formula_chooser_sets_the_family_power_and_julia_form() {
    let dir = scratch("viewer-formula");
    let scene = "version = 1\n[view]\ncenter = [\"-0.5\", \"-0.5\"]\nzoom = \"1\"\n[iteration]\nmax = 100\n";
    let mut h = harness(&dir, scene);
    let nav = h.state().nav().clone();
    let before = h.state().counters();
    h.get_by_label("family").click();
    h.run_steps(2);
    h.get_by_label("burning-ship").click();
    settle(&mut h);
    assert_eq!(h.state().formula().to_string(), "burning-ship");
    assert_eq!(h.state().nav(), &nav, "the view stays");
    assert!(h.state().counters().renders > before.renders, "the new formula renders");
    h.get_by_label("power").click();
    h.run_steps(2);
    h.get_by_label("3").click();
    settle(&mut h);
    assert_eq!(h.state().formula_title(), "burning-ship^3");
    assert_eq!(h.state().nav(), &nav);
    assert_eq!(h.state().scene_file().formula.kind.get_ref(), "burning-ship^3");
    // The GPU modes draw z² + c only.
    h.state_mut().set_mode(ViewMode::GpuF32);
    assert_eq!(h.state().mode(), ViewMode::Cpu);

    // The Julia preview and pick show burning-ship^3's Julia form.
    let r = h.state().image_rect();
    let at = r.center() + Vec2::new(-40.0, 20.0);
    h.hover_at(at);
    h.run_steps(2);
    assert!(h.state().counters().julia_previews >= 1, "hovering previews the Julia set");
    ctrl_click(&mut h, at);
    settle(&mut h);
    assert!(h.state().julia_c().is_some(), "a Julia scene now");
    assert_eq!(h.state().formula_title(), "burning-ship^3 (Julia form)");
    h.get_by_label("Mandelbrot").click();
    settle(&mut h);
    assert_eq!(h.state().julia_c(), None);
    assert_eq!(h.state().formula_title(), "burning-ship^3");

    // A power no phase comes in: refused by the field, nothing changes.
    let renders = h.state().counters().renders;
    h.get_by_label("formula").focus();
    h.run_steps(1);
    h.get_by_label("formula").type_text(",mandelbrot^33");
    h.key_press(egui::Key::Enter);
    settle(&mut h);
    assert_eq!(h.state().formula_title(), "burning-ship^3");
    assert!(h.query_by_label_contains("not 33").is_some(), "the error shows under the field");
    assert_eq!(h.state().counters().renders, renders, "nothing renders from a refused formula");
    // One digit less: a hybrid.
    h.get_by_label("formula").focus();
    h.run_steps(1);
    h.key_press(egui::Key::Backspace);
    h.key_press(egui::Key::Enter);
    settle(&mut h);
    assert_eq!(h.state().formula_title(), "burning-ship^3,mandelbrot^3");
    assert!(h.query_by_label_contains("not 33").is_none(), "the error is gone");
    assert!(h.state().counters().renders > renders);
}
