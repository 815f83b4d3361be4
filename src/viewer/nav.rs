//! Navigation: the view as exact decimal centre and zoom, changed by pans, zooms about a
//! point and box zooms, with back/forward history. Pure functions, so that "the point under
//! the cursor stays fixed" is a property tested here rather than in pixels.
//!
//! Centres are decimal strings (as in scene files) updated with exact rational arithmetic
//! (malachite), so navigation works at any depth; they are rounded to a few digits finer
//! than the pixel spacing, which keeps them exact for rendering and short to store.

use malachite_base::num::arithmetic::traits::Pow;
use malachite_base::num::conversion::traits::FromSciString;
use malachite_base::rounding_modes::RoundingMode;
use malachite_q::Rational;

use crate::field::Transform;
use crate::formula::Formula;
use crate::num::{Decimal, DecimalError};
use crate::orbit::Scale;
use crate::scene::Scene;

/// A view: centre (decimal strings, [re, im]) and log10 of the zoom (the image height spans
/// 4 / zoom), with the scene's rotation and stretch, through which pixel moves become plane
/// moves (not persisted: it belongs to the scene, which sets it).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Nav {
    /// Centre, decimal strings.
    pub center: [String; 2],
    /// log10 of the zoom.
    pub log10_zoom: f64,
    /// The view's rotation and stretch.
    #[serde(skip)]
    pub transform: Transform,
}

impl Nav {
    /// The whole Mandelbrot set.
    pub fn home() -> Self {
        Self { center: ["-0.75".into(), "0".into()], log10_zoom: 1.6f64.log10(), transform: Transform::IDENTITY }
    }

    /// The whole set of `formula` in its Mandelbrot form (`julia` false) or Julia form: z² + c's
    /// Mandelbrot set as [`Nav::home`] shows it, any other set centred on 0 at zoom 1 (the
    /// image height spans -2..2, as Kalles Fraktaler's default view).
    pub fn default_for(formula: &Formula, julia: bool) -> Self {
        if formula.is_quadratic() && !julia {
            Self::home()
        } else {
            Self { center: ["0".into(), "0".into()], log10_zoom: 0.0, transform: Transform::IDENTITY }
        }
    }

    /// The view of a validated scene: its centre, zoom, rotation and stretch. A scene that
    /// leaves its scale out shows the whole set, as [`Nav::home`] does.
    pub fn of_scene(scene: &Scene) -> Self {
        let log10_zoom = match (&scene.file.view.zoom, &scene.file.view.radius, &scene.scale) {
            (None, None, _) => Self::home().log10_zoom,
            (_, _, Scale::Zoom(z)) => z.log10_abs(),
            (_, _, Scale::Radius(r)) => 2f64.log10() - r.log10_abs(),
        };
        let center = [scene.center[0].text().to_string(), scene.center[1].text().to_string()];
        Self { center, log10_zoom, transform: scene.transform }
    }

    /// The centre as exact decimals (an error for text that is not one, as a hand-edited
    /// saved session may hold).
    pub fn center_decimal(&self) -> Result<[Decimal; 2], DecimalError> {
        Ok([Decimal::parse(&self.center[0])?, Decimal::parse(&self.center[1])?])
    }

    /// The zoom as written into scene files ([`Nav::zoom_text`]), exact from here on (an
    /// error for a zoom that is not finite).
    pub fn scale(&self) -> Result<Scale, DecimalError> {
        Decimal::parse(&self.zoom_text()).map(Scale::Zoom)
    }

    /// Plane units per pixel for an image `height` pixels high, as f64 (0 past 1e-308: for
    /// the GPU paths' precision checks; navigation uses [`Nav::log10_spacing`] and exact
    /// rationals so it works at any depth).
    pub fn spacing(&self, height: f64) -> f64 {
        10f64.powf(self.log10_spacing(height))
    }

    /// log10 of the plane units per pixel: finite at any depth.
    pub fn log10_spacing(&self, height: f64) -> f64 {
        (4.0 / height).log10() - self.log10_zoom
    }

    /// Plane units per pixel as an exact rational (10^-floor(log10) times an f64 mantissa):
    /// pans and offsets at any depth go through this rather than through an f64 spacing that
    /// underflows past 1e-308.
    fn spacing_rational(&self, height: f64) -> Rational {
        let l = self.log10_spacing(height);
        let e = l.floor();
        let mantissa = Rational::try_from(10f64.powf(l - e)).unwrap_or_default();
        let scale = Rational::from(malachite_nz::natural::Natural::from(10u32).pow(e.abs() as u64));
        if e < 0.0 { mantissa / scale } else { mantissa * scale }
    }

    /// The zoom as a decimal string for a scene file.
    pub fn zoom_text(&self) -> String {
        crate::num::scientific(self.log10_zoom, 6)
    }

    /// Moves the centre by (dx, dy) pixels of an image `height` pixels high (x right, y down
    /// on screen; the imaginary axis points up).
    pub fn pan(&self, dx: f64, dy: f64, height: f64) -> Self {
        self.shifted_px(dx, dy, height)
    }

    /// Zooms by `factor` (> 1 zooms in) keeping the point `at` (pixels from the image centre,
    /// y down) where it is on screen.
    pub fn zoom_about(&self, factor: f64, at: [f64; 2], height: f64) -> Self {
        let k = 1.0 - 1.0 / factor;
        let mut out = self.shifted_px(at[0] * k, at[1] * k, height);
        out.log10_zoom += factor.log10();
        out.round(height)
    }

    /// Zooms to the box between pixel positions `a` and `b` (from the image centre, y down)
    /// of an image `width` x `height`: the box's centre becomes the centre and the box fits.
    pub fn zoom_box(&self, a: [f64; 2], b: [f64; 2], width: f64, height: f64) -> Self {
        let mid = [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0];
        let (bw, bh) = ((a[0] - b[0]).abs().max(1.0), (a[1] - b[1]).abs().max(1.0));
        let factor = (width / bw).min(height / bh);
        let mut out = self.pan(mid[0], mid[1], height);
        out.log10_zoom += factor.log10();
        out.round(height)
    }

    /// Where another view's centre lies from this one's, in pixels of an image `height`
    /// pixels high (x right, y up), exact up to the final rounding at any depth (for placing
    /// an old image under a new view while the new one renders).
    pub fn offset_px_of(&self, other: &Nav, height: f64) -> [f64; 2] {
        let s = self.spacing_rational(height);
        if s == Rational::default() {
            return [0.0; 2];
        }
        let d = |a: &String, b: &String| -> f64 { f64::rounding_from(&((rat(b) - rat(a)) / &s)) };
        self.transform.invert([d(&self.center[0], &other.center[0]), d(&self.center[1], &other.center[1])])
    }

    /// The point of the plane at pixel `at` (from the image centre, y down), as f64.
    pub fn point_at(&self, at: [f64; 2], height: f64) -> [f64; 2] {
        let s = self.spacing(height);
        let c = |t: &String| f64::rounding_from(&rat(t));
        let o = self.transform.apply([at[0], -at[1]]);
        [c(&self.center[0]) + o[0] * s, c(&self.center[1]) + o[1] * s]
    }

    /// The view moved by (dx, dy) pixels (y down), in exact rationals.
    fn shifted_px(&self, dx: f64, dy: f64, height: f64) -> Self {
        let s = self.spacing_rational(height);
        let add = |t: &String, d: f64| rat(t) + Rational::try_from(d).unwrap_or_default() * &s;
        let digits = self.digits(height);
        let o = self.transform.apply([dx, -dy]);
        let out = Self {
            center: [text(&add(&self.center[0], o[0]), digits), text(&add(&self.center[1], o[1]), digits)],
            log10_zoom: self.log10_zoom,
            transform: self.transform,
        };
        out.round(height)
    }

    /// Decimal digits after the point that keep the centre to 1/1000 of the pixel spacing.
    fn digits(&self, height: f64) -> u64 {
        (3.0 - self.log10_spacing(height)).ceil().max(1.0) as u64
    }

    /// Rounds the centre to 1/1000 of the pixel spacing (in decimal digits).
    fn round(&self, height: f64) -> Self {
        let digits = self.digits(height);
        let r = |t: &String| text(&rat(t), digits);
        Self {
            center: [r(&self.center[0]), r(&self.center[1])],
            log10_zoom: self.log10_zoom,
            transform: self.transform,
        }
    }
}

trait RoundingFrom {
    fn rounding_from(r: &Rational) -> f64;
}

impl RoundingFrom for f64 {
    fn rounding_from(r: &Rational) -> f64 {
        use malachite_base::num::conversion::traits::RoundingFrom as RF;
        <f64 as RF<&Rational>>::rounding_from(r, RoundingMode::Nearest).0
    }
}

fn rat(t: &str) -> Rational {
    let t = t.trim();
    Rational::from_sci_string(t.strip_prefix('+').unwrap_or(t)).unwrap_or_default()
}

/// `r` as a decimal string rounded to `digits` digits after the point (0: 60 digits, for
/// intermediate values that are rounded again), trailing zeros dropped.
fn text(r: &Rational, digits: u64) -> String {
    let digits = if digits == 0 { 60 } else { digits };
    crate::num::Decimal::from_rational(r, digits).text().to_string()
}

/// Back/forward history of views.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct History {
    back: Vec<Nav>,
    forward: Vec<Nav>,
}

impl History {
    /// Records `from` before moving to a new view (clears the forward list).
    pub fn push(&mut self, from: Nav) {
        if self.back.last() != Some(&from) {
            self.back.push(from);
        }
        self.forward.clear();
    }

    /// The previous view, if any; `current` goes onto the forward list.
    pub fn back(&mut self, current: Nav) -> Option<Nav> {
        let prev = self.back.pop()?;
        self.forward.push(current);
        Some(prev)
    }

    /// The next view, if any; `current` goes onto the back list.
    pub fn forward(&mut self, current: Nav) -> Option<Nav> {
        let next = self.forward.pop()?;
        self.back.push(current);
        Some(next)
    }

    /// Views behind and ahead.
    pub fn lens(&self) -> (usize, usize) {
        (self.back.len(), self.forward.len())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zoom_about_keeps_the_point_under_the_cursor() {
        let n = Nav { center: ["-0.75".into(), "0.1".into()], log10_zoom: 0.3, transform: Default::default() };
        let at = [123.0, -45.0];
        let before = n.point_at(at, 600.0);
        for factor in [2.0, 0.5, 1.1, 10.0] {
            let z = n.zoom_about(factor, at, 600.0);
            let after = z.point_at(at, 600.0);
            let s = z.spacing(600.0);
            assert!((before[0] - after[0]).abs() < s * 0.01 && (before[1] - after[1]).abs() < s * 0.01, "{factor}");
        }
    }

    #[test]
    fn deep_pans_are_exact() {
        let n = Nav {
            center: ["-1.7400623825793399052208441670658".into(), "0.0281753397792110489924115211361".into()],
            log10_zoom: 28.0,
            transform: Default::default(),
        };
        let p = n.pan(100.0, 0.0, 1000.0).pan(-100.0, 0.0, 1000.0);
        assert_eq!(p.center, n.center);
        let q = n.pan(1.0, 0.0, 1000.0);
        let d = n.offset_px_of(&q, 1000.0);
        assert!((d[0] - 1.0).abs() < 1e-9 && d[1] == 0.0, "{d:?}");
        assert!(q.center[0].len() > 30);
    }

    /// Past 1e-308 an f64 spacing is zero: pans, zooms about a point and offsets still move
    /// by the right number of pixels (1e-1086, the depth of a public benchmark location).
    #[test]
    fn pans_and_zooms_work_past_the_f64_range() {
        // 1080 digits: within the thousandth of a spacing the centre is rounded to.
        let digits = "7".repeat(1080);
        let n =
            Nav { center: [format!("-1.{digits}"), "0.001".into()], log10_zoom: 1086.0, transform: Default::default() };
        let p = n.pan(250.0, -40.0, 800.0);
        assert_ne!(p.center, n.center);
        let d = n.offset_px_of(&p, 800.0);
        assert!((d[0] - 250.0).abs() < 1e-3 && (d[1] - 40.0).abs() < 1e-3, "{d:?}");
        assert_eq!(p.pan(-250.0, 40.0, 800.0).center, n.center);
        // Zoom in by 2 about a point 100 px right of the centre: the centre moves 50 px.
        let z = n.zoom_about(2.0, [100.0, 0.0], 800.0);
        let d = n.offset_px_of(&z, 800.0);
        assert!((d[0] - 50.0).abs() < 1e-3 && d[1].abs() < 1e-3, "{d:?}");
        assert!((z.log10_zoom - 1086.0 - 2f64.log10()).abs() < 1e-12);
        // The centre keeps digits down to a thousandth of the spacing, no more.
        assert!(z.center[0].len() < 1100 + 10, "{}", z.center[0].len());
    }

    #[test]
    fn box_zoom_fits_the_box() {
        let n = Nav::home();
        let z = n.zoom_box([-100.0, -50.0], [100.0, 50.0], 800.0, 600.0);
        // A 200 x 100 box in an 800 x 600 image: limited by width, 4x.
        assert!((z.log10_zoom - n.log10_zoom - 4f64.log10()).abs() < 1e-12);
        assert_eq!(z.center, n.center);
    }

    #[test]
    fn default_views_show_the_whole_set_of_each_formula() {
        let burning = Formula::parse("burning-ship", Some(3)).unwrap();
        assert_eq!(Nav::default_for(&Formula::default(), false), Nav::home());
        for (f, julia) in [(Formula::default(), true), (burning, false), (burning, true)] {
            let n = Nav::default_for(&f, julia);
            assert_eq!((n.center, n.log10_zoom), (["0".to_string(), "0".to_string()], 0.0), "{f} {julia}");
        }
    }

    #[test]
    fn history_goes_back_and_forward() {
        let mut h = History::default();
        let a = Nav::home();
        let b = a.pan(10.0, 0.0, 600.0);
        h.push(a.clone());
        assert_eq!(h.back(b.clone()), Some(a.clone()));
        assert_eq!(h.forward(a.clone()), Some(b));
        assert_eq!(h.lens(), (1, 0));
    }

    /// A scene's view is its centre and zoom as written (a radius as the zoom it means; no
    /// scale, the whole set), and a view's centre and zoom are exact decimals for the typed
    /// scene; a zoom that is not finite is an error, never a stand-in value.
    #[test]
    fn views_of_scenes_and_back() {
        let scene = |text: &str| {
            let file = Scene::parse_file("t", text).unwrap();
            Scene::validate(file, "t", text, std::path::Path::new("."), crate::io::load_bitmap).unwrap()
        };
        let n = Nav::of_scene(&scene("version = 1\n[view]\ncenter = [\"-1.25\", \"0.02\"]\nzoom = \"900\"\n"));
        assert_eq!((n.center.clone(), n.log10_zoom), (["-1.25".to_string(), "0.02".to_string()], 900f64.log10()));
        assert_eq!(n.center_decimal().unwrap()[0], Decimal::parse("-1.25").unwrap());
        assert_eq!(n.scale().unwrap(), Scale::Zoom(Decimal::parse("9.000000e2").unwrap()));
        let r = Nav::of_scene(&scene("version = 1\n[view]\nradius = \"0.5\"\n"));
        assert!((r.log10_zoom - 4f64.log10()).abs() < 1e-15);
        assert_eq!(Nav::of_scene(&scene("version = 1\n")), Nav::home());
        assert!(Nav { log10_zoom: f64::NAN, ..Nav::home() }.scale().is_err());
        assert!(Nav { center: ["x".into(), "0".into()], ..Nav::home() }.center_decimal().is_err());
    }

    #[test]
    fn decimal_text() {
        assert_eq!(text(&rat("-0.75"), 5), "-0.75");
        assert_eq!(text(&rat("1e-3"), 2), "0");
        assert_eq!(text(&rat("123.456"), 2), "123.46");
        assert_eq!(text(&rat("-0.0001"), 3), "0");
    }
}
