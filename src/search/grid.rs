//! The uniform bucket grid of the global search, sized on the host.

use crate::error::{Error, Result};

/// Largest number of cells a grid may have.
pub const MAX_CELLS: u64 = 1 << 24;

/// A uniform grid of cubic cells covering the master surface's bounding box grown by the
/// search radius. Its origin is the frame the GPU works in: coordinates are stored relative to
/// it in f32, so a small mesh far from the model origin keeps its precision.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// Lower corner in model coordinates (f64).
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
        // The origin is snapped down to a multiple of a power of two q (about 1/16 of the
        // extent), so that coordinates with few significant bits (structured meshes, nodes
        // exactly on edges) stay exact in the local frame and exact ties stay ties.
        let span = (0..axes)
            .map(|a| hi[a] - lo[a] + 2.0 * radius)
            .fold(0.0, f64::max);
        let q = 2f64.powi((span / 16.0).log2().floor() as i32);
        let mut origin = [0.0; 3];
        let mut extent = [0.0; 3];
        for a in 0..axes {
            origin[a] = ((lo[a] - radius) / q).floor() * q;
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
            origin,
            cell_size: h,
            dims,
        })
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
