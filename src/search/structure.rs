//! The global search's structure, chosen per pair: the tree or the seed's buckets
//! ([`SearchStructure`]), and the facet size the buckets' cells follow.

use super::*;

impl SearchStage {
    /// Sets the global search's structure. Results do not depend on it. `Auto` chooses the
    /// tree: `abut bench --search` (docs/BENCHMARKS.md, 2026-12-04) measured it faster than the
    /// buckets on the CPU path, lavapipe and llvmpipe at every radius (0.5, 1 and 3 facets): on
    /// the wavy plate of uniform facets by 1.8–2.3× on the CPU path and 4.4–7.5× on the
    /// adapters, on the graded one by 230–320×; no facet-size spread or radius measured there
    /// justifies the buckets.
    pub fn set_search_structure(&mut self, structure: SearchStructure) {
        self.structure = match structure {
            SearchStructure::Auto => SearchStructure::Tree,
            chosen => chosen,
        };
        // the plan holds the flags: the next increment makes a fresh one
        self.resident_origin = None;
    }

    /// The global search's structure in use (`Buckets` or `Tree`).
    pub fn search_structure(&self) -> SearchStructure {
        self.structure
    }

    /// The largest side of an active facet's nodes' box at the model's positions (model
    /// units): the bucket search's cells are sized to it.
    pub fn largest_facet(&self) -> f64 {
        self.largest_facet
    }
}

/// The largest side of the nodes' box of any of `facets` (padded) at `positions`.
pub(super) fn largest_facet(facets: &[[u32; 4]], positions: &[[f64; 3]]) -> f64 {
    facets
        .iter()
        .map(|fac| {
            let n = crate::model::facet_node_count(*fac);
            (0..3)
                .map(|a| {
                    let xs = fac[..n].iter().map(|&id| positions[id as usize][a]);
                    let lo = xs.clone().fold(f64::INFINITY, f64::min);
                    let hi = xs.fold(f64::NEG_INFINITY, f64::max);
                    hi - lo
                })
                .fold(0.0, f64::max)
        })
        .fold(0.0, f64::max)
}
