//! `deepfield render`: scene + flags -> PNG (+ EXR), with progress, cancel and statistics.

use std::io::Write;
use std::path::{Path, PathBuf};

use anyhow::anyhow;
use deepfield::field::ChannelSet;
use deepfield::io;
use deepfield::render::{self, Options, Stats};

use super::Failure;
use super::args::RenderArgs;
use super::terminal::{bar, install_ctrlc, show};

/// Runs `deepfield render`.
pub fn run(args: RenderArgs) -> Result<(), Failure> {
    // Ctrl-C sets a flag the kernels poll; installed first so that no output file can
    // exist before the handler does. Failing to install it only loses Ctrl-C handling.
    let cancel = install_ctrlc();
    let scene = super::scene::load(&args.scene)?;
    let plan = super::engine_plan(&scene)?;
    let simd = super::simd_level(args.simd.as_deref())?;
    let png_path = args.output.clone().unwrap_or_else(|| default_output(args.scene.path.as_deref()));
    check_distinct(&args, &png_path)?;
    let exr_channels = if args.exr.is_some() { scene.channels } else { ChannelSet::default() };

    // Open every output before computing anything: an unwritable path fails at once.
    let stats_file = match &args.stats_json {
        Some(path) => Some(io::AtomicFile::create(path).map_err(Failure::input)?),
        None => None,
    };
    let rows = match args.tile {
        Some((k, n)) => {
            if n > scene.height {
                return Err(Failure::Input(anyhow!("--tile {k}/{n}: the image has only {} rows", scene.height)));
            }
            if scene.stack.is_global() && args.exr.is_none() {
                return Err(Failure::Input(anyhow!(
                    "--tile: a histogram layer colours each pixel from the whole image, which one unit does not see; add --exr, assemble the units' EXR files and recolour the whole (the unit's PNG is then coloured from its band alone)"
                )));
            }
            Some(io::band_rows(k, n, scene.height))
        }
        None => None,
    };
    let engine = engine_text(&plan, simd);
    let targets =
        io::output::Targets { png: Some(&png_path), exr: args.exr.as_deref(), tile: args.tile, engine: &engine };
    let (writers, encoders) = io::output::open(&scene, targets).map_err(Failure::input)?;

    let references = match &args.reference {
        Some(path) => Some(std::sync::Arc::new(super::reference::read(path)?)),
        None => None,
    };
    let bar = bar(args.quiet, rows.as_ref().map_or(scene.height, |r| r.end - r.start) as u64);
    let progress = |p: render::Progress| show(&bar, p);
    let prepare = |strip: &render::RenderedStrip| {
        Ok(encoders.encode(strip.row, &strip.rgb, &strip.planes, strip.samples.as_deref())?)
    };
    let mut writers = Some(writers);
    let result = {
        let writers = &mut writers;
        let options = Options {
            threads: args.threads.unwrap_or(0) as usize,
            exr_channels,
            simd,
            rows,
            references: references.clone(),
            dense_orbit: args.dense_orbit,
            ..Options::default()
        };
        render::render(&scene, &plan, options, &cancel, &progress, &prepare, move |_strip, encoded| {
            Ok(writers.as_mut().ok_or("output already finished")?.write(encoded)?)
        })
    };
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let stats = result?;
    if let Some(w) = writers.take() {
        w.finish().map_err(|e| Failure::Runtime(e.into()))?;
    }
    report(&args, &stats, stats_file)
}

/// The header comment of an EXR: the engine, why, and the SIMD level.
pub fn engine_text(plan: &deepfield::render::engine::EnginePlan, simd: deepfield::simd_level::SimdLevel) -> String {
    format!("{}: {}; SIMD: {}", plan.name, plan.reason, simd.describe())
}

/// Refuses runs whose outputs would collide with each other or overwrite the input scene.
fn check_distinct(args: &RenderArgs, png: &Path) -> Result<(), Failure> {
    let abs = |p: &Path| std::path::absolute(p).unwrap_or_else(|_| p.to_path_buf());
    let mut named: Vec<(&str, PathBuf)> = vec![("-o", abs(png))];
    if let Some(p) = &args.exr {
        named.push(("--exr", abs(p)));
    }
    if let Some(p) = &args.stats_json {
        named.push(("--stats-json", abs(p)));
    }
    for (i, (a, pa)) in named.iter().enumerate() {
        for (b, pb) in &named[i + 1..] {
            if pa == pb {
                return Err(Failure::Input(anyhow!("{a} and {b} name the same file {}", pa.display())));
            }
        }
        if let Some(scene) = &args.scene.path
            && abs(scene) == *pa
        {
            return Err(Failure::Input(anyhow!(
                "{a} would overwrite the input {}; give another output name with {a}",
                scene.display()
            )));
        }
    }
    Ok(())
}

fn report(
    args: &RenderArgs,
    stats: &Stats,
    stats_file: Option<(io::AtomicFile, std::io::BufWriter<std::fs::File>)>,
) -> Result<(), Failure> {
    if args.stats {
        let mut out = std::io::stdout().lock();
        let mut text = format!(
            "formula     {}\nengine      {}\n  why       {}\nprecision   {}\nsimd        {}\nthreads     {}\npixels      {}\nsamples     {}\niterations  {}\nwall time   {:.3} s\nspeed       {:.3e} iterations/s\nglitches    {}\n",
            stats.formula,
            stats.engine,
            stats.engine_reason,
            stats.precision,
            stats.simd,
            stats.threads,
            stats.pixels,
            stats.samples,
            stats.iterations,
            stats.wall_seconds,
            stats.iterations_per_second,
            stats.glitched_pixels
        );
        if let Some(d) = &stats.deep {
            text.push_str(&format!(
                "reference   {} iterations{}{} at {} bits, {:.3} s (orbit {:.3} s, BLA tables {:.3} s), {:.1} MB + BLA {:.1} MB ({} period-aligned steps, {} stages{})\nsteps       {} perturbation ({} in FloatExp), {} BLA covering {} iterations{}, {} rebases\n",
                d.reference_iterations,
                match (d.reference_escaped, d.reference_period, d.reference_cycle) {
                    (true, _, _) => " (escaped)".to_string(),
                    (_, Some(p), _) => format!(" (one period: the centre is a nucleus of period {p}; stored once, samples rebase through it)"),
                    (_, _, Some(w)) => format!(" (it repeats itself exactly: stored to its first repeat and {w} iterations of copies, which samples go round)"),
                    _ => String::new(),
                },
                if d.reference_dense < d.reference_iterations {
                    format!(
                        ", {} stored densely and {} packed",
                        d.reference_dense,
                        d.reference_iterations - d.reference_dense
                    )
                } else {
                    String::new()
                },
                d.reference_bits,
                d.reference_seconds,
                d.orbit_seconds,
                d.tables_seconds,
                d.reference_bytes as f64 / 1e6,
                d.bla_bytes as f64 / 1e6,
                d.aligned_steps,
                d.aligned_stages,
                if d.block_steps > 0 {
                    format!(
                        "; {} steps of {}-iteration blocks from iteration {}, built in {:.3} s when samples got there",
                        d.block_steps, d.block_length, d.blocks_from, d.blocks_seconds
                    )
                } else {
                    String::new()
                },
                d.steps,
                d.floatexp_steps,
                d.bla_steps,
                d.bla_iterations,
                if d.reference_dense < d.reference_iterations {
                    format!(" ({} of the steps through the packed tail)", d.tail_bla_steps)
                } else {
                    String::new()
                },
                d.rebases
            ));
            if let Some((degree, m)) = d.series {
                text.push_str(&format!(
                    "series      degree {degree} to iteration {m}: {} samples started from it, skipping {} iterations\n",
                    d.series_samples, d.series_iterations
                ));
            }
            text.push_str(&format!("interior    detection {}", d.interior_detection.describe()));
            text.push_str(&match d.interior_threshold {
                Some(t) => format!(
                    ", |dz/dz|^2 < {t:.1e}: {} samples stopped early ({} by Newton's test, {} of them in disks certified at once)\n",
                    d.interior_samples, d.interior_newton_samples, d.interior_disk_samples
                ),
                None => "\n".to_string(),
            });
        }
        out.write_all(text.as_bytes()).map_err(|e| Failure::Runtime(e.into()))?;
    }
    if let Some(opened) = stats_file {
        let json = serde_json::to_string_pretty(stats).map_err(|e| Failure::Runtime(e.into()))?;
        super::commit_text(opened, &(json + "\n"))?;
    }
    Ok(())
}

fn default_output(scene: Option<&Path>) -> PathBuf {
    let stem = scene
        .and_then(|p| p.file_stem())
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "deepfield".into());
    PathBuf::from(format!("{stem}.png"))
}
