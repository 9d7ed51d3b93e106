//! CPU mirror of `shaders/bin_scatter.wgsl`: write facet ids into their cells.

use super::common::{facet_cells, for_each_cell};
use crate::search::layout::{SearchParams, STATUS_NEEDED_ENTRIES, STATUS_OVERFLOW};

/// One "invocation" per facet. `cursor` starts as a copy of `starts`. On overflow nothing is
/// written and the status words say how many entries are needed.
pub fn bin_scatter(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    starts: &[u32],
    cursor: &mut [u32],
    entries: &mut [u32],
    status: &mut [u32],
) {
    let total = starts[params.n_cells as usize];
    if total > params.entry_capacity {
        status[STATUS_OVERFLOW] = 1;
        status[STATUS_NEEDED_ENTRIES] = status[STATUS_NEEDED_ENTRIES].max(total);
        return;
    }
    for f in 0..params.n_facets as usize {
        let (lo, hi) = facet_cells(params, nodes, facets[f]);
        for_each_cell(params, lo, hi, |c| {
            let slot = cursor[c as usize];
            cursor[c as usize] += 1;
            entries[slot as usize] = f as u32;
        });
    }
}
