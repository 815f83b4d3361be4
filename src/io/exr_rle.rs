//! OpenEXR's RLE decompression of one block, into buffers a reading thread keeps.
//!
//! The format (OpenEXR's `ImfRle`, the compression deepfield writes its raw data with): the
//! block's little-endian bytes are split into two halves (the bytes at even offsets, then
//! those at odd offsets), each byte replaced by its difference from the one before plus 128,
//! and the result run-length coded in tokens: a signed count byte c, then either −c literal
//! bytes (c < 0) or one byte repeated c + 1 times. A block that would not shrink is stored
//! as it is (its size is then the decompressed size).
//!
//! The exr crate decodes these blocks too, but into fresh vectors grown token by token,
//! with the halves interleaved through a third buffer and copied back: on a 4K recolour that
//! was a fifth of the instructions. Here the tokens go into a buffer of the block's size
//! kept by the thread, the differences are summed eight bytes at a time in a machine word
//! (only one addition per eight bytes is on the dependency chain), and the halves are
//! interleaved straight into the output.

/// Why a block did not decode: its tokens end before the block does, or run past it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RleError {
    /// The tokens end before the block's size is reached.
    Short,
    /// A token runs past the block's size.
    Long,
}

impl std::fmt::Display for RleError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            RleError::Short => "an RLE block whose data ends before its pixels do",
            RleError::Long => "an RLE block whose data runs past its pixels",
        })
    }
}

/// Buffers one thread reuses from block to block.
#[derive(Debug, Default)]
pub struct RleScratch {
    tokens: Vec<u8>,
    out: Vec<u8>,
}

impl RleScratch {
    /// Decompresses one block of `expected` bytes; the bytes, in the file's (little-endian)
    /// order, are valid until the next call.
    pub fn decompress<'a>(&'a mut self, compressed: &'a [u8], expected: usize) -> Result<&'a [u8], RleError> {
        if compressed.len() == expected {
            // Stored as it is.
            return Ok(compressed);
        }
        unpack(compressed, expected, &mut self.tokens)?;
        undo_prediction(&mut self.tokens);
        interleave(&self.tokens, &mut self.out);
        Ok(&self.out)
    }
}

/// Expands the tokens into `out` (exactly `expected` bytes; trailing tokens past them are
/// ignored, as OpenEXR does).
fn unpack(mut input: &[u8], expected: usize, out: &mut Vec<u8>) -> Result<(), RleError> {
    out.clear();
    out.reserve(expected);
    while out.len() < expected {
        let [count, rest @ ..] = input else { return Err(RleError::Short) };
        let count = *count as i8;
        if count < 0 {
            let n = count.unsigned_abs() as usize;
            let literal = rest.get(..n).ok_or(RleError::Short)?;
            if out.len() + n > expected {
                return Err(RleError::Long);
            }
            out.extend_from_slice(literal);
            input = &rest[n..];
        } else {
            let [value, rest @ ..] = rest else { return Err(RleError::Short) };
            let n = count as usize + 1;
            if out.len() + n > expected {
                return Err(RleError::Long);
            }
            out.resize(out.len() + n, *value);
            input = rest;
        }
    }
    Ok(())
}

/// Undoes the prediction in place: b[i] = b[i - 1] + b[i] - 128 (wrapping). Eight bytes at a
/// time in a u64: their prefix sums by three shifted additions that keep each byte's carry
/// to itself, then the previous byte added to all eight, so one addition per eight bytes is
/// on the dependency chain.
fn undo_prediction(b: &mut [u8]) {
    const HIGH: u64 = 0x8080_8080_8080_8080;
    /// Bytewise addition modulo 256.
    fn add8(a: u64, b: u64) -> u64 {
        ((a & !HIGH) + (b & !HIGH)) ^ ((a ^ b) & HIGH)
    }
    let Some((first, rest)) = b.split_first_mut() else { return };
    let mut prev = *first;
    let mut chunks = rest.chunks_exact_mut(8);
    for c in &mut chunks {
        let bytes: &mut [u8; 8] = c.try_into().expect("chunks of eight");
        // d - 128 and d ^ 0x80 are the same byte.
        let mut x = u64::from_le_bytes(*bytes) ^ HIGH;
        x = add8(x, x << 8);
        x = add8(x, x << 16);
        x = add8(x, x << 32);
        x = add8(x, u64::from(prev) * 0x0101_0101_0101_0101);
        *bytes = x.to_le_bytes();
        prev = (x >> 56) as u8;
    }
    for v in chunks.into_remainder() {
        prev = prev.wrapping_add(*v ^ 0x80);
        *v = prev;
    }
}

/// The bytes at even offsets are the first half (rounded up), those at odd offsets the
/// second.
fn interleave(b: &[u8], out: &mut Vec<u8>) {
    let (first, second) = b.split_at(b.len().div_ceil(2));
    // Blocks of one file have one size: the buffer keeps its length, and every byte is
    // written below.
    out.resize(b.len(), 0);
    for ((o, x), y) in out.chunks_exact_mut(2).zip(first).zip(second) {
        o[0] = *x;
        o[1] = *y;
    }
    if first.len() > second.len() {
        out[b.len() - 1] = first[first.len() - 1];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The encoder, written from the format's description: split, predict, then tokens
    /// (runs of three or more as repeats, the rest as literals of up to 127).
    fn compress(data: &[u8]) -> Vec<u8> {
        let mut split: Vec<u8> = data.iter().step_by(2).chain(data.iter().skip(1).step_by(2)).copied().collect();
        for i in (1..split.len()).rev() {
            split[i] = split[i].wrapping_sub(split[i - 1]).wrapping_add(128);
        }
        let mut out = Vec::new();
        let mut i = 0;
        while i < split.len() {
            let run = split[i..].iter().take(128).take_while(|&&v| v == split[i]).count();
            if run >= 3 {
                out.extend([(run - 1) as u8, split[i]]);
                i += run;
            } else {
                let start = i;
                while i < split.len()
                    && i - start < 127
                    && !(i + 2 < split.len() && split[i] == split[i + 1] && split[i] == split[i + 2])
                {
                    i += 1;
                }
                out.push((-((i - start) as i32)) as u8);
                out.extend_from_slice(&split[start..i]);
            }
        }
        out
    }

    #[test]
    fn blocks_round_trip() {
        let mut state = 5u32;
        let mut noise = |m: u32| {
            state = state.wrapping_mul(1664525).wrapping_add(1013904223);
            (state >> 24) % m
        };
        let mut scratch = RleScratch::default();
        for len in [1usize, 2, 3, 4, 5, 7, 8, 9, 255, 256, 1001, 40_000] {
            // Runs and noise mixed, like float planes beside integer ones.
            let data: Vec<u8> =
                (0..len).map(|i| if (i / 300) % 2 == 0 { (i / 17) as u8 } else { noise(256) as u8 }).collect();
            let packed = compress(&data);
            if packed.len() != data.len() {
                assert_eq!(scratch.decompress(&packed, len), Ok(&data[..]), "{len} bytes");
            }
            // Stored as it is where it would not shrink.
            assert_eq!(scratch.decompress(&data, len), Ok(&data[..]));
        }
    }

    #[test]
    fn damaged_blocks_are_refused() {
        let mut scratch = RleScratch::default();
        let data: Vec<u8> = (0..100u8).collect();
        let packed = compress(&data);
        assert_eq!(scratch.decompress(&packed[..packed.len() - 1], 100), Err(RleError::Short));
        assert_eq!(scratch.decompress(&packed, 99), Err(RleError::Long));
        assert_eq!(scratch.decompress(&packed, 101), Err(RleError::Short));
        assert_eq!(scratch.decompress(&[], 3), Err(RleError::Short));
        // A repeat token with no value, a literal cut short.
        assert_eq!(scratch.decompress(&[5], 6), Err(RleError::Short));
        assert_eq!(scratch.decompress(&[0xfc, 1, 2], 4), Err(RleError::Short));
        // Trailing tokens past the block are ignored.
        assert_eq!(scratch.decompress(&[0, 128, 0, 128], 1), Ok(&[128u8][..]));
    }
}
