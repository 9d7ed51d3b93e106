// nodal_normals.wgsl — smoothed unit normal of the master nodes at the current positions: of
// every master node (small sliding), or of those a spring reads this increment.
// CPU mirror: src/cpu/nodal_normals.rs.
//
// Bindings: 0 pp (uniform PenaltyParams), 1 nodes, 2 facets, 3 pair_nodes (node, slave index,
//           adjacency start, end), 4 adjacency (active facet indices, increasing per node),
//           5 normals (vec4 per model node; only master nodes are written), 6 need (NEED_* bits
//           per pair node and rigid slot: need_normals sets NEED_NORMAL, add_forces clears the
//           word), 7 hits, 8 status (from ACTIVE_LIST the active slaves, active.wgsl),
//           9 facet_nodes (pair-node index of each active facet's nodes, NO_NODE padded).
// Dispatch: nodal_normals and nodal_normals_needed one invocation per pair node; need_normals
//           one per slave (global increments, when the active list was just compacted) or per
//           active slave (local increments), indirect from the plan, reading the active list
//           either way; ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: a node's normal is the normalised sum of the area-weighted normals of its active
//             facets, summed in increasing facet order (deterministic, whichever pass computes
//             it); nodes on no facet keep their previous value (never read). The springs of a
//             pair (penalty.wgsl) read the normals of their facet's nodes only: need_normals
//             marks those of every active slave with a facet — a slave with a facet is tracked,
//             so in the active list — and nodal_normals_needed computes those alone, so a master
//             node far from every contact costs its need word. A slave of a pair with
//             PENALTY_SLAVES_APART reads nothing (it is on no facet).

@group(0) @binding(0) var<uniform> pp: PenaltyParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> pair_nodes: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> adjacency: array<u32>;
@group(0) @binding(5) var<storage, read_write> normals: array<vec4<f32>>;
@group(0) @binding(6) var<storage, read_write> need: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read> hits: array<Hit>;
@group(0) @binding(8) var<storage, read> status: array<u32>;
@group(0) @binding(9) var<storage, read> facet_nodes: array<vec4<u32>>;

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

// Pair node i's normal (a master node: on at least one active facet).
fn node_normal(i: u32) {
    let pn = pair_nodes[i];
    if (pn.z == pn.w) { return; }
    var sum = vec3<f32>(0.0);
    for (var a = pn.z; a < pn.w; a++) {
        sum += facet_area_normal(facets[adjacency[a]]);
    }
    normals[pn.x] = vec4<f32>(normalize_or_zero(sum), 0.0);
}

// Whether pair node i is a slave of a pair whose slaves are no master nodes (no normal).
fn apart_slave(i: u32) -> bool {
    return i < pp.n_slaves && (pp.flags & PENALTY_SLAVES_APART) != 0u;
}

// Small sliding: every master node's normal.
@compute @workgroup_size(64)
fn nodal_normals(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= pp.n_pair_nodes || apart_slave(i)) { return; }
    node_normal(i);
}

// The facet nodes of each active slave with a facet marked NEED_NORMAL.
@compute @workgroup_size(64)
fn need_normals(@builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    let k = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (k >= status[ACTIVE_LIST]) { return; }
    let facet = hits[status[ACTIVE_LIST + 1u + k]].facet;
    if (facet >= pp.n_facets) { return; }
    let fac = facet_nodes[facet];
    let n = facet_node_count(fac);
    for (var j = 0u; j < n; j++) {
        atomicOr(&need[fac[j]], NEED_NORMAL);
    }
}

// The normals the springs read this increment: of the pair nodes marked NEED_NORMAL.
@compute @workgroup_size(64)
fn nodal_normals_needed(@builtin(workgroup_id) wg: vec3<u32>,
                        @builtin(num_workgroups) nwg: vec3<u32>,
                        @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= pp.n_pair_nodes || apart_slave(i)) { return; }
    if ((atomicLoad(&need[i]) & NEED_NORMAL) == 0u) { return; }
    node_normal(i);
}
