//! CPU mirror of `shaders/bin_count.wgsl`: count the facets overlapping each cell.

use std::sync::atomic::Ordering;

use rayon::prelude::*;

use super::common::{facet_cells, facet_collapsed, for_each_cell};
use crate::search::layout::SearchParams;

/// One "invocation" per active facet; `counts` has n_cells + 1 words, zeroed by the caller. A
/// facet collapsed at `nodes` is not counted.
pub fn bin_count(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    counts: &mut [u32],
) {
    let counts = super::as_atomic(counts);
    (0..params.n_facets as usize)
        .into_par_iter()
        .with_min_len(super::PAR_MIN)
        .for_each(|f| {
            if facet_collapsed(nodes, facets[f]) {
                return;
            }
            let (lo, hi) = facet_cells(params, nodes, facets[f]);
            for_each_cell(params, lo, hi, |c| {
                counts[c as usize].fetch_add(1, Ordering::Relaxed);
            });
        });
}

/// One "invocation" per word of the counts up to the cell capacity: zeroed
/// (WGSL: `clear_counts`).
pub fn clear_counts(params: &SearchParams, counts: &mut [u32]) {
    let n = (params.cell_capacity as usize + 1).min(counts.len());
    counts[..n].iter_mut().for_each(|c| *c = 0);
}
