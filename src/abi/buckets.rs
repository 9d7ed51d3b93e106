//! The bucket search's grid (WGSL twins in `buckets.wgsl`): cells of a power of two of box-grid
//! steps ([`crate::abi::boxes`]), hashed into `2^bits` buckets, plus one bucket of the facets
//! too large to bin; its layout in one buffer of words; a slave's cells in rings outward.
//!
//! Cells are taken in the box grid's integer codes, so a facet's cells (from its leaf box) and
//! a slave's (from its box point) are the same integers on every device and in the CPU mirror.

use crate::abi::search::ScanLevels;

/// Cells plus bucket entries one bucket walk visits at most (WGSL: `BUCKET_VISITS`); a walk
/// that would go past it leaves the rest to the chunks (every leaf slot), as a capped tree walk
/// does.
pub const BUCKET_VISITS: u32 = 2048;

/// Cells per axis a facet may span and still be binned (at most `2^3` cells); a larger facet
/// goes to the last bucket, which every walk visits first.
pub const BIN_SPAN: u32 = 2;

/// Where the bucket grid's parts lie in its buffer of words.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct BucketLayout {
    /// `2^bits` hashed buckets.
    pub bits: u32,
    /// The scan of the `2^bits + 1` bucket words (counts, then starts, then ends).
    pub levels: ScanLevels,
    /// Word where the entries start (two words each: leaf slot, facet).
    pub entries: u32,
    /// Words the buffer needs.
    pub words: u32,
}

impl BucketLayout {
    /// The layout for `facets` active facets: at least two buckets per facet (64 at least),
    /// room for every facet in `BIN_SPAN^3` cells.
    /// (Sizes past `u32` saturate: no device holds such a buffer, and allocating it fails.)
    pub fn new(facets: u32) -> Self {
        let bits = (2 * facets.max(32) as u64)
            .next_power_of_two()
            .trailing_zeros()
            .min(30);
        let levels = ScanLevels::new((1 << bits) + 1);
        let entries = levels.words;
        let cap = facets.max(1).saturating_mul(BIN_SPAN.pow(3));
        Self {
            bits,
            entries,
            words: entries.saturating_add(cap.saturating_mul(2)),
            levels,
        }
    }

    /// Buckets, the overflow bucket included.
    pub fn buckets(&self) -> u32 {
        (1 << self.bits) + 1
    }
}

/// The bucket of cell `c` (its three cell coordinates) in a table of `2^bits` (WGSL:
/// `bucket_of`).
pub fn bucket_of(c: [u32; 3], bits: u32) -> u32 {
    let h = c[0].wrapping_mul(0x8da6_b343)
        ^ c[1].wrapping_mul(0xd816_3841)
        ^ c[2].wrapping_mul(0xcb1a_b31f);
    h.wrapping_mul(0x9e37_79b1) >> (32 - bits)
}

/// Box-grid codes per cell, as a shift: the largest power of two of grid steps at or below
/// `cell` (frame units), between 1 and 2^20 (WGSL: `cell_shift`). `margin` is the box margin
/// the grid's step comes from.
pub fn cell_shift(cell: f32, margin: f32) -> u32 {
    let exp = |x: f32| ((x.to_bits() >> 23) & 0xff) as i32 - 127;
    let step = exp(margin).clamp(-100, 100);
    (exp(cell) - step).clamp(0, 20) as u32
}

/// Cells in ring `r` around a cell (Chebyshev distance exactly `r`), in `dim` 2 or 3 (WGSL:
/// `ring_cells`).
pub fn ring_cells(r: u32, dim: u32) -> u32 {
    if r == 0 {
        1
    } else if dim == 2 {
        8 * r
    } else {
        24 * r * r + 2
    }
}

/// The offset of the `m`-th cell of ring `r` (`m < ring_cells(r, dim)`; WGSL: `ring_cell`):
/// in 3D the two faces z = ∓r row by row, then each layer between them as in 2D; in 2D the
/// rows y = ∓r, then the columns x = ∓r between them.
pub fn ring_cell(r: u32, m: u32, dim: u32) -> [i32; 3] {
    let ri = r as i32;
    let side = 2 * r + 1;
    let square = |e: u32| -> [i32; 2] {
        // cell e of the square ring r in x, y
        if e < 2 * side {
            let y = if e < side { -ri } else { ri };
            [(e % side) as i32 - ri, y]
        } else {
            let e = e - 2 * side;
            let inner = 2 * r - 1;
            let x = if e < inner { -ri } else { ri };
            [x, (e % inner) as i32 - (ri - 1)]
        }
    };
    if r == 0 {
        return [0; 3];
    }
    if dim == 2 {
        let [x, y] = square(m);
        return [x, y, 0];
    }
    let face = side * side;
    if m < 2 * face {
        let z = if m < face { -ri } else { ri };
        let e = m % face;
        return [(e % side) as i32 - ri, (e / side) as i32 - ri, z];
    }
    let m = m - 2 * face;
    let layer = m / (8 * r);
    let [x, y] = square(m % (8 * r));
    [x, y, layer as i32 - (ri - 1)]
}

/// Where the walk over ring `r` around cell `c` goes after its `m`-th cell when the run of
/// cells it starts (a face or layer of the cube, or a row or column of a layer) lies outside
/// the cells `lo..=hi` along the axis that fixes it: the first cell after the run; `m` itself
/// otherwise (WGSL: `ring_skip`). The runs in order are those of [`ring_cell`].
pub fn ring_skip(r: u32, m: u32, dim: u32, c: [i32; 3], lo: [i32; 3], hi: [i32; 3]) -> u32 {
    if r == 0 {
        return m;
    }
    let ri = r as i32;
    let side = 2 * r + 1;
    let outside = |a: usize, x: i32| x < lo[a] || x > hi[a];
    // a layer of the square ring starting at index `base`, e = m − base
    let square = |base: u32, e: u32| -> u32 {
        if e < 2 * side {
            let (y, end) = if e < side {
                (-ri, side)
            } else {
                (ri, 2 * side)
            };
            return if outside(1, c[1] + y) { base + end } else { m };
        }
        let f = e - 2 * side;
        let inner = 2 * r - 1;
        let (x, end) = if f < inner {
            (-ri, inner)
        } else {
            (ri, 2 * inner)
        };
        if outside(0, c[0] + x) {
            base + 2 * side + end
        } else {
            m
        }
    };
    if dim == 2 {
        return square(0, m);
    }
    let face = side * side;
    if m < 2 * face {
        let (z, end) = if m < face {
            (-ri, face)
        } else {
            (ri, 2 * face)
        };
        return if outside(2, c[2] + z) { end } else { m };
    }
    let layer = (m - 2 * face) / (8 * r);
    let base = 2 * face + layer * 8 * r;
    if outside(2, c[2] + layer as i32 - (ri - 1)) {
        return base + 8 * r;
    }
    square(base, m - base)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ring r's cells are exactly those at Chebyshev distance r, each once.
    #[test]
    fn rings_cover_each_cell_once() {
        for dim in [2, 3] {
            let mut seen = std::collections::HashSet::new();
            for r in 0..6u32 {
                for m in 0..ring_cells(r, dim) {
                    let c = ring_cell(r, m, dim);
                    let cheb = c.iter().map(|x| x.unsigned_abs()).max().unwrap();
                    assert_eq!(cheb, r, "{dim}D ring {r} cell {m}: {c:?}");
                    assert!(dim == 3 || c[2] == 0);
                    assert!(seen.insert(c), "{dim}D ring {r}: {c:?} twice");
                }
            }
            let side = 11usize;
            assert_eq!(seen.len(), if dim == 2 { side * side } else { side.pow(3) });
        }
    }

    /// Skipping runs outside a box visits exactly the ring's cells inside it, in order.
    #[test]
    fn skipped_runs_leave_the_cells_inside() {
        for dim in [2, 3] {
            for (lo, hi) in [
                ([-1, -2, 0], [3, 1, 0]),
                ([-9, -9, -1], [9, 9, 2]),
                ([2, 2, 2], [5, 5, 5]),
            ] {
                let (lo, hi) = if dim == 2 {
                    ([lo[0], lo[1], 0], [hi[0], hi[1], 0])
                } else {
                    (lo, hi)
                };
                for r in 0..7 {
                    let inside = |o: [i32; 3]| (0..3).all(|a| lo[a] <= o[a] && o[a] <= hi[a]);
                    let all: Vec<[i32; 3]> = (0..ring_cells(r, dim))
                        .map(|m| ring_cell(r, m, dim))
                        .filter(|&o| inside(o))
                        .collect();
                    let mut got = Vec::new();
                    let mut m = 0;
                    while m < ring_cells(r, dim) {
                        let next = ring_skip(r, m, dim, [0; 3], lo, hi);
                        if next != m {
                            assert!(next > m);
                            for k in m..next {
                                assert!(!inside(ring_cell(r, k, dim)), "{dim}D r {r}: skipped {k}");
                            }
                            m = next;
                            continue;
                        }
                        let o = ring_cell(r, m, dim);
                        if inside(o) {
                            got.push(o);
                        }
                        m += 1;
                    }
                    assert_eq!(got, all, "{dim}D ring {r}, box {lo:?}..{hi:?}");
                }
            }
        }
    }

    #[test]
    fn layout_and_shift() {
        let l = BucketLayout::new(1000);
        assert_eq!(l.bits, 11);
        assert_eq!(l.buckets(), 2049);
        assert_eq!(l.entries, l.levels.words);
        assert_eq!(l.words, l.entries + 16_000);
        assert_eq!(BucketLayout::new(0).bits, 6);
        // cells of 2^s steps at or below the cell size
        let margin = 1.0 / 1024.0;
        assert_eq!(cell_shift(1.0, margin), 10);
        assert_eq!(cell_shift(1.5, margin), 10);
        assert_eq!(cell_shift(0.5 / 1024.0, margin), 0);
        assert_eq!(cell_shift(1e30, margin), 20);
        for c in [[0, 0, 0], [1, 2, 3], [u32::MAX >> 11; 3]] {
            assert!(bucket_of(c, 6) < 64);
        }
    }
}
