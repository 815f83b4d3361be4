//! `deepfield recolor`: raw data (EXR) + layers -> PNG, without recomputing the fractal.
//!
//! The layers come from the scene stored in the EXR (so a bare `recolor DATA.exr`
//! reproduces the render), from `--scene`, or from `--layer` specifications; `--palette`
//! overrides the palette of each. The view of the scene must match the data (same
//! sample raster); planes a layer needs but the file lacks are named in the error.

use std::collections::BTreeMap;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::anyhow;
use deepfield::coloring::Context;
use deepfield::field::{Channel, Needs, Planes};
use deepfield::io::{ExrStrips, PngEncoder, PngWriter, RawHeader};
use deepfield::render;
use deepfield::scene::Scene;
use deepfield::scene::raw::cli;
use deepfield::simd_level::SimdLevel;

use super::Failure;
use super::args::RecolorArgs;

/// Runs `deepfield recolor`.
pub fn run(args: RecolorArgs) -> Result<(), Failure> {
    let t0 = Instant::now();
    if !args.data.exists() {
        return Err(Failure::Input(anyhow!("{}: no such file", args.data.display())));
    }
    let out = args.output.clone().unwrap_or_else(|| args.data.with_extension("png"));
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    if abs(&out) == abs(&args.data) || args.scene.as_deref().is_some_and(|s| abs(s) == abs(&out)) {
        return Err(Failure::Input(anyhow!("-o {} would overwrite an input; choose another name", out.display())));
    }
    let simd = super::simd_level(args.simd.as_deref())?;
    let data = ExrStrips::open(&args.data, 32).map_err(Failure::input)?;
    let (origin, text, base) = match &args.scene {
        Some(path) => super::scene::read_source(path)?,
        None => {
            let text = data.header().scene.clone().ok_or_else(|| {
                Failure::Input(anyhow!("{}: the file carries no scene; give one with --scene", args.data.display()))
            })?;
            (format!("{} (stored scene)", args.data.display()), text, PathBuf::from("."))
        }
    };
    let mut specs = Vec::new();
    for (i, spec) in args.layers.iter().enumerate() {
        specs.push(super::scene::layer_spec(spec, i + 1)?);
    }
    let scene = super::scene::load_text(&origin, &text, &base, |file| {
        if !specs.is_empty() {
            file.layers = specs.into_iter().map(cli).collect();
        }
        if let Some(p) = &args.palette {
            super::scene::apply_palette(file, p);
        }
        if let Some(c) = args.cycle {
            file.render.cycle = Some(cli(c));
        }
        if let Some(b) = &args.bits {
            file.output.bits = Some(cli(b.parse().unwrap_or(8)));
        }
    })?;
    check_fits(&scene, data.header(), &args.data)?;

    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0) as usize)
        .build()
        .map_err(|e| Failure::Runtime(e.into()))?;
    let png =
        PngWriter::create(&out, scene.width, scene.height, scene.png_bits, &scene.to_toml()).map_err(Failure::input)?;
    let read_s = write_coloured(&scene, data, &pool, png, simd)?;
    if args.stats {
        let read = match read_s {
            Some(s) => format!("read {s:.3} s, then colour and write"),
            None => "read, colour and write (streamed)".into(),
        };
        let line = format!(
            "{read}: {:.3} s in all ({} x {} pixels, {} layers; simd {})\n",
            t0.elapsed().as_secs_f64(),
            scene.width,
            scene.height,
            scene.stack.layers.len(),
            simd.describe(),
        );
        std::io::stdout().lock().write_all(line.as_bytes()).map_err(|e| Failure::Runtime(e.into()))?;
    }
    Ok(())
}

/// Reads, colours and writes the strips on `pool`: the writer thread deflates one strip
/// while the workers colour the next ones, and puts the strips, which finish in any order,
/// back in order. Layers that need nothing image-wide colour each strip as soon as the
/// reader has it (reading, colouring and deflating overlap; `None` returned); otherwise the
/// whole file is read first for the image-wide context (the seconds that took returned).
/// A fault in the data file is the input's (nothing is written); one writing the PNG, the
/// run's.
fn write_coloured(
    scene: &Scene,
    data: ExrStrips,
    pool: &rayon::ThreadPool,
    mut png: PngWriter,
    simd: SimdLevel,
) -> Result<Option<f64>, Failure> {
    use rayon::prelude::*;
    let enc = PngEncoder::new(scene.png_bits);
    let colour = |planes: &Planes, ctx: &Context| match scene.png_bits {
        8 => render::strip_rgb8(&scene.stack, planes, scene.aa, ctx),
        _ => enc.encode(&render::strip_linear(&scene.stack, planes, scene.aa, ctx)),
    };
    let (tx, rx) = std::sync::mpsc::channel::<(usize, Vec<u8>)>();
    std::thread::scope(|s| {
        let writer = s.spawn(move || {
            let mut waiting = BTreeMap::new();
            let mut next = 0;
            for (k, bytes) in rx {
                waiting.insert(k, bytes);
                while let Some(bytes) = waiting.remove(&next) {
                    png.write_encoded(&bytes)?;
                    next += 1;
                }
            }
            Ok(png)
        });
        // A failed writer drops the receiver; the workers' sends then fail and are ignored.
        let read = pool.install(|| {
            if scene.stack.is_global() {
                let t = Instant::now();
                let raw = data.collect()?;
                let read_s = t.elapsed().as_secs_f64();
                let ctx = Context { simd, ..render::context(&scene.stack, &raw.strips) };
                raw.strips.par_iter().enumerate().for_each(|(k, p)| drop(tx.send((k, colour(p, &ctx)))));
                Ok(Some(read_s))
            } else {
                let ctx = Context { simd, ..Context::default() };
                data.for_each_strip_lent(|k, p| drop(tx.send((k, colour(p, &ctx))))).map(|()| None)
            }
        });
        drop(tx);
        let written = writer.join().unwrap_or_else(|panic| std::panic::resume_unwind(panic));
        // A read fault comes first (the file is then never moved into place, even where every
        // strip had arrived before the fault showed); then the writer's.
        let read = read.map_err(Failure::input)?;
        written.and_then(PngWriter::finish).map(|()| read).map_err(|e| Failure::Runtime(e.into()))
    })
}

/// Refuses a scene whose raster or layers the data cannot serve.
pub(super) fn check_fits(scene: &Scene, raw: &RawHeader, data: &Path) -> Result<(), Failure> {
    let name = data.display();
    let (w, h) = ((scene.width * scene.aa) as usize, (scene.height * scene.aa) as usize);
    if (w, h) != (raw.width, raw.height) {
        return Err(Failure::Input(anyhow!(
            "{name} holds {} x {} samples; the scene needs {w} x {h} ({} x {} pixels, aa {}): recolour with the scene that made it, or change only its layers",
            raw.width,
            raw.height,
            scene.width,
            scene.height,
            scene.aa
        )));
    }
    let needs: Needs = scene.stack.needs(&scene.traps);
    for (on, channel) in
        [(needs.nf, Channel::NF), (needs.t, Channel::T), (needs.de, Channel::DEX), (needs.de, Channel::DEY)]
    {
        if on && !raw.channels.contains(channel) {
            return Err(Failure::Input(anyhow!(
                "{name} has no {channel} channel, which the layers need; render it again with --exr and --channels including {channel}"
            )));
        }
    }
    let kinds = &raw.traps;
    for (k, trap) in scene.traps.iter().enumerate() {
        let want = trap.plane_kind();
        if kinds.get(k) != Some(&want) {
            return Err(Failure::Input(anyhow!(
                "{name} has no {want:?} data for trap {k}, which the layers need (trap and stripe data are computed while iterating: render with the layers that use them)"
            )));
        }
    }
    Ok(())
}
