//! How soon the viewer shows something after a change of view: the time from submitting a
//! job to the viewer's render worker until its coarse (1/8) pass and its final pass arrive.
//!
//! `cargo run --release --example viewer_latency [SCENE] [WxH]` (default
//! `scenes/seahorse-valley.toml` at 1100x680, the image area of a 1400x800 window), five
//! times each, the worker on its own thread exactly as in the viewer.
#![allow(clippy::print_stdout)] // printing the measurement is the point

use std::sync::Arc;
use std::time::{Duration, Instant};

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
        Scene::validate(file, &src.origin, &src.text, &src.base_dir, &deepfield::io::load_bitmap).expect("valid");
    scene.width = w;
    scene.height = h;
    let mut worker = Worker::spawn(Arc::new(|| {}));
    println!("{path} at {w}x{h} (aa {} in the final pass)", scene.aa);
    for run in 0..5 {
        let start = Instant::now();
        worker.submit(Job { scene: scene.clone(), nav: Nav::home(), passes: vec![8, 2, 1] });
        let mut first = None;
        loop {
            let mut done = false;
            for r in worker.poll() {
                if let Report::Pass(p) = r {
                    first.get_or_insert(start.elapsed());
                    done |= p.last;
                }
            }
            if done {
                break;
            }
            std::thread::sleep(Duration::from_micros(200));
        }
        let first = first.unwrap_or_default().as_secs_f64() * 1e3;
        println!("run {run}: coarse pass {first:.1} ms, final pass {:.1} ms", start.elapsed().as_secs_f64() * 1e3);
    }
}
