//! CPU mirror of `shaders/bin_scatter.wgsl`: write facet ids into their cells.

use super::common::{facet_cells, facet_collapsed, for_each_cell};
use crate::search::layout::{
    SearchParams, FLAG_RESIDENT, STATUS_COLLAPSED, STATUS_NEEDED_ENTRIES, STATUS_OVERFLOW,
    STATUS_SPILLED,
};

/// One "invocation" per word of `starts` up to n_cells: the cursors from the starts, and the
/// spill emptied (WGSL: `copy_starts`).
pub fn copy_starts(params: &SearchParams, starts: &[u32], cursor: &mut [u32], entries: &mut [u32]) {
    let n = params.n_cells as usize + 1;
    cursor[..n].copy_from_slice(&starts[..n]);
    entries[params.entry_capacity as usize] = 0;
}

/// One "invocation" per facet. `cursor` starts as a copy of `starts`; `entries` holds
/// `entry_capacity` bin words, the spill count, then room for every facet. An entry past the
/// capacity is not written and its facet spills (once); outside a device-resident increment
/// the overflow is raised for the host to grow and run again. A facet collapsed at `nodes` is
/// neither binned nor spilled, and is counted in `STATUS_COLLAPSED`.
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
    let cap = params.entry_capacity;
    if params.n_facets > 0 && total > cap {
        status[STATUS_NEEDED_ENTRIES] = status[STATUS_NEEDED_ENTRIES].max(total);
        if params.flags & FLAG_RESIDENT == 0 {
            status[STATUS_OVERFLOW] = 1;
        }
    }
    for f in 0..params.n_facets as usize {
        if facet_collapsed(nodes, facets[f]) {
            status[STATUS_COLLAPSED] += 1;
            continue;
        }
        let (lo, hi) = facet_cells(params, nodes, facets[f]);
        let mut spilled = false;
        for_each_cell(params, lo, hi, |c| {
            let slot = cursor[c as usize];
            cursor[c as usize] += 1;
            if slot < cap {
                entries[slot as usize] = f as u32;
            } else {
                spilled = true;
            }
        });
        if spilled {
            let k = entries[cap as usize];
            entries[cap as usize] += 1;
            entries[(cap + 1 + k) as usize] = f as u32;
            status[STATUS_SPILLED] += 1;
        }
    }
}
