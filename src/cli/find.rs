//! `deepfield find`: the lowest-period minibrot (or simplest Misiurewicz point) in a view,
//! printed as a scene centred and framed on it.

use anyhow::anyhow;
use deepfield::locate::search;
use deepfield::num::bigcomplex::BigC;
use deepfield::num::{Decimal, FloatExp, scientific};
use deepfield::scene::FamilySpec;
use deepfield::scene::raw::cli;

use super::Failure;
use super::args::FindArgs;

/// Iterations per period given to a minibrot's scene: exterior pixels near a minibrot of
/// period p escape after a few dozen multiples of p.
const ITERATIONS_PER_PERIOD: u64 = 64;

/// Runs `deepfield find`.
pub fn run(args: FindArgs) -> Result<(), Failure> {
    let scene = super::scene::load(&args.scene)?;
    if !scene.formula.is_quadratic() {
        return Err(Failure::Input(anyhow!(
            "find searches z^2 + c's parameter plane (nuclei by Newton's method on its quadratic orbit, Misiurewicz points); this scene's formula is {}",
            scene.formula
        )));
    }
    if !matches!(scene.family, FamilySpec::Mandelbrot) {
        return Err(Failure::Input(anyhow!(
            "find searches the Mandelbrot set's parameter plane; this scene is a Julia set"
        )));
    }
    // Opened first, so an unwritable path fails before the search.
    let out = match &args.output {
        Some(path) => Some(deepfield::io::AtomicFile::create(path).map_err(Failure::input)?),
        None => None,
    };
    // The disc searched: the view's half-diagonal about its centre, at the precision the
    // view needs plus a margin.
    let aspect = scene.width as f64 / scene.height as f64;
    let log10_disc = scene.log10_radius + 0.5 * (1.0 + aspect * aspect).log10();
    let (center, disc) = search::disc(&scene.center, log10_disc);
    let mut file = scene.file.clone();
    let header = if args.misiurewicz {
        // Limits not given follow the view's lowest minibrot period.
        let (max_preperiod, max_period) = match (args.max_preperiod, args.max_period) {
            (Some(k), Some(p)) => (k, p),
            (k, p) => {
                let (auto_k, auto_p) = search::misiurewicz_limits(&center, disc);
                (k.unwrap_or(auto_k), p.unwrap_or(auto_p))
            }
        };
        let m = search::misiurewicz_in_view(&center, disc, max_preperiod, max_period)
            .map_err(|e| Failure::Runtime(e.into()))?;
        file.view.center = cli(decimals(&m.point));
        format!(
            "# deepfield find: Misiurewicz point of preperiod {} and period {}, at the zoom of the view searched\n",
            m.preperiod, m.period
        )
    } else {
        let m = search::minibrot_in_view(&center, disc, args.max_period.unwrap_or(100_000))
            .map_err(|e| Failure::Runtime(e.into()))?;
        file.view.center = cli(decimals(&m.nucleus));
        file.view.zoom = Some(cli(scientific(search::framing_log10_zoom(m.size), 6)));
        file.view.radius = None;
        // The scene is centred on the nucleus, so its reference is one period: any limit serves.
        let iterations = (m.period as u64 * ITERATIONS_PER_PERIOD).min(deepfield::scene::MAX_ITER_LIMIT);
        if (*file.iteration.max.get_ref() as u64) < iterations {
            file.iteration.max = cli(iterations as i64);
        }
        format!(
            "# deepfield find: minibrot of period {}, size {}, turned {:.1} degrees; framed at 2.2 sizes\n",
            m.period,
            sci(m.size, 3),
            m.angle.to_degrees()
        )
    };
    let text = header + &toml::to_string(&file).map_err(|e| Failure::Runtime(e.into()))?;
    match out {
        Some(opened) => super::commit_text(opened, &text),
        None => {
            use std::io::Write as _;
            std::io::stdout().lock().write_all(text.as_bytes()).map_err(|e| Failure::Runtime(e.into()))
        }
    }
}

/// A found point's parts as decimal text, every bit of its precision kept.
fn decimals(p: &BigC) -> [String; 2] {
    p.to_decimals(3).map(|d: Decimal| d.text().to_string())
}

/// A positive FloatExp in scientific notation at any exponent.
fn sci(x: FloatExp, digits: usize) -> String {
    scientific(x.log2() * std::f64::consts::LOG10_2, digits)
}
