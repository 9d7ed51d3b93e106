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
    /// The layout for `facets` active facets: at least four buckets per facet (64 at least),
    /// room for every facet in `BIN_SPAN^3` cells.
    /// (Sizes past `u32` saturate: no device holds such a buffer, and allocating it fails.)
    pub fn new(facets: u32) -> Self {
        let bits = (4 * facets.max(16) as u64)
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

/// A walk over the cells around a slave's cell in rings outward (WGSL: `Ring` and its
/// functions): ring r is the cells at Chebyshev distance r, taken layer by layer along z
/// (dz = −r ..= r; one layer in 2D), row by row along y, and along x: every cell of a row on the
/// ring's boundary in y or z, the two ends (dx = ∓r) of the others. No division: on a software
/// adapter an integer division is a loop over the SIMD lanes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Ring {
    /// The ring.
    pub r: i32,
    /// The offset of the current cell from the centre cell.
    pub d: [i32; 3],
}

impl Ring {
    /// At ring 0, the centre cell.
    pub fn new() -> Self {
        Self { r: 0, d: [0; 3] }
    }

    /// Whether the current cell starts its row (WGSL: `ring_row_start`).
    pub fn row_start(&self) -> bool {
        self.d[0] == -self.r
    }

    /// Whether the current cell starts its layer (WGSL: `ring_layer_start`).
    pub fn layer_start(&self) -> bool {
        self.row_start() && self.d[1] == -self.r
    }

    /// To the next row (the next layer, or the next ring's first cell, after the last row);
    /// true when that starts a new ring (WGSL: `ring_next_row`).
    pub fn next_row(&mut self, dim: u32) -> bool {
        let r = self.r;
        self.d[0] = -r;
        self.d[1] += 1;
        if self.d[1] <= r {
            return false;
        }
        self.d[1] = -r;
        self.d[2] += 1;
        if dim != 2 && self.d[2] <= r {
            return false;
        }
        self.r += 1;
        let r = self.r;
        self.d = [-r, -r, if dim == 2 { 0 } else { -r }];
        true
    }

    /// To the next layer (or the next ring); true when that starts a new ring (WGSL:
    /// `ring_next_layer`).
    pub fn next_layer(&mut self, dim: u32) -> bool {
        self.d[1] = self.r;
        self.next_row(dim)
    }

    /// To the next cell of the ring (or the next ring's first); true when that starts a new
    /// ring (WGSL: `ring_next_cell`).
    pub fn next_cell(&mut self, dim: u32) -> bool {
        let r = self.r;
        let edge = self.d[1].abs() == r || (dim != 2 && self.d[2].abs() == r);
        if self.d[0] < r {
            self.d[0] = if edge { self.d[0] + 1 } else { r };
            return false;
        }
        self.next_row(dim)
    }
}

impl Default for Ring {
    fn default() -> Self {
        Self::new()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Ring r's cells are exactly those at Chebyshev distance r, each once, in order of r;
    /// skipping a row or a layer leaves out exactly its cells.
    #[test]
    fn rings_cover_each_cell_once() {
        for dim in [2, 3] {
            let mut seen = std::collections::HashSet::new();
            let mut ring = Ring::new();
            let mut last_r = 0;
            while ring.r < 6 {
                let cheb = ring.d.iter().map(|x| x.abs()).max().unwrap();
                assert_eq!(cheb, ring.r, "{dim}D: {ring:?}");
                assert!(ring.r >= last_r);
                last_r = ring.r;
                assert!(dim == 3 || ring.d[2] == 0);
                assert!(seen.insert(ring.d), "{dim}D: {ring:?} twice");
                let r = ring.r;
                assert_eq!(ring.next_cell(dim), ring.r != r);
            }
            let side = 11usize;
            assert_eq!(seen.len(), if dim == 2 { side * side } else { side.pow(3) });
            // skip every row with dy = 1 and every layer with dz = −1: the rest is the same
            let mut kept = Vec::new();
            let mut ring = Ring::new();
            while ring.r < 5 {
                if dim == 3 && ring.layer_start() && ring.d[2] == -1 {
                    ring.next_layer(dim);
                    continue;
                }
                if ring.row_start() && ring.d[1] == 1 {
                    ring.next_row(dim);
                    continue;
                }
                kept.push(ring.d);
                ring.next_cell(dim);
            }
            let mut all = Vec::new();
            let mut ring = Ring::new();
            while ring.r < 5 {
                all.push(ring.d);
                ring.next_cell(dim);
            }
            all.retain(|d| d[1] != 1 && !(dim == 3 && d[2] == -1));
            assert_eq!(kept, all, "{dim}D");
        }
    }

    #[test]
    fn layout_and_shift() {
        let l = BucketLayout::new(1000);
        assert_eq!(l.bits, 12);
        assert_eq!(l.buckets(), 4097);
        assert_eq!(l.entries, l.levels.words);
        assert_eq!(l.words, l.entries + 16_000);
        assert_eq!(BucketLayout::new(0).bits, 6);
        assert_eq!(BucketLayout::new(u32::MAX).bits, 30);
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
