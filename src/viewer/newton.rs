//! Newton zooming: from a point of the view, the view of the minibrot (or Misiurewicz
//! point) nearest it, found by [`crate::locate::search`] in big floats. Pure: a view and a
//! pixel in, a view out; the app runs it on a thread of its own.
//!
//! The search disc is a quarter of the view's height about the pixel. A minibrot's view is
//! framed at its size (the whole minibrot in the window) or, with a step factor, zoomed by
//! that factor towards its nucleus without passing the framing zoom, so a user can keep
//! pressing the key to approach it. A Misiurewicz point's view is centred on it and zoomed
//! by the factor (4 when none is set: the structure there looks alike at every depth).

use crate::locate::search;
use crate::num::Decimal;
use crate::num::bigcomplex::BigC;

use super::nav::Nav;

/// What to look for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Target {
    /// The lowest-period minibrot.
    Minibrot,
    /// The simplest Misiurewicz point.
    Misiurewicz,
}

/// Largest minibrot period searched.
const MAX_PERIOD: u32 = 100_000;

/// The view of the `target` nearest pixel `at` (from the image centre, y down) of `nav`
/// (an image `height` pixels high), and a line saying what was found. `factor` > 1 zooms by
/// that much towards it instead of framing it.
pub fn newton_zoom(nav: &Nav, at: [f64; 2], height: f64, target: Target, factor: f64) -> Result<(Nav, String), String> {
    let here = nav.pan(at[0], at[1], height);
    let log10_disc = nav.log10_spacing(height) + (height / 4.0).log10();
    let decimal = |t: &String| Decimal::parse(t).map_err(|e| e.to_string());
    let (c, disc) = search::disc(&[decimal(&here.center[0])?, decimal(&here.center[1])?], log10_disc);
    let text = |p: &BigC| p.to_decimals(3).map(|d| d.text().to_string());
    match target {
        Target::Minibrot => {
            let m = search::minibrot_in_view(&c, disc, MAX_PERIOD).map_err(|e| e.to_string())?;
            let framing = search::framing_log10_zoom(m.size);
            let log10_zoom = if factor > 1.0 { (nav.log10_zoom + factor.log10()).min(framing) } else { framing };
            let size = m.size.log2() * std::f64::consts::LOG10_2;
            let line = format!("minibrot of period {}, size 1e{size:.1}", m.period);
            Ok((Nav { center: text(&m.nucleus), log10_zoom, transform: nav.transform }, line))
        }
        Target::Misiurewicz => {
            let (max_preperiod, max_period) = search::misiurewicz_limits(&c, disc);
            let m = search::misiurewicz_in_view(&c, disc, max_preperiod, max_period).map_err(|e| e.to_string())?;
            let step = if factor > 1.0 { factor } else { 4.0 };
            let line = format!("Misiurewicz point of preperiod {} and period {}", m.preperiod, m.period);
            Ok((
                Nav { center: text(&m.point), log10_zoom: nav.log10_zoom + step.log10(), transform: nav.transform },
                line,
            ))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// From a view of the antenna with the pointer near the airplane: its nucleus
    /// (-1.7548776662466927..., published), framed; with a factor, a zoom by that factor.
    #[test]
    fn finds_the_airplane_and_frames_it() {
        let nav = Nav { center: ["-1.7".into(), "0".into()], log10_zoom: 1.0, transform: Default::default() };
        // 0.05 to the left of the centre: 0.05 / (4 / 10 / 600) = 75 px.
        let (framed, line) = newton_zoom(&nav, [-75.0, 0.0], 600.0, Target::Minibrot, 0.0).unwrap();
        assert!(line.contains("period 3"), "{line}");
        assert!(framed.center[0].starts_with("-1.754877666246692760049508896358"), "{:?}", framed.center);
        // Size ~0.019: framed at 2.2 sizes, zoom ~ 2 / 0.042 ~ 48.
        assert!((framed.log10_zoom - 48f64.log10()).abs() < 0.15, "{}", framed.log10_zoom);
        let (step, _) = newton_zoom(&nav, [-75.0, 0.0], 600.0, Target::Minibrot, 2.0).unwrap();
        assert_eq!(step.center, framed.center);
        assert!((step.log10_zoom - 1.0 - 2f64.log10()).abs() < 1e-12);
    }

    #[test]
    fn finds_a_misiurewicz_point_and_refuses_empty_views() {
        // c = i (preperiod 2, period 2), 0.02 above a view centre at 0.01 + 0.98i.
        let nav = Nav { center: ["0.01".into(), "0.98".into()], log10_zoom: 1.3, transform: Default::default() };
        let (at, line) = newton_zoom(&nav, [0.0, -60.0], 600.0, Target::Misiurewicz, 0.0).unwrap();
        assert!(line.contains("preperiod 2 and period 2"), "{line}");
        let part = |k: usize| at.center[k].parse::<f64>().unwrap();
        assert!(part(0).abs() < 1e-15 && (part(1) - 1.0).abs() < 1e-15, "{:?}", at.center);
        let far = Nav { center: ["0.6".into(), "0.6".into()], log10_zoom: 6.0, transform: Default::default() };
        assert!(newton_zoom(&far, [0.0, 0.0], 600.0, Target::Minibrot, 0.0).is_err());
    }

    /// At depth the search's limits follow the view's minibrot period: Kalles Fraktaler's
    /// 1e1086 benchmark location seen at 1e30 holds Misiurewicz points of periods in the
    /// hundreds (fixed limits of 64 found none there).
    #[test]
    fn finds_a_misiurewicz_point_at_depth() {
        let text = include_str!("../../scenes/bench-e1086.toml");
        let centre = |key: usize| {
            let line = text.lines().find(|l| l.starts_with("center")).expect("centre");
            line.split('"').nth(2 * key + 1).expect("part").to_string()
        };
        let nav = Nav { center: [centre(0), centre(1)], log10_zoom: 30.0, transform: Default::default() };
        let (at, line) = newton_zoom(&nav, [0.0, 0.0], 600.0, Target::Misiurewicz, 0.0).unwrap();
        let period: u32 = line.rsplit(' ').next().and_then(|p| p.parse().ok()).expect("a period");
        assert!(period > 64, "{line}");
        assert!((at.log10_zoom - 30.0 - 4f64.log10()).abs() < 1e-12);
    }
}
