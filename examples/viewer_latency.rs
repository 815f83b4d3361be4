//! How soon the viewer shows something after a change of view: the time from submitting a
//! job to the viewer's render worker until its coarse (1/8) pass and its final pass arrive.
//!
//! `cargo run --release --example viewer_latency [SCENE] [WxH]` (default
//! `scenes/seahorse-valley.toml` at 1100x680, the image area of a 1400x800 window), the
//! worker on its own thread exactly as in the viewer: the view itself five times, then a
//! navigation sequence (pans of a quarter view, zooms in by 2 about the centre), where a
//! deep view keeps its reference orbit and BLA tables while they serve.
#![allow(clippy::print_stdout)] // printing the measurement is the point

use std::sync::Arc;
use std::time::{Duration, Instant};

use deepfield::num::Decimal;
use deepfield::orbit::Scale;
use deepfield::scene::Scene;
use deepfield::viewer::nav::Nav;
use deepfield::viewer::worker::{Job, Report, Worker};

fn main() {
    let mut args = std::env::args().skip(1);
    let path = args.next().unwrap_or_else(|| "scenes/seahorse-valley.toml".into());
    let (w, h) = args
        .next()
        .and_then(|s| s.split_once('x').and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?))))
        .unwrap_or((1100u32, 680u32));
    let src = deepfield::io::read_scene_source(std::path::Path::new(&path)).expect("scene");
    let file = Scene::parse_file(&src.origin, &src.text).expect("parses");
    let mut scene =
        Scene::validate(file, &src.origin, &src.text, &src.base_dir, deepfield::io::load_bitmap).expect("valid");
    scene.width = w;
    scene.height = h;
    let mut worker = Worker::spawn(Arc::new(|| {}), None);
    println!("{path} at {w}x{h} (aa {} in the final pass)", scene.aa);
    let mut run = |label: &str, scene: &Scene| {
        let start = Instant::now();
        worker.submit(Job { scene: scene.clone(), nav: Nav::home(), passes: vec![8, 2, 1] });
        let mut first = None;
        loop {
            let mut done = false;
            for r in worker.poll() {
                match r {
                    Report::Pass(p) => {
                        first.get_or_insert(start.elapsed());
                        done |= p.last;
                    }
                    Report::Failed { message, .. } => panic!("{message}"),
                    _ => {}
                }
            }
            if done {
                break;
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        let first = first.unwrap_or_default().as_secs_f64() * 1e3;
        println!("{label}: coarse pass {first:.1} ms, final pass {:.1} ms", start.elapsed().as_secs_f64() * 1e3);
    };
    for k in 0..5 {
        run(&format!("run {k}"), &scene);
    }
    let mut nav =
        Nav { center: scene.center.clone().map(|d| d.text().to_string()), log10_zoom: 0.0, transform: scene.transform };
    nav.log10_zoom = 2f64.log10() - scene.log10_radius;
    for step in ["pan", "pan", "zoom", "pan", "zoom"] {
        nav = match step {
            "pan" => nav.pan(w as f64 / 4.0, 0.0, h as f64),
            _ => nav.zoom_about(2.0, [0.0, 0.0], h as f64),
        };
        scene.center = nav.center.clone().map(|t| Decimal::parse(&t).expect("a decimal"));
        if step == "zoom" {
            let zoom = Decimal::parse(&nav.zoom_text()).expect("a decimal");
            scene.log10_radius = 2f64.log10() - nav.log10_zoom;
            scene.radius = 10f64.powf(scene.log10_radius);
            scene.scale = Scale::Zoom(zoom);
        }
        let label = if step == "pan" { "pan by a quarter view" } else { "zoom in by 2" };
        run(label, &scene);
    }
}
