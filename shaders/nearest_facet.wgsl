// nearest_facet.wgsl — step 5: the globally nearest active facet of each slave node.
// CPU mirror: src/cpu/nearest_facet.rs.
// Prelude: common.wgsl, search_common.wgsl (projection, self-contact exclusion, free edges).
//
// Bindings: 0 params, 1 nodes, 2 facets, 3 slaves (node id per slave), 4 starts, 5 entries,
//           6 status (overflow skips the pass; self-contact crowding counted), 7 hits (one Hit
//           per slave), 8 adjacency (as in local_search.wgsl; read for self-contact only).
// Dispatch: one invocation per slave node, ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: every facet within the radius of a node is binned in the node's cell (bins are
//             grown by bin_margin ≥ radius), so looking in that one cell is exact. Candidates
//             come in increasing id order and only a strictly nearer one replaces the best, so
//             exact ties go to the lowest facet id; the tracked node is the facet node nearest
//             the slave node, ties to the lowest node id. A node outside the grid, or with no
//             facet within the radius, gets facet = NO_FACET. With FLAG_SELF_CONTACT a slave's
//             own facets and the facets touching them are skipped, and a slave with another
//             facet within the radius that shares no node with its nearest and faces it (its
//             gap is more than half its distance: not a neighbour in the same plane) is counted
//             in STATUS_CROWDED (the schedule then searches globally more often). A slave
//             nearest to a free edge or corner of the master and off to its side gets
//             HIT_BESIDE_FREE_EDGE in its candidates word: the master ends there.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> slaves: array<u32>;
@group(0) @binding(4) var<storage, read> starts: array<u32>;
@group(0) @binding(5) var<storage, read> entries: array<u32>;
@group(0) @binding(6) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(8) var<storage, read> adjacency: array<u32>;

// Whether two facets share a node.
fn share_node(a: vec4<u32>, b: vec4<u32>) -> bool {
    let na = facet_node_count(a);
    let nb = facet_node_count(b);
    for (var i = 0u; i < na; i++) {
        for (var j = 0u; j < nb; j++) {
            if (a[i] == b[j]) { return true; }
        }
    }
    return false;
}

@compute @workgroup_size(64)
fn nearest_facet(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= params.n_slaves) { return; }
    if (atomicLoad(&status[STATUS_OVERFLOW]) != 0u) { return; }
    var hit: Hit;
    hit.facet = NO_FACET;
    hit.node = NO_NODE;
    hit.candidates = 0u;
    hit.slave = slaves[i];
    hit.point_gap = vec4<f32>(0.0);
    hit.normal_dist = vec4<f32>(0.0);
    hit.weights = vec4<f32>(0.0);
    let p = nodes[slaves[i]].xyz;
    let g = p * params.inv_cell_size;
    let inside = g.x >= 0.0 && g.y >= 0.0 && g.z >= 0.0
        && g.x < f32(params.dims_x) && g.y < f32(params.dims_y) && g.z < f32(params.dims_z);
    if (inside) {
        let c = cell_index(params, vec3<u32>(u32(g.x), u32(g.y), u32(g.z)));
        let s = starts[c];
        let e = starts[c + 1u];
        hit.candidates = e - s;
        var best: Projection;
        var best_f = NO_FACET;
        var best_d2 = params.radius * params.radius;
        let slave = slaves[i];
        for (var k = s; k < e; k++) {
            let f = entries[k];
            if (excluded(slave, facets[f])) { continue; }
            let pr = project_facet(p, facets[f]);
            if (pr.dist2 < best_d2 || (best_f == NO_FACET && pr.dist2 == best_d2)) {
                best = pr;
                best_d2 = pr.dist2;
                best_f = f;
            }
        }
        if (best_f != NO_FACET && (params.flags & FLAG_SELF_CONTACT) != 0u) {
            let r2 = params.radius * params.radius;
            var crowded = false;
            for (var k = s; k < e; k++) {
                let f = entries[k];
                if (f == best_f || excluded(slave, facets[f]) || share_node(facets[f], facets[best_f])) { continue; }
                // near and facing the slave (not merely beside it in its own plane)
                let pr = project_facet(p, facets[f]);
                let gap = dot(p - pr.point, pr.normal);
                if (pr.dist2 <= r2 && 4.0 * gap * gap > pr.dist2) { crowded = true; }
            }
            if (crowded) { atomicAdd(&status[STATUS_CROWDED], 1u); }
        }
        if (best_f != NO_FACET) {
            let fac = facets[best_f];
            let n = facet_node_count(fac);
            var best_node = NO_NODE;
            var best_nd2 = 0.0;
            for (var j = 0u; j < n; j++) {
                let node = fac[j];
                let d = nodes[node].xyz - p;
                let d2 = dot(d, d);
                if (best_node == NO_NODE || d2 < best_nd2 || (d2 == best_nd2 && node < best_node)) {
                    best_node = node;
                    best_nd2 = d2;
                }
            }
            hit.facet = best_f;
            hit.node = best_node;
            hit.point_gap = vec4<f32>(best.point, dot(p - best.point, best.normal));
            hit.normal_dist = vec4<f32>(best.normal, sqrt(best.dist2));
            hit.weights = best.weights;
            if (beside_free_edge(best_f, fac, best.weights, p, best.point, best.normal)) {
                hit.candidates |= HIT_BESIDE_FREE_EDGE;
            }
        }
    }
    hits[i] = hit;
}
