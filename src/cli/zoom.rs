//! `deepfield zoom`: a zoom-out sequence of keyframes, each a fixed factor shallower than
//! the next, as EXR raw data (Kalles Fraktaler / Fraktaler-3 channels) for a zoom video
//! assembler, all from the one reference orbit of the deepest frame.
//!
//! Keyframe k of N is `DIR/NNNNN.exr` (five digits), the view at zoom Z / factor^(N-1-k):
//! index 0 is the outermost, N-1 the scene's own view, so depth grows with the index.
//! Every frame that perturbs reads the deepest frame's reference orbits (computed once, or
//! read from `--reference`): a shallower frame needs fewer bits and the same centre, so
//! they serve it; frames shallow enough for direct f64 iteration need none. `--units A..B`
//! renders only those keyframes: a work unit of the sequence for a job array.
//!
//! With `--exponential-map F` the keyframes are instead the strips of an exponential map
//! (`field::projection`), one per factor F, sized for video frames of the scene's size and
//! supersampling: strip k's outer circle circumscribes the frame k factors out, and
//! `center.exr` holds the flat view inside the deepest ring (written with the unit that
//! holds the last strip). Its spacing is the finest, so its reference orbits serve all.

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use anyhow::anyhow;
use deepfield::num::{Decimal, scientific};
use deepfield::orbit::saved::{SavedReferences, key_of};
use deepfield::render::{self, Options};
use deepfield::scene::Scene;
use deepfield::scene::raw::cli;
use malachite_base::num::arithmetic::traits::Pow;
use malachite_q::Rational;

use super::Failure;
use super::args::ZoomArgs;

/// Runs `deepfield zoom`.
pub fn run(args: ZoomArgs) -> Result<(), Failure> {
    let cancel = super::terminal::install_ctrlc();
    let simd = super::simd_level(args.simd.as_deref())?;
    let deepest = super::scene::load(&args.scene)?;
    let factor_text = match (&args.factor, args.scene.exponential_map) {
        (Some(_), Some(_)) => {
            return Err(Failure::Input(anyhow!(
                "give the zoom factor once: --exponential-map F is the factor between its strips"
            )));
        }
        (Some(f), None) => f.clone(),
        (None, Some(f)) => format!("{f}"),
        (None, None) => "2".into(),
    };
    let factor = Decimal::parse(&factor_text).map_err(Failure::input)?;
    if factor.is_negative() || factor.log10_abs() <= 0.0 || factor.log10_abs() > 1e6 {
        return Err(Failure::Input(anyhow!("--factor must be above 1, got {factor}")));
    }
    let log10_zoom = 2f64.log10() - deepest.log10_radius;
    let frames = match (args.frames, &args.to_zoom) {
        (Some(n), _) => n,
        (None, Some(z)) => {
            let z = Decimal::parse(z).map_err(Failure::input)?;
            if z.is_zero() || z.is_negative() || z.log10_abs() > log10_zoom {
                return Err(Failure::Input(anyhow!(
                    "--to-zoom {z} must be positive and no deeper than the scene's zoom"
                )));
            }
            ((log10_zoom - z.log10_abs()) / factor.log10_abs()).ceil() as u32 + 1
        }
        (None, None) => return Err(Failure::Input(anyhow!("give --frames N or --to-zoom Z"))),
    };
    if frames == 0 || frames > 100_000 {
        return Err(Failure::Input(anyhow!("{frames} keyframes: give between 1 and 100000")));
    }
    let units = match args.units {
        Some((a, b)) if a < b && b <= frames => a..b,
        Some((a, b)) => {
            return Err(Failure::Input(anyhow!("--units {a}..{b}: keyframes are 0..{frames}, and A must be below B")));
        }
        None => 0..frames,
    };
    let dir = &args.output;
    std::fs::create_dir_all(dir).map_err(|e| Failure::Input(anyhow!("{}: {e}", dir.display())))?;
    let start = Instant::now();
    // An exponential map: strips for video frames of the scene's size, each ring from a
    // keyframe's circumscribed circle inwards by the factor, and the flat view inside the
    // deepest ring (the finest spacing: its reference orbits serve every strip).
    let map = args.scene.exponential_map.map(|f| ExponentialMap::of(&deepest, f));
    let center = match &map {
        Some(m) => Some(super::scene::load_edited(&args.scene, |file| {
            file.view.zoom = Some(cli(scaled_zoom(&deepest, &factor, 0, m.circumradius / m.factor)));
            file.view.radius = None;
            file.view.width = cli(m.center_side as i64);
            file.view.height = cli(m.center_side as i64);
            file.view.exponential_map = None;
        })?),
        None => None,
    };
    let finest = center.as_ref().unwrap_or(&deepest);
    // The finest frame's reference orbits, shared by every frame that perturbs.
    let plan = super::engine_plan(finest)?;
    let options = Options { simd, ..Options::default() };
    // (Reference files hold z² + c's orbits; every frame of another formula that perturbs
    // computes its own references.)
    let quadratic = finest.formula.is_quadratic();
    let references = match (&args.reference, render::deep_spec(finest, &plan, &options).1) {
        (Some(path), _) => Some(Arc::new(super::reference::read(path)?)),
        (None, Some(_)) if !quadratic => None,
        (None, Some(spec)) => {
            let refs = deepfield::orbit::references(&spec, &|_, _| {}, &cancel).map_err(|_| Failure::Cancelled)?;
            Some(Arc::new(SavedReferences { key: key_of(&spec), refs: Arc::new(refs) }))
        }
        (None, None) => None,
    };
    let reference_seconds = start.elapsed().as_secs_f64();
    let mut frame_seconds = 0.0;
    for k in units.clone() {
        let steps_out = frames - 1 - k;
        let zoom = match &map {
            Some(m) => scaled_zoom(&deepest, &factor, steps_out, m.circumradius),
            None => scaled_zoom(&deepest, &factor, steps_out, 1.0),
        };
        // The deepest keyframe is the scene as given (its zoom written as it was).
        let scene = match &map {
            None if steps_out == 0 => deepest.clone(),
            _ => super::scene::load_edited(&args.scene, |file| {
                file.view.zoom = Some(cli(zoom.clone()));
                file.view.radius = None;
                if let Some(m) = &map {
                    file.view.width = cli(m.strip.0 as i64);
                    file.view.height = cli(m.strip.1 as i64);
                    file.render.aa = cli(1);
                    file.view.exponential_map = Some(cli(m.factor));
                }
            })?,
        };
        let path = dir.join(format!("{k:05}.exr"));
        let t = Instant::now();
        write_frame(&scene, &path, simd, references.clone(), &cancel)?;
        frame_seconds += t.elapsed().as_secs_f64();
        if !args.quiet {
            // The zoom in short: the scene holds it exactly, in as many digits as it has.
            let short = Decimal::parse(&zoom).map_or(zoom.clone(), |z| scientific(z.log10_abs(), 3));
            eprintln!("keyframe {k} of {frames}: zoom {short} ({:.2} s)", t.elapsed().as_secs_f64());
        }
    }
    if let Some(center) = center.as_ref().filter(|_| units.end == frames) {
        let t = Instant::now();
        write_frame(center, &dir.join(CENTER), simd, references.clone(), &cancel)?;
        frame_seconds += t.elapsed().as_secs_f64();
    }
    if args.stats {
        let total = start.elapsed().as_secs_f64();
        use std::io::Write as _;
        let text = format!(
            "keyframes   {} of {frames} (factor {})\nreference   {reference_seconds:.3} s, once\nframes      {frame_seconds:.3} s\nwall time   {total:.3} s\n",
            units.len(),
            factor
        );
        std::io::stdout().lock().write_all(text.as_bytes()).map_err(|e| Failure::Runtime(e.into()))?;
    }
    Ok(())
}

/// The file of an exponential map that holds the flat view inside its deepest ring.
pub const CENTER: &str = "center.exr";

/// The layout of an exponential map for video frames of a scene's size.
struct ExponentialMap {
    /// Zoom factor per strip.
    factor: f64,
    /// The frames' circumscribed radius in units of their half-height.
    circumradius: f64,
    /// Strip columns and rows.
    strip: (u32, u32),
    /// Side of the square flat view inside the deepest ring, in pixels.
    center_side: u32,
}

impl ExponentialMap {
    fn of(scene: &Scene, factor: f64) -> ExponentialMap {
        let (w, h) = (scene.width as f64, scene.height as f64);
        let circumradius = w.hypot(h) / h;
        let strip = deepfield::field::projection::strip_size(scene.width, scene.height, scene.aa, factor.ln());
        ExponentialMap { factor, circumradius, strip, center_side: (h * circumradius / factor).ceil() as u32 }
    }
}

/// The zoom of the view `steps` factors shallower than the scene's whose radius is
/// `radius_scale` times the scene's, as decimal text (exact for a scale of 1).
fn scaled_zoom(scene: &Scene, factor: &Decimal, steps: u32, radius_scale: f64) -> String {
    let zoom = match &scene.scale {
        deepfield::orbit::Scale::Zoom(z) => z.to_rational(),
        deepfield::orbit::Scale::Radius(r) => Rational::from(2u32) / r.to_rational(),
    };
    let scale = if radius_scale == 1.0 {
        Rational::from(1u32)
    } else {
        Rational::try_from(1.0 / radius_scale).unwrap_or_else(|_| Rational::from(1u32))
    };
    let z = zoom * scale / factor.to_rational().pow(steps as u64);
    // Digits enough for any zoom of at most 1e6 steps of a factor above 1.
    Decimal::from_rational(&z, 40).text().to_string()
}

/// Renders one keyframe's raw data to `path` (EXR, the scene's channels).
fn write_frame(
    scene: &Scene,
    path: &Path,
    simd: deepfield::simd_level::SimdLevel,
    references: Option<Arc<SavedReferences>>,
    cancel: &std::sync::atomic::AtomicBool,
) -> Result<(), Failure> {
    let plan = super::engine_plan(scene)?;
    let perturbs = matches!(plan.kind, deepfield::render::engine::EngineKind::Perturb { .. });
    let engine = super::render::engine_text(&plan, simd);
    let targets = deepfield::io::output::Targets { png: None, exr: Some(path), tile: None, engine: &engine };
    let (mut writers, encoders) = deepfield::io::output::open(scene, targets).map_err(Failure::input)?;
    let prepare = |strip: &render::RenderedStrip| {
        Ok(encoders.encode(strip.row, &strip.rgb, &strip.planes, strip.samples.as_deref())?)
    };
    let options = Options {
        exr_channels: scene.channels,
        simd,
        references: if perturbs { references } else { None },
        ..Options::default()
    };
    render::render(scene, &plan, options, cancel, &|_| {}, &prepare, |_, encoded| Ok(writers.write(encoded)?))?;
    writers.finish().map_err(|e| Failure::Runtime(e.into()))
}
