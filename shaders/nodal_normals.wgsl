// nodal_normals.wgsl — smoothed unit normal of each master node at the current positions.
// CPU mirror: src/cpu/nodal_normals.rs.
//
// Bindings: 0 pp (uniform PenaltyParams), 1 nodes, 2 facets, 3 pair_nodes (node, slave index,
//           adjacency start, end), 4 adjacency (active facet indices, increasing per node),
//           5 normals (vec4 per model node; only master nodes are written).
// Dispatch: one invocation per pair node, ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: a slave of a pair with PENALTY_SLAVES_APART reads nothing (it is on no facet); a node's normal is the normalised sum of the area-weighted normals of its active
//             facets, summed in increasing facet order (deterministic); nodes on no facet keep
//             their previous value (never read).

@group(0) @binding(0) var<uniform> pp: PenaltyParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> pair_nodes: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> adjacency: array<u32>;
@group(0) @binding(5) var<storage, read_write> normals: array<vec4<f32>>;

// Area vector of a facet (length-weighted normal for a segment).
fn facet_area_normal(fac: vec4<u32>) -> vec3<f32> {
    let x0 = nodes[fac.x].xyz;
    let x1 = nodes[fac.y].xyz;
    let n = facet_node_count(fac);
    if (n == 2u) {
        let t = x1 - x0;
        return vec3<f32>(t.y, -t.x, 0.0);
    }
    let x2 = nodes[fac.z].xyz;
    if (n == 3u) {
        return 0.5 * cross(x1 - x0, x2 - x0);
    }
    return 0.5 * cross(x2 - x0, nodes[fac.w].xyz - x1);
}

@compute @workgroup_size(64)
fn nodal_normals(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= pp.n_pair_nodes) { return; }
    // a pair whose slaves are no master nodes: the slaves (the first pair nodes) have no normal
    if (i < pp.n_slaves && (pp.flags & PENALTY_SLAVES_APART) != 0u) { return; }
    let pn = pair_nodes[i];
    if (pn.z == pn.w) { return; }
    var sum = vec3<f32>(0.0);
    for (var a = pn.z; a < pn.w; a++) {
        sum += facet_area_normal(facets[adjacency[a]]);
    }
    normals[pn.x] = vec4<f32>(normalize_or_zero(sum), 0.0);
}
