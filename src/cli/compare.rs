//! `deepfield compare`: a table of engines, their speed and their error against the truth.

use std::io::{IsTerminal, Write};

use anyhow::anyhow;
use deepfield::compare::{self, Row};
use indicatif::{ProgressBar, ProgressStyle};

use super::Failure;
use super::args::CompareArgs;

/// Runs `deepfield compare`.
pub fn run(args: CompareArgs) -> Result<(), Failure> {
    let cancel = super::terminal::install_ctrlc();
    let scene = super::scene::load(&args.scene)?;
    if !scene.projection.is_flat() {
        return Err(Failure::Input(anyhow::anyhow!(
            "compare measures flat views; drop view.exponential_map (a strip's samples are the same engines' at other points)"
        )));
    }
    let simd = super::simd_level(args.simd.as_deref())?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.unwrap_or(0) as usize)
        .build()
        .map_err(|e| Failure::Runtime(e.into()))?;
    let mut variants = compare::variants(&scene);
    if variants.is_empty() {
        return Err(Failure::Input(anyhow!("no engine can address this view")));
    }
    if !args.only.is_empty() {
        variants.retain(|v| args.only.iter().any(|o| v.name.contains(o.as_str())));
        if variants.is_empty() {
            return Err(Failure::Input(anyhow!("--only {}: no engine's name matches", args.only.join(","))));
        }
    }
    if variants.iter().any(|v| v.kind.is_gpu())
        && let Err(e) = deepfield::gpu::GpuContext::shared()
    {
        // No GPU is no failure: the comparison goes on without the GPU rows, unless they
        // were all that --only kept.
        variants.retain(|v| !v.kind.is_gpu());
        if variants.is_empty() {
            return Err(Failure::Runtime(anyhow!("--only kept only GPU engines, and there is no GPU: {e}")));
        }
        eprintln!("note: leaving out the gpu and gpu-df rows: {e}");
    }
    // Opened before any work: an unwritable path fails at once.
    let pixel_file = match &args.pixels {
        Some(path) => Some(deepfield::io::AtomicFile::create(path).map_err(Failure::input)?),
        None => None,
    };
    let pixels = compare::sample_pixels(&scene, args.samples);
    // Peers' values, read before any work: a file that does not fit the view fails at once.
    let samples_wide = (scene.width * scene.aa) as usize;
    let samples_high = (scene.height * scene.aa) as usize;
    let peers = args
        .peer
        .iter()
        .map(|spec| peer(spec, (samples_wide, samples_high), &pixels))
        .collect::<Result<Vec<_>, _>>()?;
    let bar = (!args.quiet && std::io::stderr().is_terminal()).then(|| {
        let b = ProgressBar::new(pixels.len() as u64);
        let style = ProgressStyle::with_template("{spinner} [{elapsed_precise}] {wide_bar} {pos}/{len} {msg}")
            .unwrap_or_else(|_| ProgressStyle::default_bar());
        b.set_style(style);
        b.set_message("ground-truth pixels (big floats)");
        b
    });
    let done = pool.install(|| -> Result<(Vec<Row>, Option<String>), Failure> {
        let progress = |n: u64| {
            if let Some(b) = &bar {
                b.set_position(n);
            }
        };
        let mut truths =
            compare::truths(&scene, scene.formula, &pixels, &cancel, &progress).map_err(|_| Failure::Cancelled)?;
        if let Some(b) = &bar {
            b.set_length(variants.len() as u64);
            b.set_position(0);
        }
        let mut measured = Vec::new();
        for (k, v) in variants.iter().enumerate() {
            if let Some(b) = &bar {
                b.set_message(v.name.clone());
            }
            let m = compare::run(&scene, v, &pixels, args.sample_only, simd, &cancel).map_err(|e| match e {
                compare::RunError::Cancelled => Failure::Cancelled,
                compare::RunError::Gpu(e) => Failure::Runtime(anyhow!(e)),
                compare::RunError::Engine(e) => Failure::Input(anyhow!(e)),
            })?;
            measured.push(m);
            if let Some(b) = &bar {
                b.set_position(k as u64 + 1);
            }
        }
        let names: Vec<String> =
            variants.iter().map(|v| v.name.clone()).chain(peers.iter().map(|p| p.0.clone())).collect();
        measured.extend(peers.into_iter().map(|p| p.1));
        let suspects = compare::suspects(&measured, &truths, scene.escape_radius, scene.transform);
        if let Some(b) = &bar {
            b.set_message(format!("conditioning of {} disagreeing pixels", suspects.len()));
        }
        compare::mark_ill_conditioned(&scene, scene.formula, &pixels, &mut truths, &suspects, &cancel)
            .map_err(|_| Failure::Cancelled)?;
        let rows = names
            .iter()
            .zip(&measured)
            .map(|(name, m)| compare::score(name, m, &truths, scene.escape_radius, scene.transform))
            .collect();
        let names: Vec<&str> = names.iter().map(String::as_str).collect();
        let csv =
            pixel_file.is_some().then(|| compare::pixel_csv(&pixels, &truths, &names, &measured, scene.escape_radius));
        Ok((rows, csv))
    });
    if let Some(b) = &bar {
        b.finish_and_clear();
    }
    let (rows, pixel_text) = done?;
    if let (Some(opened), Some(text)) = (pixel_file, pixel_text) {
        super::commit_text(opened, &text)?;
    }
    let text = if args.json {
        serde_json::to_string_pretty(&rows).map_err(|e| Failure::Runtime(e.into()))? + "\n"
    } else if args.csv {
        csv(&rows)
    } else {
        table(&rows, &scene.origin, pixels.len())
    };
    std::io::stdout().lock().write_all(text.as_bytes()).map_err(|e| Failure::Runtime(anyhow!(e)))
}

/// A peer's name and values from `NAME=FILE` (see `--peer`), at the sampled `pixels` of a
/// view of `size` samples.
fn peer(spec: &str, size: (usize, usize), pixels: &[(u32, u32)]) -> Result<(String, compare::Measured), Failure> {
    let Some((name, file)) = spec.split_once('=').filter(|(n, f)| !n.is_empty() && !f.is_empty()) else {
        return Err(Failure::Input(anyhow!("--peer {spec}: expected NAME=FILE (for example fraktaler-3=f3.exr)")));
    };
    let path = std::path::Path::new(file);
    let raw = deepfield::io::read_exr_planes(path, usize::MAX).map_err(Failure::input)?;
    let bias = deepfield::io::read_exr_iteration_bias(path).map_err(Failure::input)?;
    let (mut n, mut nf) = (Vec::new(), Vec::new());
    for strip in &raw.strips {
        n.extend_from_slice(&strip.n);
        nf.extend_from_slice(&strip.nf);
    }
    let m = compare::peer::measured(&n, &nf, (raw.header.width, raw.header.height), size, bias, pixels)
        .map_err(|e| Failure::Input(anyhow!("--peer {name}: {file}: {e}")))?;
    Ok((format!("peer {name}"), m))
}

const KEYS: [&str; 14] = [
    "engine",
    "seconds",
    "iterations_per_second",
    "n_mismatch_fraction",
    "nf_error_p50",
    "nf_error_p99",
    "de_error_p50",
    "de_error_p99",
    "compared",
    "nf_scored",
    "de_scored",
    "ill_conditioned",
    "nf_ill_conditioned",
    "de_ill_conditioned",
];

fn fields(r: &Row) -> [String; 14] {
    // Not measured (a peer's time and distance errors, errors over no pixel): "-".
    let or_dash = |x: f64, s: String| if x.is_nan() { "-".to_string() } else { s };
    [
        r.engine.clone(),
        or_dash(r.seconds, format!("{:.4}", r.seconds)),
        or_dash(r.iterations_per_second, format!("{:.4e}", r.iterations_per_second)),
        format!("{:.6}", r.n_mismatch_fraction),
        or_dash(r.nf_error_p50, format!("{:.3e}", r.nf_error_p50)),
        or_dash(r.nf_error_p99, format!("{:.3e}", r.nf_error_p99)),
        or_dash(r.de_error_p50, format!("{:.3e}", r.de_error_p50)),
        or_dash(r.de_error_p99, format!("{:.3e}", r.de_error_p99)),
        r.compared.to_string(),
        r.nf_scored.to_string(),
        r.de_scored.to_string(),
        r.ill_conditioned.to_string(),
        r.nf_ill_conditioned.to_string(),
        r.de_ill_conditioned.to_string(),
    ]
}

fn csv(rows: &[Row]) -> String {
    let mut out = KEYS.join(",") + "\n";
    for r in rows {
        out += &(fields(r).join(",") + "\n");
    }
    out
}

fn table(rows: &[Row], origin: &str, samples: usize) -> String {
    let heads = [
        "engine",
        "seconds",
        "iter/s",
        "N mismatch",
        "NF p50",
        "NF p99",
        "DE p50",
        "DE p99",
        "pixels",
        "NF px",
        "DE px",
        "ill-cond.",
        "NF ill-cond.",
        "DE ill-cond.",
    ];
    let cells: Vec<[String; 14]> = rows.iter().map(fields).collect();
    let width: Vec<usize> =
        (0..heads.len()).map(|k| cells.iter().map(|c| c[k].len()).chain([heads[k].len()]).max().unwrap_or(0)).collect();
    let line = |c: &[&str]| -> String {
        let mut s = format!("{:<w$}", c[0], w = width[0]);
        for k in 1..heads.len() {
            s += &format!("  {:>w$}", c[k], w = width[k]);
        }
        s + "\n"
    };
    let mut out = format!("{origin}: {samples} sampled pixels against direct big-float iteration\n");
    out += &line(&heads);
    for c in &cells {
        out += &line(&c.iter().map(String::as_str).collect::<Vec<_>>());
    }
    out + "pixels: compared for N (orbits passing within 1e-9 of the escape circle left out); \
           NF px, DE px: the pixels the NF and distance errors are taken over (escaped, N right; \
           \"-\": none); \
           ill-cond.: wrong N where the true N changes within 1e-9 pixel, or the orbit spreads 1e-9 pixel \
           to 1 while |z| <= 2 (left out); \
           NF ill-cond.: NF more than 1e-4 off where the true NF changes by more than 1e-4 within 1e-9 pixel \
           (left out of the NF and DE errors); \
           DE ill-cond.: distance estimate more than 1e-6 off where the true one moves by more than 1e-4 of itself \
           within 1e-9 pixel (left out of the DE errors)\n"
}
