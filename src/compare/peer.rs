//! Another program's raw data scored like an engine: the values a peer (Fraktaler-3,
//! fractall-rust, Kalles Fraktaler) wrote to a raw EXR, read at the pixels `compare`
//! sampled, so that its N and NF meet the same big-float truth and the same tests of
//! conditioning as deepfield's engines.
//!
//! Those programs write N as a u32 with a bias added (their `IterationsBias` attribute,
//! 1024 in Fraktaler-3 and fractall-rust) and u32::MAX where the sample did not escape, and
//! NF as 1 - log_p(ln|z| / ln R), the same fraction as deepfield's. They carry no distance
//! estimate in that form, and their time is not this process's to measure: a peer's row has
//! neither.

use super::Measured;
use crate::formula::end::INTERIOR;

/// Why a peer's values do not fit the view.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PeerError {
    /// The file's size is not the view's sample grid.
    #[error("it holds {}x{} samples, the view {}x{}", got.0, got.1, want.0, want.1)]
    Size {
        /// The file's width and height.
        got: (usize, usize),
        /// The view's samples across and down.
        want: (usize, usize),
    },
    /// It has no NF channel.
    #[error("it has no NF channel")]
    NoNf,
}

/// A peer's N at one sample: its stored value less `bias`, or [`INTERIOR`] where it did
/// not escape (u32::MAX) or the value lies below the bias.
pub fn unbiased(stored: u32, bias: u32) -> u32 {
    if stored == u32::MAX { INTERIOR } else { stored.checked_sub(bias).unwrap_or(INTERIOR) }
}

/// The peer's values at `pixels` (sample-grid positions) from its planes `n` and `nf`,
/// `width` × `height` samples with the top row first, which must be the view's
/// (`view_width` × `view_height`).
pub fn measured(
    n: &[u32],
    nf: &[f32],
    (width, height): (usize, usize),
    (view_width, view_height): (usize, usize),
    bias: u32,
    pixels: &[(u32, u32)],
) -> Result<Measured, PeerError> {
    if (width, height) != (view_width, view_height) || n.len() != width * height {
        return Err(PeerError::Size { got: (width, height), want: (view_width, view_height) });
    }
    if nf.len() != n.len() {
        return Err(PeerError::NoNf);
    }
    let values = pixels
        .iter()
        .map(|&(x, y)| {
            let k = y as usize * width + x as usize;
            (unbiased(n[k], bias), nf[k], 0.0, 0.0)
        })
        .collect();
    Ok(Measured { values, iterations: 0, seconds: f64::NAN, distance: false })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_bias_comes_off_and_unescaped_samples_are_interior() {
        assert_eq!(unbiased(1024 + 77, 1024), 77);
        assert_eq!(unbiased(u32::MAX, 1024), INTERIOR);
        assert_eq!(unbiased(5, 1024), INTERIOR);
        assert_eq!(unbiased(9, 0), 9);
    }

    #[test]
    fn values_are_read_at_the_sampled_pixels_top_row_first() {
        // 3 x 2 samples: row 0 is the top row.
        let n = [1030, 1031, 1032, 1040, 1041, u32::MAX];
        let nf = [0.0, 0.1, 0.2, 0.5, 0.6, 0.0];
        let m = measured(&n, &nf, (3, 2), (3, 2), 1024, &[(1, 0), (0, 1), (2, 1)]).unwrap();
        assert_eq!(m.values, vec![(7, 0.1, 0.0, 0.0), (16, 0.5, 0.0, 0.0), (INTERIOR, 0.0, 0.0, 0.0)]);
    }

    #[test]
    fn a_file_of_another_size_is_refused_with_both_sizes() {
        let e = measured(&[0; 6], &[0.0; 6], (3, 2), (4, 2), 0, &[]).unwrap_err();
        assert_eq!(e.to_string(), "it holds 3x2 samples, the view 4x2");
        let e = measured(&[0; 6], &[], (3, 2), (3, 2), 0, &[]).unwrap_err();
        assert_eq!(e, PeerError::NoNf);
    }
}
