//! Reference files: a view's reference orbits computed once (`deepfield reference`) and read
//! by every render that shares them (`render --reference`: the work units of one poster,
//! the frames of one zoom), so no machine computes them again.
//!
//! The format (version 3, little-endian throughout):
//!
//! ```text
//! b"DFREFORB"                       magic, 8 bytes
//! u32 version (3; versions 1, without the packed part, and 2, without the cycle, are read too)
//! u32 key length, key (UTF-8)       what determined the orbits: `name = value` lines
//! u32 number of orbits (1 or 2)
//! per orbit:
//!   u64 bits, u8 escaped, u32 period (0: none)
//!   u32 cycle (0: none; see `Reference::cycle`)
//!   u64 n, n x (f64 re, f64 im)     Z_0 .. Z_(n-1) as f64, the part stored densely
//!   tiny list                       its values too small for f64, with their exponents:
//!     u64 m, m x (u32 index, f64 re mantissa, i32 re exponent, f64 im mantissa, i32 im exponent)
//!   u8 packed (0 or 1); if 1, the packed tail after Z_(n-1) (see `orbit::reference::packed`):
//!     f64 c re, f64 c im, u32 values, u64 b, b bytes of codes, tiny list
//! u32 CRC-32 (IEEE) of everything before it
//! ```
//!
//! The key holds the centre and Julia parameter as written, the iteration limit, escape
//! radius, precision and the period test's threshold. A file serves a view whose centre,
//! parameter, limit and escape radius are the same and whose precision is at most the
//! file's; the orbits then equal those the view would compute (bit for bit when the
//! precision and threshold match too, which [`SavedReferences::identical_for`] tells).
//! Every length is checked against the bytes that remain before anything is allocated.

use std::sync::Arc;

use crate::num::FloatExp;

use super::reference::Reference;
use super::reference::packed::{Packed, Tiny};
use super::{DeepSpec, reference_bits};

const MAGIC: &[u8; 8] = b"DFREFORB";
const VERSION: u32 = 3;

/// Why a reference file cannot be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum SavedError {
    /// Not a reference file, or damaged.
    #[error("not a deepfield reference file: {0}")]
    Format(String),
    /// A reference file of a version this build does not read.
    #[error("reference file version {0}; this deepfield reads versions 1 to {VERSION}")]
    Version(u32),
    /// The file's orbits are not this view's.
    #[error("this reference file does not serve the scene: {0}")]
    Mismatch(String),
}

/// Reference orbits read from (or to be written to) a file, with the key that made them.
#[derive(Debug, Clone)]
pub struct SavedReferences {
    /// `name = value` lines.
    pub key: String,
    /// The orbits.
    pub refs: Arc<Vec<Reference>>,
}

/// The key of a view's references.
pub fn key_of(spec: &DeepSpec) -> String {
    let julia = spec.julia.as_ref().map_or("none".to_string(), |c| format!("{} {}", c[0], c[1]));
    let periodic =
        super::periodic_below(spec).map_or("none".to_string(), |t| format!("{} {}", t.mantissa(), t.exponent()));
    format!(
        "center = {} {}\njulia = {julia}\nmax_iter = {}\nescape_radius = {}\nbits = {}\nperiodic_below = {periodic}\n",
        spec.center[0],
        spec.center[1],
        spec.max_iter,
        spec.escape_radius,
        reference_bits(spec)
    )
}

fn field<'a>(key: &'a str, name: &str) -> Option<&'a str> {
    key.lines().find_map(|l| l.strip_prefix(name)?.strip_prefix(" = "))
}

impl SavedReferences {
    /// Checks that these orbits serve `spec`: the same centre, parameter, iteration limit
    /// and escape radius, and at least the precision it needs.
    pub fn serves(&self, spec: &DeepSpec) -> Result<(), SavedError> {
        let want = key_of(spec);
        for name in ["center", "julia", "max_iter", "escape_radius"] {
            let (a, b) = (field(&self.key, name), field(&want, name));
            if a != b {
                return Err(SavedError::Mismatch(format!(
                    "its {name} is {}, the scene's {}",
                    a.unwrap_or("missing"),
                    b.unwrap_or("missing")
                )));
            }
        }
        let bits = |k: &str| field(k, "bits").and_then(|b| b.parse::<u64>().ok()).unwrap_or(0);
        if bits(&self.key) < bits(&want) {
            return Err(SavedError::Mismatch(format!(
                "its orbits have {} bits, the scene's view needs {} (it is deeper than the view the file was made for)",
                bits(&self.key),
                bits(&want)
            )));
        }
        Ok(())
    }

    /// True when these are exactly the orbits `spec` would compute (same key).
    pub fn identical_for(&self, spec: &DeepSpec) -> bool {
        self.key == key_of(spec)
    }

    /// The file's bytes.
    pub fn encode(&self) -> Vec<u8> {
        let mut out = Vec::new();
        out.extend_from_slice(MAGIC);
        out.extend_from_slice(&VERSION.to_le_bytes());
        out.extend_from_slice(&(self.key.len() as u32).to_le_bytes());
        out.extend_from_slice(self.key.as_bytes());
        out.extend_from_slice(&(self.refs.len() as u32).to_le_bytes());
        for r in self.refs.iter() {
            let (z, tiny) = r.parts();
            out.extend_from_slice(&r.bits().to_le_bytes());
            out.push(r.escaped() as u8);
            out.extend_from_slice(&r.period().unwrap_or(0).to_le_bytes());
            out.extend_from_slice(&r.cycle().unwrap_or(0).to_le_bytes());
            out.extend_from_slice(&(z.len() as u64).to_le_bytes());
            for p in z {
                out.extend_from_slice(&p[0].to_le_bytes());
                out.extend_from_slice(&p[1].to_le_bytes());
            }
            write_tiny(&mut out, tiny);
            match r.packed() {
                None => out.push(0),
                Some(p) => {
                    let (c, codes, tiny, len) = (p.c(), p.codes(), p.tiny(), p.len());
                    out.push(1);
                    out.extend_from_slice(&c[0].to_le_bytes());
                    out.extend_from_slice(&c[1].to_le_bytes());
                    out.extend_from_slice(&len.to_le_bytes());
                    out.extend_from_slice(&(codes.len() as u64).to_le_bytes());
                    out.extend_from_slice(codes);
                    write_tiny(&mut out, tiny);
                }
            }
        }
        let crc = crc32fast::hash(&out);
        out.extend_from_slice(&crc.to_le_bytes());
        out
    }

    /// Reads a file's bytes, checking magic, version, lengths and checksum.
    pub fn decode(bytes: &[u8]) -> Result<SavedReferences, SavedError> {
        let bad = |what: &str| SavedError::Format(what.to_string());
        if bytes.len() < MAGIC.len() + 8 || &bytes[..MAGIC.len()] != MAGIC {
            return Err(bad("it does not start with the reference file's magic bytes"));
        }
        let (body, crc) = bytes.split_at(bytes.len() - 4);
        if crc32fast::hash(body) != u32::from_le_bytes(crc.try_into().map_err(|_| bad("too short"))?) {
            return Err(bad("its checksum does not match: the file is damaged or cut short"));
        }
        let mut r = Reader { bytes: body, at: MAGIC.len() };
        let version = r.u32()?;
        if !(1..=VERSION).contains(&version) {
            return Err(SavedError::Version(version));
        }
        let key_len = r.u32()? as usize;
        let key = String::from_utf8(r.take(key_len)?.to_vec()).map_err(|_| bad("its key is not UTF-8"))?;
        let count = r.u32()?;
        if !(1..=2).contains(&count) {
            return Err(bad("it holds neither one orbit nor two"));
        }
        let mut refs = Vec::new();
        for _ in 0..count {
            let bits = r.u64()?;
            let escaped = r.take(1)?[0] != 0;
            let period = Some(r.u32()?).filter(|&p| p > 0);
            let cycle = if version >= 3 { Some(r.u32()?).filter(|&w| w > 0) } else { None };
            let n = r.len(16)?;
            if n == 0 {
                return Err(bad("an orbit is empty"));
            }
            let mut z = Vec::with_capacity(n);
            for _ in 0..n {
                z.push([r.f64()?, r.f64()?]);
            }
            let tiny = r.tiny(0..n as u64)?;
            if z.iter().flatten().any(|x| !x.is_finite()) {
                return Err(bad("an orbit holds a value that is not finite"));
            }
            let flag = if version >= 2 { r.take(1)?[0] } else { 0 };
            if flag > 1 {
                return Err(bad("its packed-orbit flag is neither 0 nor 1"));
            }
            let packed = if flag == 1 {
                let c = [r.f64()?, r.f64()?];
                let len = r.u32()?;
                let codes = r.len(1)?;
                let codes = r.take(codes)?.to_vec();
                let seed_index = (n - 1) as u32;
                let tiny = r.tiny(seed_index as u64 + 1..seed_index as u64 + 1 + len as u64)?;
                let p = Packed::from_parts(c, seed_index, z[n - 1], codes, tiny, len);
                Some(p.ok_or_else(|| bad("its packed orbit does not decode to the length it claims"))?)
            } else {
                None
            };
            let end = packed.as_ref().map_or(n as u64 - 1, |p| p.last() as u64);
            if period.is_some_and(|p| p as u64 != end) {
                return Err(bad("an orbit's period is not its length"));
            }
            if cycle.is_some_and(|w| w as u64 > end || packed.is_some() || escaped || period.is_some()) {
                return Err(bad("an orbit's cycle reaches outside its densely stored values"));
            }
            refs.push(Reference::from_parts(z, tiny, packed, escaped, bits, period, cycle));
        }
        // Samples rebase onto the last orbit and go on from its index 1.
        if refs.last().is_some_and(|r| r.last() < 1) {
            return Err(bad("the orbit samples rebase onto holds fewer than two values"));
        }
        if r.at != body.len() {
            return Err(bad("it has bytes after its last orbit"));
        }
        Ok(SavedReferences { key, refs: Arc::new(refs) })
    }
}

/// A list of values too small for f64: count, then index and values with exponents.
fn write_tiny(out: &mut Vec<u8>, tiny: &[Tiny]) {
    out.extend_from_slice(&(tiny.len() as u64).to_le_bytes());
    for (n, v) in tiny {
        out.extend_from_slice(&n.to_le_bytes());
        for x in v {
            out.extend_from_slice(&x.mantissa().to_le_bytes());
            out.extend_from_slice(&x.exponent().to_le_bytes());
        }
    }
}

/// Little-endian reads that never run past the end.
struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> Result<&[u8], SavedError> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| SavedError::Format("it is cut short".into()))?;
        let s = &self.bytes[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn array<const N: usize>(&mut self) -> Result<[u8; N], SavedError> {
        let s = self.take(N)?;
        let mut a = [0; N];
        a.copy_from_slice(s);
        Ok(a)
    }
    fn u32(&mut self) -> Result<u32, SavedError> {
        Ok(u32::from_le_bytes(self.array()?))
    }
    fn i32(&mut self) -> Result<i32, SavedError> {
        Ok(i32::from_le_bytes(self.array()?))
    }
    fn u64(&mut self) -> Result<u64, SavedError> {
        Ok(u64::from_le_bytes(self.array()?))
    }
    fn f64(&mut self) -> Result<f64, SavedError> {
        Ok(f64::from_le_bytes(self.array()?))
    }
    /// A list written by [`write_tiny`], its indices in order and within `range`.
    fn tiny(&mut self, range: std::ops::Range<u64>) -> Result<Vec<Tiny>, SavedError> {
        let m = self.len(28)?;
        let mut tiny: Vec<Tiny> = Vec::with_capacity(m);
        for _ in 0..m {
            let n = self.u32()?;
            let mut v = [FloatExp::ZERO; 2];
            for x in &mut v {
                let (mantissa, exponent) = (self.f64()?, self.i32()?);
                *x = FloatExp::new(mantissa, exponent);
            }
            if !range.contains(&(n as u64)) || tiny.last().is_some_and(|&(prev, _)| prev >= n) {
                return Err(SavedError::Format("its small values are out of order or beyond its orbit".into()));
            }
            tiny.push((n, v));
        }
        Ok(tiny)
    }

    /// A count of items of `size` bytes each, checked against the bytes left.
    fn len(&mut self, size: usize) -> Result<usize, SavedError> {
        let n = self.u64()?;
        let left = (self.bytes.len() - self.at) as u64;
        if n.checked_mul(size as u64).is_none_or(|b| b > left) {
            return Err(SavedError::Format(format!("it claims {n} entries but holds {left} bytes")));
        }
        Ok(n as usize)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> SavedReferences {
        let tiny = vec![(1, [FloatExp::new(1.5, -2000), FloatExp::ZERO])];
        let r =
            Reference::from_parts(vec![[0.0, 0.0], [0.0, 0.0], [-1.25, 0.5]], tiny, None, false, 300, Some(2), None);
        SavedReferences { key: "center = -1 0\n".into(), refs: Arc::new(vec![r]) }
    }

    #[test]
    fn encode_decode_round_trip() {
        let s = sample();
        let d = SavedReferences::decode(&s.encode()).unwrap();
        assert_eq!(d.key, s.key);
        let (a, b) = (d.refs[0].parts(), s.refs[0].parts());
        assert_eq!(a.0, b.0);
        assert_eq!(a.1, b.1);
        assert_eq!((d.refs[0].period(), d.refs[0].bits()), (Some(2), 300));
    }

    /// An orbit that repeats reads back with its cycle; a cycle reaching outside the orbit
    /// is refused.
    #[test]
    fn cycles_round_trip() {
        let z = vec![[0.0, 0.0], [0.5, 0.0], [0.25, 0.125], [0.25, 0.125]];
        let r = Reference::from_parts(z.clone(), vec![], None, false, 300, None, Some(1));
        let s = SavedReferences { key: "k\n".into(), refs: Arc::new(vec![r]) };
        let d = SavedReferences::decode(&s.encode()).unwrap();
        assert_eq!((d.refs[0].cycle(), d.refs[0].end()), (Some(1), 3));
        let wide = Reference::from_parts(z, vec![], None, false, 300, None, Some(4));
        let s = SavedReferences { key: "k\n".into(), refs: Arc::new(vec![wide]) };
        assert!(SavedReferences::decode(&s.encode()).is_err(), "a cycle longer than the orbit");
    }

    /// An orbit with a packed tail (tiny values in both parts) reads back whole, and a
    /// version 1 file (no packed part) is still read.
    #[test]
    fn packed_tails_round_trip() {
        let mut p = Packed::new([-1.75, 0.0], 2, [-1.25, 0.5]);
        p.push([-0.3125, -1.25], None);
        p.push([0.0, 0.0], Some([FloatExp::new(1.25, -3000), FloatExp::ZERO]));
        p.push([-1.75, 0.0], None);
        let tiny = vec![(1, [FloatExp::new(1.5, -2000), FloatExp::ZERO])];
        let r =
            Reference::from_parts(vec![[0.0, 0.0], [0.0, 0.0], [-1.25, 0.5]], tiny, Some(p), false, 300, None, None);
        let s = SavedReferences { key: "k\n".into(), refs: Arc::new(vec![r]) };
        let d = SavedReferences::decode(&s.encode()).unwrap();
        let values = |r: &Reference| r.values_fe(0, 10).collect::<Vec<_>>();
        assert_eq!((d.refs[0].last(), d.refs[0].end()), (2, 5));
        assert_eq!(values(&d.refs[0]), values(&s.refs[0]));
        assert_eq!(d.refs[0].packed(), s.refs[0].packed());
        // Version 1: the same bytes without the cycle (after the period) and the packed flag.
        let v1 = sample();
        assert_eq!(v1.refs.len(), 1);
        let cycle_at = MAGIC.len() + 4 + 4 + v1.key.len() + 4 + 8 + 1 + 4;
        let mut bytes = v1.encode();
        bytes.truncate(bytes.len() - 5);
        bytes.drain(cycle_at..cycle_at + 4);
        bytes[8..12].copy_from_slice(&1u32.to_le_bytes());
        let crc = crc32fast::hash(&bytes);
        bytes.extend_from_slice(&crc.to_le_bytes());
        let d = SavedReferences::decode(&bytes).unwrap();
        assert_eq!(d.refs[0].parts().0, v1.refs[0].parts().0);
        // A packed flag other than 0 or 1 is refused.
        let mut bytes = v1.encode();
        bytes.truncate(bytes.len() - 4);
        *bytes.last_mut().unwrap() = 2;
        let crc = crc32fast::hash(&bytes);
        bytes.extend_from_slice(&crc.to_le_bytes());
        let e = SavedReferences::decode(&bytes).unwrap_err().to_string();
        assert!(e.contains("neither 0 nor 1"), "{e}");
    }

    /// A file whose checksum is right but whose counts claim more than it holds (a crafted
    /// file) is refused before anything that size is allocated.
    #[test]
    fn counts_past_the_end_are_refused_before_allocating() {
        let mut bytes = sample().encode();
        bytes.truncate(bytes.len() - 4);
        // The first orbit's value count sits after magic, version, key, count, bits,
        // escaped and period.
        let at = 8 + 4 + 4 + "center = -1 0\n".len() + 4 + 8 + 1 + 4;
        bytes[at..at + 8].copy_from_slice(&u64::MAX.to_le_bytes());
        let crc = crc32fast::hash(&bytes);
        bytes.extend_from_slice(&crc.to_le_bytes());
        let e = SavedReferences::decode(&bytes).unwrap_err().to_string();
        assert!(e.contains("claims"), "{e}");
        assert!(SavedReferences::decode(b"DFREFORB").is_err());
        assert!(SavedReferences::decode(&[]).is_err());
    }
}
