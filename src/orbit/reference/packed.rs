//! A long reference orbit's tail, stored exactly in about a byte and a quarter per iteration.
//!
//! A reference orbit stored as f64 pairs takes 16 bytes per iteration, so the 1e9
//! iterations of a deep minibrot zoom would need 16 GB. Past the part stored densely, the
//! orbit is kept here instead, as the difference between each stored value and a
//! prediction of it:
//!
//! - The prediction of Z_n is one f64 step from the stored value of Z_(n-1):
//!   P = fl(Z_(n-1)^2 + c), with c rounded to f64, computed the same way by the writer and
//!   the reader (no fused multiply-add, so the same bits on every CPU).
//! - The difference is taken between the values' bit patterns, mapped so that consecutive
//!   floats are consecutive integers ([`ordered`]): it counts the units in the last place
//!   between P and Z_n, whatever their exponents and signs, and adding it back to P gives
//!   Z_n's bits exactly.
//! - The true orbit differs from P only by Z_(n-1)'s rounding times 2 Z_(n-1), c's rounding
//!   and the step's own roundings, a few units in the last place where |Z_n| is not much
//!   below |Z_(n-1)|^2 and |c| (more where it is, as the orbit passes near 0).
//!
//! So the values read back are exactly the values the dense store would hold: the engine's
//! results do not depend on how the orbit is stored. Each iteration takes one byte holding
//! both differences as 4-bit codes when both are small (zig-zag coded, 0–14), and a LEB128
//! number after it for each that is not (code 15). Values too small for f64 keep their
//! exponent in a sparse list, as the dense store's do.
//!
//! This is predictive coding of the exact values. Zhuoran's reference compression, as
//! Imagina and FractalShark use it, stores instead only the waypoints where an f64
//! re-iteration drifts from the orbit by more than a tolerance, which takes far less
//! memory but gives the samples a reference that is no longer the rounded orbit; the exact
//! form keeps every result the same bits as the dense store's.
//!
//! The tail is read in order only ([`Cursor`]): samples reach it by single steps from the
//! end of the dense part, cross it by single steps and by BLA steps of whole blocks (whose
//! table keeps a cursor at each block boundary: `bla::TailSteps`), and leave it by rebasing
//! to the orbit's start.

use crate::num::FloatExp;

/// A value too small for f64: its index and value.
pub type Tiny = (u32, [FloatExp; 2]);

/// Values below this magnitude (2^-300) are kept as `FloatExp` as well, densely or packed.
pub const TINY: f64 = 1.0 / (1u128 << 100) as f64 / (1u128 << 100) as f64 / (1u128 << 100) as f64;

/// f64 bits mapped to integers in the floats' order (consecutive floats differ by one).
#[inline(always)]
pub fn ordered(x: f64) -> i64 {
    let b = x.to_bits() as i64;
    b ^ (((b >> 63) as u64) >> 1) as i64
}

/// The inverse of [`ordered`].
#[inline(always)]
pub fn from_ordered(o: i64) -> f64 {
    f64::from_bits((o ^ (((o >> 63) as u64) >> 1) as i64) as u64)
}

/// The prediction of the value after `z`: one f64 step of z^2 + c.
#[inline(always)]
pub fn predict(z: [f64; 2], c: [f64; 2]) -> [f64; 2] {
    [(z[0] * z[0] - z[1] * z[1]) + c[0], (z[0] * z[1]) * 2.0 + c[1]]
}

/// Zig-zag code of a signed difference (0, -1, 1, -2, ... as 0, 1, 2, 3, ...).
#[inline(always)]
fn zigzag(d: i64) -> u64 {
    ((d << 1) ^ (d >> 63)) as u64
}

#[inline(always)]
fn unzigzag(u: u64) -> i64 {
    (u >> 1) as i64 ^ -((u & 1) as i64)
}

/// The largest difference coded in the leading byte's 4 bits; code 15 says a LEB128
/// number follows.
const SMALL: u64 = 14;
const ESCAPE: u8 = 15;

fn push_leb128(out: &mut Vec<u8>, mut v: u64) {
    loop {
        let b = (v & 0x7f) as u8;
        v >>= 7;
        if v == 0 {
            out.push(b);
            return;
        }
        out.push(b | 0x80);
    }
}

/// Reads a LEB128 number at `pos`; None past the end or past 64 bits.
#[inline]
fn read_leb128(bytes: &[u8], pos: &mut usize) -> Option<u64> {
    let mut v = 0u64;
    for shift in (0..64).step_by(7) {
        let b = *bytes.get(*pos)?;
        *pos += 1;
        v |= ((b & 0x7f) as u64) << shift;
        if b & 0x80 == 0 {
            return Some(v);
        }
    }
    None
}

/// The tail of an orbit: the values after a seed value, predictively coded.
#[derive(Debug, Clone, PartialEq)]
pub struct Packed {
    /// The parameter, rounded to f64 (the predictions' c).
    c: [f64; 2],
    /// Index of the seed: the last value before the tail (stored elsewhere).
    seed_index: u32,
    /// The seed value as stored (f64).
    seed: [f64; 2],
    /// The values' codes.
    bytes: Vec<u8>,
    /// The values too small for f64, in index order.
    tiny: Vec<Tiny>,
    /// The number of values coded.
    len: u32,
    /// The previous value while writing.
    prev: [f64; 2],
}

impl Packed {
    /// An empty tail after the value `seed` at `seed_index`, for the parameter `c`.
    pub fn new(c: [f64; 2], seed_index: u32, seed: [f64; 2]) -> Packed {
        Packed { c, seed_index, seed, bytes: Vec::new(), tiny: Vec::new(), len: 0, prev: seed }
    }

    /// Appends the next value: `z` as stored in f64, and `fe` when it is too small for f64.
    pub fn push(&mut self, z: [f64; 2], fe: Option<[FloatExp; 2]>) {
        let p = predict(self.prev, self.c);
        let d = [0, 1].map(|i| zigzag(ordered(z[i]).wrapping_sub(ordered(p[i]))));
        let code = |u: u64| if u <= SMALL { u as u8 } else { ESCAPE };
        self.bytes.push(code(d[0]) << 4 | code(d[1]));
        for u in d {
            if u > SMALL {
                push_leb128(&mut self.bytes, u - SMALL - 1);
            }
        }
        self.len += 1;
        if let Some(fe) = fe {
            self.tiny.push((self.seed_index + self.len, fe));
        }
        self.prev = z;
    }

    /// Frees the writer's spare capacity.
    pub fn shrink_to_fit(&mut self) {
        self.bytes.shrink_to_fit();
        self.tiny.shrink_to_fit();
    }

    /// Index of the seed (the tail holds the values after it).
    pub fn seed_index(&self) -> u32 {
        self.seed_index
    }

    /// Index of the last value (the seed's when the tail is empty).
    pub fn last(&self) -> u32 {
        self.seed_index + self.len
    }

    /// The parameter the predictions add (a file's part).
    pub fn c(&self) -> [f64; 2] {
        self.c
    }

    /// The values' codes (a file's part).
    pub fn codes(&self) -> &[u8] {
        &self.bytes
    }

    /// The values too small for f64 (a file's part).
    pub fn tiny(&self) -> &[Tiny] {
        &self.tiny
    }

    /// The number of values (a file's part).
    pub fn len(&self) -> u32 {
        self.len
    }

    /// True when it holds no value.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// A tail from a file's parts, checked by decoding it whole: None when the codes do not
    /// hold `len` finite values exactly or the tiny values are out of order or range.
    pub fn from_parts(
        c: [f64; 2],
        seed_index: u32,
        seed: [f64; 2],
        bytes: Vec<u8>,
        tiny: Vec<Tiny>,
        len: u32,
    ) -> Option<Packed> {
        let end = seed_index.checked_add(len)?;
        let ordered_tiny = tiny.windows(2).all(|w| w[0].0 < w[1].0);
        if !ordered_tiny || tiny.iter().any(|t| t.0 <= seed_index || t.0 > end) {
            return None;
        }
        let mut p = Packed { c, seed_index, seed, bytes, tiny, len, prev: seed };
        let mut cur = p.cursor();
        for _ in 0..len {
            cur.try_advance(&p)?;
            let tiny_here = p.tiny.get(cur.tiny).is_some_and(|t| t.0 == cur.m);
            let small = cur.z[0].abs().max(cur.z[1].abs()) < TINY;
            if !cur.z.iter().all(|x| x.is_finite()) || (tiny_here && !small) {
                return None;
            }
        }
        if cur.pos != p.bytes.len() {
            return None;
        }
        p.prev = cur.z;
        Some(p)
    }

    /// A cursor at the seed.
    pub fn cursor(&self) -> Cursor {
        Cursor { m: self.seed_index, z: self.seed, pos: 0, tiny: 0 }
    }

    /// Bytes of memory the tail uses.
    pub fn bytes(&self) -> usize {
        self.bytes.capacity() + self.tiny.capacity() * std::mem::size_of::<Tiny>()
    }
}

/// A reader of a tail, in order: the index and value it stands at.
#[derive(Debug, Clone, Copy)]
pub struct Cursor {
    m: u32,
    z: [f64; 2],
    pos: usize,
    tiny: usize,
}

impl Cursor {
    /// The index it stands at.
    #[inline(always)]
    pub fn index(&self) -> u32 {
        self.m
    }

    /// The value there, rounded to f64 (zero or subnormal for tiny values).
    #[inline(always)]
    pub fn get(&self) -> [f64; 2] {
        self.z
    }

    /// The value there at full range (past the seed: the seed's own exponent, when it is
    /// tiny, is in the dense store's list).
    #[inline]
    pub fn get_fe(&self, packed: &Packed) -> [FloatExp; 2] {
        // The tiny value at this index, if any: the list is in index order and the cursor
        // keeps its place in it.
        if let Some(&(i, v)) = packed.tiny.get(self.tiny)
            && i == self.m
        {
            return v;
        }
        [FloatExp::from(self.z[0]), FloatExp::from(self.z[1])]
    }

    /// Moves to the next value; false at the tail's end.
    #[inline(always)]
    pub fn advance(&mut self, packed: &Packed) -> bool {
        self.m < packed.last() && self.try_advance(packed).is_some()
    }

    #[inline(always)]
    fn try_advance(&mut self, packed: &Packed) -> Option<()> {
        let head = *packed.bytes.get(self.pos)?;
        self.pos += 1;
        let mut diff = |code: u8| -> Option<u64> {
            if code == ESCAPE {
                Some(read_leb128(&packed.bytes, &mut self.pos)?.checked_add(SMALL + 1)?)
            } else {
                Some(code as u64)
            }
        };
        let d = [diff(head >> 4)?, diff(head & 15)?];
        let p = predict(self.z, packed.c);
        self.z = [0, 1].map(|i| from_ordered(ordered(p[i]).wrapping_add(unzigzag(d[i]))));
        if packed.tiny.get(self.tiny).is_some_and(|t| t.0 <= self.m) {
            self.tiny += 1;
        }
        self.m += 1;
        Some(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ordered_is_monotone_and_inverts() {
        let xs = [-f64::MAX, -1.5, -f64::MIN_POSITIVE, -0.0, 0.0, 5e-324, 1.0, 1.0000000000000002, f64::MAX];
        for w in xs.windows(2) {
            assert!(ordered(w[0]) <= ordered(w[1]), "{} {}", w[0], w[1]);
        }
        assert_eq!(ordered(1.0000000000000002) - ordered(1.0), 1);
        assert_eq!(ordered(5e-324) - ordered(0.0), 1);
        for x in xs {
            assert_eq!(from_ordered(ordered(x)).to_bits(), x.to_bits());
        }
        for d in [0i64, -1, 1, -7, 7, 14, -15, i64::MAX, i64::MIN] {
            assert_eq!(unzigzag(zigzag(d)), d);
        }
    }

    /// Any values, predictable or not (a chaotic orbit's, then noise with far-off
    /// exponents, signs and zeros), read back to the same bits, and tiny values keep theirs.
    #[test]
    fn values_read_back_exactly() {
        // The rabbit's parameter: the orbit stays bounded.
        let c = [-0.12256116687665362, 0.7448617666197442];
        let mut values = Vec::new();
        let mut z = [0.1, 0.2];
        for _ in 0..3000 {
            z = predict(z, c);
            // A few ulps off the prediction, as a rounded orbit is.
            values.push([z[0] * (1.0 + 3e-16), z[1]]);
        }
        let mut state = 0x9e3779b97f4a7c15u64;
        for _ in 0..2000 {
            state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            let v = f64::from_bits(state >> 1 & !(0x7ffu64 << 52) | ((state >> 53) % 2046 + 1) << 52);
            values.push([if state & 1 == 0 { v } else { -v }, if state & 2 == 0 { 0.0 } else { -0.0 }]);
        }
        let mut p = Packed::new(c, 41, [0.1, 0.2]);
        let tiny_at = 41 + 1500;
        // A value tiny in f64 (zero) with its exponent kept aside.
        values[tiny_at as usize - 42] = [0.0, 0.0];
        for (k, v) in values.iter().enumerate() {
            let fe = (41 + 1 + k as u32 == tiny_at).then(|| [FloatExp::from(1e-300).mul_f64(1e-300), FloatExp::ZERO]);
            p.push(*v, fe);
        }
        assert_eq!(p.last(), 41 + values.len() as u32);
        let mut cur = p.cursor();
        assert_eq!((cur.index(), cur.get()), (41, [0.1, 0.2]));
        for v in &values {
            assert!(cur.advance(&p));
            assert_eq!(cur.get().map(f64::to_bits), v.map(f64::to_bits), "at {}", cur.index());
            let fe = cur.get_fe(&p);
            if cur.index() == tiny_at {
                assert!((fe[0].log2() + 1993.2).abs() < 0.1);
            } else {
                assert_eq!(fe[0].to_f64().to_bits(), v[0].to_bits());
            }
        }
        assert!(!cur.advance(&p));
        let (bytes, tiny, len) = (p.codes(), p.tiny(), p.len());
        let again = Packed::from_parts(c, 41, [0.1, 0.2], bytes.to_vec(), tiny.to_vec(), len).unwrap();
        assert_eq!(again, p);
        assert!(Packed::from_parts(c, 41, [0.1, 0.2], bytes[..bytes.len() - 1].to_vec(), tiny.to_vec(), len).is_none());
        assert!(Packed::from_parts(c, 41, [0.1, 0.2], bytes.to_vec(), tiny.to_vec(), len - 1).is_none());
    }
}
