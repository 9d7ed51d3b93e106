// bin_scatter.wgsl — step 3 of the bucket sort: write each facet id into the cells it overlaps.
// CPU mirror: src/cpu/bin_scatter.rs.
//
// Bindings: 0 params, 1 nodes, 2 facets, 3 starts (scanned counts: cell c owns entries
//           starts[c]..starts[c+1], starts[n_cells] = total), 4 cursor (copy of starts, bumped
//           atomically), 5 entries (entry_capacity words of bins, then the spill: its count at
//           word entry_capacity and up to n_facets facet ids after it), 6 status (atomic words,
//           STATUS_*).
// Dispatch: bin_scatter one invocation per active facet; copy_starts one per word of starts up
//           to n_cells + 1 (it also empties the spill); ITEM_WORKGROUP per workgroup, folded
//           into 2D.
// Invariants: an entry whose slot lies past entry_capacity is not written and its facet is
//             appended to the spill (once), which every slave examines besides its cell: the
//             search stays exact whatever the capacity. STATUS_SPILLED counts the spilled facets
//             and STATUS_NEEDED_ENTRIES holds the total; outside a device-resident increment
//             (FLAG_RESIDENT) STATUS_OVERFLOW is set too, and the host grows the buffer and runs
//             the search again. The order within a cell and in the spill depends on scheduling;
//             nothing downstream depends on it (nearest_facet breaks ties by facet id). A facet
//             collapsed at these positions is neither binned nor spilled, and is counted in
//             STATUS_COLLAPSED.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> starts: array<u32>;
@group(0) @binding(4) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> entries: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> status: array<atomic<u32>>;

@compute @workgroup_size(64)
fn copy_starts(@builtin(workgroup_id) wg: vec3<u32>,
               @builtin(num_workgroups) nwg: vec3<u32>,
               @builtin(local_invocation_index) li: u32) {
    let c = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (c > params.n_cells) { return; }
    atomicStore(&cursor[c], starts[c]);
    if (c == 0u) { atomicStore(&entries[params.entry_capacity], 0u); }
}

@compute @workgroup_size(64)
fn bin_scatter(@builtin(workgroup_id) wg: vec3<u32>,
               @builtin(num_workgroups) nwg: vec3<u32>,
               @builtin(local_invocation_index) li: u32) {
    let f = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (f >= params.n_facets) { return; }
    let total = starts[params.n_cells];
    if (f == 0u && total > params.entry_capacity) {
        atomicMax(&status[STATUS_NEEDED_ENTRIES], total);
        if ((params.flags & FLAG_RESIDENT) == 0u) { atomicStore(&status[STATUS_OVERFLOW], 1u); }
    }
    let fac = facets[f];
    let n = facet_node_count(fac);
    let x0 = nodes[fac.x].xyz;
    let x1 = nodes[fac.y].xyz;
    var x2 = x1;
    var x3 = x1;
    if (n >= 3u) { x2 = nodes[fac.z].xyz; }
    if (n == 4u) { x3 = nodes[fac.w].xyz; }
    if (facet_collapsed(x0, x1, x2, x3, n)) {
        atomicAdd(&status[STATUS_COLLAPSED], 1u);
        return;
    }
    let r = facet_cells(params, x0, x1, x2, x3, n);
    var spilled = false;
    for (var z = r.lo.z; z <= r.hi.z; z++) {
        for (var y = r.lo.y; y <= r.hi.y; y++) {
            for (var x = r.lo.x; x <= r.hi.x; x++) {
                let slot = atomicAdd(&cursor[cell_index(params, vec3<u32>(x, y, z))], 1u);
                if (slot < params.entry_capacity) {
                    atomicStore(&entries[slot], f);
                } else {
                    spilled = true;
                }
            }
        }
    }
    if (spilled) {
        let k = atomicAdd(&entries[params.entry_capacity], 1u);
        atomicStore(&entries[params.entry_capacity + 1u + k], f);
        atomicAdd(&status[STATUS_SPILLED], 1u);
    }
}
