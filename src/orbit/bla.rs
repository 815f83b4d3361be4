//! Bilinear approximation (BLA): tables of linear steps that skip runs of iterations.
//!
//! While a delta is small against the reference, the perturbed step
//! z -> 2 Z_m z + z^2 + c is linear to a relative accuracy ε: z -> A z + B c with
//! A = 2 Z_m, B = 1 (Mandelbrot; B = 0 for Julia, whose delta lives in z_0), valid while
//! |z| < R = ε |Z_m| (then |z^2| <= ε |2 Z_m z| / 2). Two consecutive steps x then y compose:
//! A = A_y A_x, B = A_y B_x + B_y, and the composite is valid while z is valid for x and x's
//! image is valid for y: R = min(R_x, max(0, (R_y - |B_x| |c|max) / |A_x|)), |c|max the
//! largest pixel offset. Merging pairs level by level gives a binary tree: level k holds
//! steps of 2^k iterations starting at origin + i 2^k, so at any index the loop tries the
//! longest aligned step first. (After Zhuoran's BLA and Claude Heiland-Allen's notes on it.)
//!
//! Tables are built in `FloatExp` (radii below 1e-300 and products above 1e300 are normal at
//! depth) and converted to f64 for the f64 phase of the loop, where entries f64 cannot hold
//! are marked unusable. Level 0 (single steps) is not stored: a single linear step costs as
//! much as the perturbed step it would replace.

use super::reference::Reference;
use crate::num::real::{cadd, cmul, norm2};
use crate::num::{FloatExp, Real};

/// One linear step z -> a z + b c over 2^level iterations, valid while |z|^2 < r2.
#[derive(Debug, Clone, Copy)]
pub struct Bla<T> {
    /// Multiplier of the delta.
    pub a: [T; 2],
    /// Multiplier of the pixel offset.
    pub b: [T; 2],
    /// Squared validity radius (negative: never valid).
    pub r2: T,
}

/// Levels 1.. of the tree for one reference orbit.
#[derive(Debug, Clone)]
pub struct BlaTable<T> {
    origin: u32,
    /// levels[k] holds steps of 2^(k+1) iterations.
    levels: Vec<Vec<Bla<T>>>,
    /// The squared radii again, by start index: for index i (from the origin) the radii of
    /// its steps of every level, shortest first, side by side (see [`column`]). A lookup then
    /// reads one cache line instead of one per level.
    radii: Vec<T>,
}

/// Where index i's radii start in `radii` and how many there are, for `top` levels. Index
/// i starts steps of levels k < tz(i) (index 0 of all `top`), and sum_{j=1}^{n} tz(j) =
/// n - popcount(n) (Legendre), so the columns before i's take top + (i - 1) - popcount(i - 1).
#[inline]
fn column(i: u32, top: usize) -> (usize, usize) {
    if i == 0 {
        (0, top)
    } else {
        let before = top + (i - 1) as usize - (i - 1).count_ones() as usize;
        (before, (i.trailing_zeros() as usize).min(top))
    }
}

/// The column layout of `levels`' radii; `never` marks a step past a level's end.
fn columns<T: Real>(levels: &[Vec<Bla<T>>], never: T) -> Vec<T> {
    let top = levels.len();
    let count = levels.first().map_or(0, |l| 2 * l.len() as u32);
    let mut radii = Vec::with_capacity(count as usize + top);
    for i in 0..count {
        let (start, n) = column(i, top);
        debug_assert_eq!(start, radii.len());
        radii.extend((0..n).map(|k| levels[k].get((i >> (k + 1)) as usize).map_or(never, |e| e.r2)));
    }
    radii
}

/// An entry under construction: radius kept unsquared for merging.
#[derive(Clone, Copy)]
struct Node {
    a: [FloatExp; 2],
    b: [FloatExp; 2],
    r: FloatExp,
}

fn cabs(v: [FloatExp; 2]) -> FloatExp {
    norm2(v).sqrt()
}

fn merge(x: &Node, y: &Node, dc_max: FloatExp) -> Node {
    let a = cmul(y.a, x.a);
    let b = cadd(cmul(y.a, x.b), y.b);
    let through = (y.r - cabs(x.b) * dc_max).max(FloatExp::ZERO);
    let ax = cabs(x.a);
    let ry = if ax.is_zero() { y.r.max(FloatExp::ZERO) } else { through / ax };
    Node { a, b, r: x.r.min(ry) }
}

impl BlaTable<FloatExp> {
    /// Builds the table for steps from index `origin` of `orbit`. `epsilon` is the relative
    /// tolerance, `dc_max` the largest |c offset| (zero for Julia), `mandelbrot` sets B = 1.
    pub fn build(orbit: &Reference, origin: u32, mandelbrot: bool, epsilon: f64, dc_max: FloatExp) -> Self {
        let one = if mandelbrot { FloatExp::ONE } else { FloatExp::ZERO };
        let mut level: Vec<Node> = (origin..orbit.last())
            .map(|m| {
                let z = orbit.get_fe(m);
                let a = [z[0].ldexp(1), z[1].ldexp(1)];
                Node { a, b: [one, FloatExp::ZERO], r: cabs(z).mul_f64(epsilon) }
            })
            .collect();
        let mut levels = Vec::new();
        while level.len() >= 2 {
            level = level.chunks_exact(2).map(|p| merge(&p[0], &p[1], dc_max)).collect();
            levels.push(level.iter().map(|n| Bla { a: n.a, b: n.b, r2: n.r * n.r }).collect());
        }
        let radii = columns(&levels, FloatExp::ZERO);
        BlaTable { origin, levels, radii }
    }

    /// The same table for the f64 loop; entries f64 cannot hold are never valid.
    pub fn to_f64(&self) -> BlaTable<f64> {
        let conv = |e: &Bla<FloatExp>| {
            let a = [e.a[0].to_f64(), e.a[1].to_f64()];
            let b = [e.b[0].to_f64(), e.b[1].to_f64()];
            let ok = a.iter().chain(&b).all(|v| v.is_finite());
            Bla { a, b, r2: if ok { e.r2.to_f64() } else { -1.0 } }
        };
        let levels: Vec<Vec<Bla<f64>>> = self.levels.iter().map(|l| l.iter().map(conv).collect()).collect();
        let radii = columns(&levels, -1.0);
        BlaTable { origin: self.origin, levels, radii }
    }
}

impl<T: Real> BlaTable<T> {
    /// The longest valid step at index `m` for a delta with |z|^2 = `z2`, at most `budget`
    /// iterations long; returns the step and its length. A longer step starting at the same
    /// index is valid on a subset of where a shorter one is (its radius is a minimum over
    /// more steps), so the search climbs from the shortest step and stops at the first that
    /// fails: one probe where nothing is valid, which is the common case.
    #[inline]
    pub fn lookup(&self, m: u32, z2: T, budget: u32) -> Option<(&Bla<T>, u32)> {
        let i = m.checked_sub(self.origin)?;
        let (start, n) = column(i, self.levels.len());
        let radii = self.radii.get(start..start + n)?;
        let mut k = 0;
        while k < n && z2 < radii[k] && (2u32 << k) <= budget {
            k += 1;
        }
        // Steps past a level's end have radius "never", so levels[k - 1] holds this one.
        (k > 0).then(|| (&self.levels[k - 1][(i >> k) as usize], 1u32 << k))
    }

    /// The largest squared radius of the shortest steps: no step of any length is valid for
    /// a delta with |z|^2 at or above it (a longer step's radius is at most its first
    /// half's).
    pub fn max_r2(&self) -> Option<T> {
        let first = self.levels.first()?;
        first.iter().map(|e| e.r2).reduce(|a, b| if b > a { b } else { a })
    }

    /// Bytes of memory the table uses.
    pub fn bytes(&self) -> usize {
        self.levels.iter().map(|l| l.capacity() * std::mem::size_of::<Bla<T>>()).sum::<usize>()
            + self.radii.capacity() * std::mem::size_of::<T>()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use malachite_float::Float;
    use std::sync::atomic::AtomicBool;

    #[test]
    fn merged_step_matches_iterated_linear_steps() {
        // Reference at c = -0.75 + 0.1i; one merged step over 4 iterations equals four
        // linearised steps applied in turn.
        let c = [Float::from(-0.75), Float::from(0.1)];
        let z0 = [Float::from(0.0), Float::from(0.0)];
        let r = Reference::compute(&z0, &c, 64, 1e10, 128, &|_| {}, &AtomicBool::new(false)).unwrap();
        let dc = [FloatExp::from(1e-12), FloatExp::from(-2e-12)];
        let t = BlaTable::build(&r, 1, true, 1e-6, cabs(dc));
        let (e, len) = t.lookup(1, FloatExp::from(1e-24), 4).expect("valid");
        assert_eq!(len, 4);
        let mut z = [FloatExp::from(3e-12), FloatExp::ZERO];
        let start = z;
        for m in 1..5 {
            let zm = r.get_fe(m);
            z = cadd(cmul([zm[0].ldexp(1), zm[1].ldexp(1)], z), dc);
        }
        let lin = cadd(cmul(e.a, start), cmul(e.b, dc));
        for k in 0..2 {
            assert!(((lin[k] - z[k]).abs().to_f64()) <= 1e-14 * cabs(z).to_f64());
        }
        // Too large a delta gets no step; an unaligned index gets none longer than allowed.
        assert!(t.lookup(1, FloatExp::from(1.0), 64).is_none());
        assert_eq!(t.lookup(3, FloatExp::from(1e-24), 64).map(|x| x.1), Some(2));
        assert!(t.lookup(2, FloatExp::from(1e-24), 64).is_none());
    }
}
