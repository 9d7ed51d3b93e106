// bin_count.wgsl — step 1 of the bucket sort: count the facets overlapping each grid cell.
// CPU mirror: src/cpu/bin_count.rs.
//
// Bindings: 0 params (uniform SearchParams), 1 nodes (grid-local xyz, w unused),
//           2 facets (active facets, padded node ids), 3 counts (n_cells + 1 words, zeroed
//           by the host before the pass; word n_cells stays 0 so the scan's last entry is the
//           total).
// Dispatch: one invocation per active facet, ITEM_WORKGROUP per workgroup, folded into 2D;
//           clear_counts (device-resident increments, instead of the host's clear) one per
//           word of counts up to cell_capacity + 1, indirect from the plan.
// Invariants: a facet is counted once in every cell its bounding box, grown by bin_margin
//             (≥ the search radius), overlaps; counts are order-independent integers, so the
//             result is deterministic. A facet collapsed at these positions (facet_collapsed)
//             is not binned: no slave finds it (bin_scatter counts it).

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read_write> counts: array<atomic<u32>>;

@compute @workgroup_size(64)
fn bin_count(@builtin(workgroup_id) wg: vec3<u32>,
             @builtin(num_workgroups) nwg: vec3<u32>,
             @builtin(local_invocation_index) li: u32) {
    let f = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (f >= params.n_facets) { return; }
    let fac = facets[f];
    let n = facet_node_count(fac);
    let x0 = nodes[fac.x].xyz;
    let x1 = nodes[fac.y].xyz;
    var x2 = x1;
    var x3 = x1;
    if (n >= 3u) { x2 = nodes[fac.z].xyz; }
    if (n == 4u) { x3 = nodes[fac.w].xyz; }
    if (facet_collapsed(x0, x1, x2, x3, n)) { return; }
    let r = facet_cells(params, x0, x1, x2, x3, n);
    for (var z = r.lo.z; z <= r.hi.z; z++) {
        for (var y = r.lo.y; y <= r.hi.y; y++) {
            for (var x = r.lo.x; x <= r.hi.x; x++) {
                atomicAdd(&counts[cell_index(params, vec3<u32>(x, y, z))], 1u);
            }
        }
    }
}

@compute @workgroup_size(64)
fn clear_counts(@builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    let c = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (c > params.cell_capacity) { return; }
    atomicStore(&counts[c], 0u);
}
