//! How the three squares of one reference step are cut between the threads of a team
//! ([`super::fixed`]): which thread computes which columns (or rows) of which square.
//!
//! A step of a wide orbit is three squarings (|x|^2, |x + y|^2, |y|^2) of the same width, and
//! every column of a square (64-bit limbs, [`super::comba`]) or block of rows (26-bit
//! digits, [`super::square`]) can be computed on its own: a range of them gives its limbs
//! and a carry, or its column sums, and the ranges put back together give exactly the bits
//! of one pass. So the three squares are laid end to end as one line of work, measured in
//! products, and the line is cut into one share per thread; each thread computes the pieces
//! of the squares its share covers, publishes them, takes everyone else's and finishes the
//! step itself (FractalShark computes its reference with helper threads doing the squarings
//! of its wide numbers; here every thread also finishes every step, so no thread waits for
//! an answer to a request).
//!
//! The calling thread also stores every value of the orbit (the period test, rounding to
//! f64, the packed tail), which costs about a tenth of a square at the e1086 benchmark's 60
//! limbs: its share is that much shorter than the others'. With two threads that puts the
//! cut 45 % of the way into the middle square, where the two-thread split was tuned
//! (`cargo bench --bench reference`). The order of the line, |x|^2, |x + y|^2, |y|^2, gives
//! each of two threads one square whole and part of the middle one.
//!
//! Where each cut falls depends on the widths and the team's size only, never on timing; and
//! wherever it falls the step gives the same bits.

use std::ops::Range;

/// The squares of a step, in the order of the line: |x|^2, |x + y|^2, |y|^2.
pub const SQUARES: usize = 3;

/// How much shorter the caller's share is than a helper's, in per cent of one square.
pub const CALLER_LESS: usize = 10;

/// One piece of a shared step: positions `range` (columns, or starts of blocks of rows) of
/// square `square` (an index into the line, [`SQUARES`]).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Piece {
    /// Which square, in the line's order.
    pub square: usize,
    /// Which columns or blocks of rows.
    pub range: Range<usize>,
}

/// The pieces of each of `threads` threads (0 the caller), in the line's order, for squares
/// whose possible cuts are `cuts`: ascending positions, each with the products before it,
/// from the square's first position (no products before it) to its end (all of them).
///
/// Thread t's share of the line ends at the caller's share plus t - 1 helpers' shares; a
/// share's end within a square is the first cut with at least that many products before
/// it, so two neighbouring threads agree on where one's piece ends and the next begins,
/// and every position of every square belongs to exactly one piece.
pub fn plan(cuts: &[(usize, usize)], threads: usize) -> Vec<Vec<Piece>> {
    let threads = threads.max(1);
    let per_square = cuts.last().map_or(0, |c| c.1) as f64;
    let line = SQUARES as f64 * per_square;
    let less = per_square * CALLER_LESS as f64 / 100.0;
    // Each helper's share, and the caller's (which may be empty on a large team).
    let helper = (line + less) / threads as f64;
    let caller = (line - (threads - 1) as f64 * helper).max(0.0);
    let bound = |t: usize| -> f64 {
        match t {
            0 => 0.0,
            t if t >= threads => line,
            t => (caller + (t - 1) as f64 * helper).min(line),
        }
    };
    // The position in a square where `v` products of it lie before.
    let position = |v: f64| -> usize {
        let (first, last) = (cuts.first().map_or(0, |c| c.0), cuts.last().map_or(0, |c| c.0));
        if v <= 0.0 {
            return first;
        }
        cuts.iter().find(|c| c.1 as f64 >= v).map_or(last, |c| c.0)
    };
    (0..threads)
        .map(|t| {
            let (from, to) = (bound(t), bound(t + 1));
            (0..SQUARES)
                .filter_map(|q| {
                    let base = q as f64 * per_square;
                    let (lo, hi) = (position(from - base), position(to - base));
                    (lo < hi).then_some(Piece { square: q, range: lo..hi })
                })
                .collect()
        })
        .collect()
}

/// The products of a share of the line: the pieces' products (for tests and balance).
pub fn products(cuts: &[(usize, usize)], pieces: &[Piece]) -> usize {
    let before = |p: usize| cuts.iter().find(|c| c.0 == p).map_or(0, |c| c.1);
    pieces.iter().map(|p| before(p.range.end) - before(p.range.start)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cuts of a square with `count` positions from `first`, each costing its index + 1.
    fn cuts(first: usize, count: usize) -> Vec<(usize, usize)> {
        let mut sum = 0;
        let mut out = Vec::new();
        for k in 0..=count {
            out.push((first + k, sum));
            sum += k + 1;
        }
        out
    }

    /// Every position of every square belongs to exactly one piece, the pieces come in the
    /// line's order, and the shares are balanced to within a cut's products (the caller's
    /// shorter by [`CALLER_LESS`]), on teams of 1 to 16 threads.
    #[test]
    fn the_pieces_cover_every_square_once_and_in_order() {
        for (first, count) in [(57, 60), (0, 3), (5, 200)] {
            let c = cuts(first, count);
            let end = first + count;
            let total = c.last().unwrap().1;
            for threads in 1..=16 {
                let plan = plan(&c, threads);
                assert_eq!(plan.len(), threads);
                let all: Vec<&Piece> = plan.iter().flatten().collect();
                for q in 0..SQUARES {
                    let mine: Vec<&&Piece> = all.iter().filter(|p| p.square == q).collect();
                    assert_eq!(mine.first().unwrap().range.start, first, "{threads} threads, square {q}");
                    assert_eq!(mine.last().unwrap().range.end, end, "{threads} threads, square {q}");
                    assert!(mine.windows(2).all(|w| w[0].range.end == w[1].range.start), "{threads}: {mine:?}");
                }
                assert!(all.windows(2).all(|w| w[0].square <= w[1].square), "{threads}: line order");
                let shares: Vec<usize> = plan.iter().map(|p| products(&c, p)).collect();
                assert_eq!(shares.iter().sum::<usize>(), SQUARES * total);
                if count >= 60 && threads > 1 {
                    let widest = c.windows(2).map(|w| w[1].1 - w[0].1).max().unwrap();
                    let helper = (SQUARES * total + total * CALLER_LESS / 100) as f64 / threads as f64;
                    for (t, &s) in shares.iter().enumerate().skip(1) {
                        assert!((s as f64 - helper).abs() <= 2.0 * widest as f64, "{threads}: thread {t} has {s}");
                    }
                }
            }
        }
    }

    /// Two threads: one square whole each and the middle one cut where the caller has
    /// CALLER_LESS per cent of a square less than the helper.
    #[test]
    fn two_threads_take_a_square_each_and_part_of_the_middle_one() {
        let c = cuts(57, 60);
        let plan = plan(&c, 2);
        assert_eq!(plan[0][0], Piece { square: 0, range: 57..117 });
        assert_eq!(plan[1][1], Piece { square: 2, range: 57..117 });
        let (mid, total) = (plan[0][1].range.end, c.last().unwrap().1);
        let before = c.iter().find(|x| x.0 == mid).unwrap().1;
        assert!((before as f64 / total as f64 - 0.45).abs() < 0.05, "{before} of {total}");
    }
}
