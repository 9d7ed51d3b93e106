//! The frame of the search kernels and the box it covers, fitted on the host (and on the device
//! for device-resident increments, `schedule.wgsl`). The search itself walks a tree
//! (`search::tree`); the box, kept as a grid of cells, is what `to_local` checks a master node
//! against (one leaving it moves the frame) and what the frame's extent is measured by.

use crate::error::{Error, Result};

/// Largest number of cells a grid may have.
pub const MAX_CELLS: u64 = 1 << 24;

/// The box the kernels' frame covers — the master surface's bounding box grown by the search
/// radius, as a grid of cubic cells — and the frame itself: coordinates are stored relative to
/// `frame` in f32, so a small mesh far from the model origin keeps its precision. The frame
/// comes from the master's own extent, not from the radius, so that a search radius far larger
/// than the master (10⁶ model sizes, say) does not turn the gaps into round-off.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// Origin of the kernels' local frame, model coordinates (f64): the master's lower corner
    /// snapped down to a power of two about 1/16 of the master's extent.
    pub frame: [f64; 3],
    /// Lower corner of cell (0, 0, 0), model coordinates (f64); relative to `frame` it is a
    /// multiple of a power of two, exact in f32 ([`Grid::lo_in_frame`]).
    pub origin: [f64; 3],
    /// Cell edge length, model units.
    pub cell_size: f64,
    /// Cells per axis (z = 1 in 2D).
    pub dims: [u32; 3],
}

impl Grid {
    /// Fits a grid to the master bounds `[lo, hi]`, the search `radius` and the mean facet
    /// bounding-box extent `facet_extent`, for `n_facets` facets in `dim` dimensions.
    ///
    /// Cell size: half of `facet_extent + 2·radius` (but at least `facet_extent`), so a
    /// facet's grown box spans about three cells per axis and a query examines few facets
    /// beyond those within its radius; enlarged when needed so the grid has at most `max(8·n_facets, 4096)` cells
    /// (and never more than [`MAX_CELLS`]).
    pub fn fit(
        lo: [f64; 3],
        hi: [f64; 3],
        radius: f64,
        facet_extent: f64,
        n_facets: usize,
        dim: u32,
    ) -> Result<Self> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(Error::BadParameter {
                name: "search radius",
                value: radius.to_string(),
                expected: "must be finite and positive",
            });
        }
        let axes = dim as usize;
        // The frame is the master's lower corner snapped down to a multiple of a power of two
        // q (about 1/16 of the master's extent), so that coordinates with few significant bits
        // (structured meshes, nodes exactly on edges) stay exact in it and exact ties stay
        // ties; the grid's corner, a radius below, is snapped to a multiple of a power of two
        // about 1/16 of the grid's span, so it is exact in f32 relative to the frame.
        let pow2_below = |x: f64| 2f64.powi((x / 16.0).log2().floor() as i32);
        let master_span = (0..axes).map(|a| hi[a] - lo[a]).fold(0.0, f64::max);
        let q = pow2_below(if master_span > 0.0 {
            master_span
        } else {
            radius
        });
        let span = (0..axes)
            .map(|a| hi[a] - lo[a] + 2.0 * radius)
            .fold(0.0, f64::max);
        let q_grid = pow2_below(span).max(q);
        let mut frame = [0.0; 3];
        let mut origin = [0.0; 3];
        let mut extent = [0.0; 3];
        for a in 0..axes {
            frame[a] = (lo[a] / q).floor() * q;
            origin[a] = frame[a] + ((lo[a] - radius - frame[a]) / q_grid).floor() * q_grid;
            extent[a] = hi[a] + radius - origin[a];
        }
        let budget = Self::cell_budget(n_facets) as f64;
        let mut h = Self::base_cell(radius, facet_extent);
        let cells = |h: f64| -> f64 {
            (0..axes)
                .map(|a| (extent[a] / h).floor() + 1.0)
                .product::<f64>()
        };
        if cells(h) > budget {
            let volume: f64 = (0..axes).map(|a| extent[a]).product();
            h = h.max((volume / budget).powf(1.0 / axes as f64));
            while cells(h) > budget {
                h *= 1.1;
            }
        }
        let mut dims = [1u32; 3];
        for a in 0..axes {
            dims[a] = ((extent[a] / h).floor() as u32 + 1).max(1);
        }
        Ok(Self {
            frame,
            origin,
            cell_size: h,
            dims,
        })
    }

    /// The grid's lower corner relative to the frame (`SearchParams::grid_lo`), f32.
    pub fn lo_in_frame(&self) -> [f32; 3] {
        [0, 1, 2].map(|a| (self.origin[a] - self.frame[a]) as f32)
    }

    /// The most cells a grid over `n_facets` facets may have: `max(8·n_facets, 4096)`, at most
    /// [`MAX_CELLS`].
    pub fn cell_budget(n_facets: usize) -> u32 {
        (8 * n_facets as u64).clamp(4096, MAX_CELLS) as u32
    }

    /// The cell size before the cell budget is applied: half of `facet_extent + 2·radius`, but
    /// at least `facet_extent`.
    pub fn base_cell(radius: f64, facet_extent: f64) -> f64 {
        (0.5 * (facet_extent + 2.0 * radius)).max(facet_extent)
    }

    /// Number of cells.
    pub fn n_cells(&self) -> u32 {
        self.dims[0] * self.dims[1] * self.dims[2]
    }
}
