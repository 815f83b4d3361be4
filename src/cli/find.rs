//! `deepfield find`: the lowest-period minibrot (or simplest Misiurewicz point) in a view,
//! printed as a scene centred and framed on it. z² + c has its own search
//! (`locate::search`); every other formula and hybrid the generic one (`locate::family`),
//! whose Misiurewicz search takes the Mandelbrot family at one power only.

use anyhow::anyhow;
use deepfield::locate::family::{self, Mini};
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
    let quadratic = scene.formula.is_quadratic();
    if !matches!(scene.family, FamilySpec::Mandelbrot) {
        return Err(Failure::Input(if quadratic {
            anyhow!("find searches the Mandelbrot set's parameter plane; this scene is a Julia set")
        } else {
            anyhow!(
                "find searches the parameter plane (the Mandelbrot form, c the pixel); this scene is {}'s Julia form, whose plane is z_0's",
                scene.formula
            )
        }));
    }
    // Misiurewicz points of the folded families and hybrids are refused before any work.
    if args.misiurewicz && !quadratic {
        family::check_conformal(scene.formula).map_err(|e| Failure::Input(e.into()))?;
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
                let (auto_k, auto_p) = if quadratic {
                    search::misiurewicz_limits(&center, disc)
                } else {
                    family::misiurewicz_limits(scene.formula, &center, disc)
                };
                (k.unwrap_or(auto_k), p.unwrap_or(auto_p))
            }
        };
        let (point, preperiod, period) = if quadratic {
            let m = search::misiurewicz_in_view(&center, disc, max_preperiod, max_period)
                .map_err(|e| Failure::Runtime(e.into()))?;
            (m.point, m.preperiod, m.period)
        } else {
            let m = family::misiurewicz_in_view(scene.formula, &center, disc, max_preperiod, max_period)
                .map_err(|e| Failure::Runtime(e.into()))?;
            (m.point, m.preperiod, m.period)
        };
        file.view.center = cli(decimals(&point));
        format!(
            "# deepfield find: Misiurewicz point of preperiod {preperiod} and period {period}, at the zoom of the view searched\n"
        )
    } else {
        let max_period = args.max_period.unwrap_or(100_000);
        let m = if quadratic {
            let m = search::minibrot_in_view(&center, disc, max_period).map_err(|e| Failure::Runtime(e.into()))?;
            Mini { nucleus: m.nucleus, period: m.period, size: m.size, angle: m.angle }
        } else {
            family::minibrot_in_view(scene.formula, &center, disc, max_period)
                .map_err(|e| Failure::Runtime(e.into()))?
        };
        file.view.center = cli(decimals(&m.nucleus));
        file.view.zoom = Some(cli(scientific(search::framing_log10_zoom(m.size), 6)));
        file.view.radius = None;
        // The scene is centred on the nucleus, so its reference is one period: any limit serves.
        let iterations = (m.period as u64 * ITERATIONS_PER_PERIOD).min(deepfield::scene::MAX_ITER_LIMIT);
        if (*file.iteration.max.get_ref() as u64) < iterations {
            file.iteration.max = cli(iterations as i64);
        }
        format!(
            "# deepfield find: {} of period {}, size {}, turned {:.1} degrees; framed at 2.2 sizes\n",
            if quadratic { "minibrot" } else { "mini" },
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
