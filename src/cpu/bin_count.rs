//! CPU mirror of `shaders/bin_count.wgsl`: count the facets overlapping each cell.

use super::common::{facet_cells, for_each_cell};
use crate::search::layout::SearchParams;

/// One "invocation" per active facet; `counts` has n_cells + 1 words, zeroed by the caller.
pub fn bin_count(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    counts: &mut [u32],
) {
    for f in 0..params.n_facets as usize {
        let (lo, hi) = facet_cells(params, nodes, facets[f]);
        for_each_cell(params, lo, hi, |c| counts[c as usize] += 1);
    }
}

/// One "invocation" per word of the counts up to the cell capacity: zeroed
/// (WGSL: `clear_counts`).
pub fn clear_counts(params: &SearchParams, counts: &mut [u32]) {
    let n = (params.cell_capacity as usize + 1).min(counts.len());
    counts[..n].iter_mut().for_each(|c| *c = 0);
}
