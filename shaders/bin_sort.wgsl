// bin_sort.wgsl — step 4 of the bucket sort: order each cell's facet ids increasingly.
// CPU mirror: src/cpu/bin_sort.rs.
//
// Bindings: 0 params, 1 starts (scanned counts), 2 entries.
// Dispatch: one invocation per cell, ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: after this pass the entries equal those of a stable counting sort of
//             (cell, facet) by cell, independent of how bin_scatter was scheduled; the
//             nearest-facet query therefore meets candidates in increasing id order, which is
//             how ties go to the lowest facet id. Skipped when the binning overflowed.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> starts: array<u32>;
@group(0) @binding(2) var<storage, read_write> entries: array<u32>;

@compute @workgroup_size(64)
fn bin_sort(@builtin(workgroup_id) wg: vec3<u32>,
            @builtin(num_workgroups) nwg: vec3<u32>,
            @builtin(local_invocation_index) li: u32) {
    let c = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (c >= params.n_cells) { return; }
    if (starts[params.n_cells] > params.entry_capacity) { return; }
    let s = starts[c];
    let e = starts[c + 1u];
    // insertion sort: cells hold few facets by construction of the grid
    for (var i = s + 1u; i < e; i++) {
        let key = entries[i];
        var j = i;
        while (j > s && entries[j - 1u] > key) {
            entries[j] = entries[j - 1u];
            j--;
        }
        entries[j] = key;
    }
}
