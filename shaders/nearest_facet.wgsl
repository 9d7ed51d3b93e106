// nearest_facet.wgsl — step 4: the globally nearest active facet of each slave node, with work
// per invocation bounded by CANDIDATE_CHUNK projections however many facets share a cell.
// CPU mirror: src/cpu/nearest_facet.rs.
// Prelude: common.wgsl, search_common.wgsl (projection, self-contact exclusion, free edges).
//
// A slave's candidates are the facets binned in its cell (as far as the entry buffer holds
// them) and the spill (facets whose entries did not fit: bin_scatter.wgsl); they are cut into chunks of
// CANDIDATE_CHUNK, and each (slave, chunk) pair is one work item. The passes, in order:
//   nearest_count    one invocation per slave: its cell's candidate count, its chunk count into
//                    `work` (then scanned by scan.wgsl into each slave's first work item), and its
//                    `best` record reset (radius², NO_FACET, not crowded, the candidate count).
//   nearest_args     one invocation: the indirect dispatch of the work items (folded into 2D).
//   nearest_chunks   one invocation per work item (indirect): the chunk's nearest facet; a slave
//                    of one chunk stores it, a slave of several lowers its best distance (atomicMin
//                    on the bits of a non-negative f32, which order as the values).
//   nearest_ties     per work item (indirect), slaves of several chunks only: a chunk whose nearest
//                    facet is at the best distance offers its id (atomicMin): the lowest id wins.
//   nearest_crowded  per work item (indirect), self-contact only: flags a slave with another
//                    facet near and facing it (see below).
//   nearest_facet    one invocation per slave: the hit from the winning facet.
//
// Dispatch: nearest_count and nearest_facet one invocation per slave, nearest_args one, the chunk
//           passes one per work item through the indirect arguments; ITEM_WORKGROUP per
//           workgroup, folded into 2D.
// Bindings: 0 params, 1 nodes, 2 facets, 3 slaves (node id per slave), 4 starts (cell starts),
//           5 entries (bins, then the spill), 6 status (self-contact crowding counted), 7 hits
//           (one Hit per slave), 8 adjacency (as in local_search.wgsl; self-contact and free
//           edges), 9 work (chunk counts, scanned to first work items; word n_slaves: total),
//           10 best (4 words per slave: distance² bits, facet, crowded, candidates), 11 args
//           (the indirect dispatch: x, y, z). Each entry point binds the subset it uses.
// Invariants: every facet within the radius of a node is binned in the node's cell (bins are
//             grown by bin_margin ≥ radius), so looking in that one cell is exact. The nearest
//             facet is the one at the least distance, ties to the lowest facet id, decided by
//             comparison (the order of a cell's entries does not matter, so the bins need no
//             sort); the tracked node is the facet node nearest the slave node, ties to the
//             lowest node id. A node outside the grid, or with no facet within the radius, gets
//             facet = NO_FACET. With FLAG_SELF_CONTACT a slave's own facets and the facets
//             touching them are skipped, and a slave with another facet within the radius that
//             shares no node with its nearest and faces it (its gap is more than half its
//             distance: not a neighbour in the same plane) is counted in STATUS_CROWDED (the
//             schedule then searches globally more often). A slave nearest to a free edge or
//             corner of the master and off to its side gets HIT_BESIDE_FREE_EDGE in its
//             candidates word: the master ends there. No loop runs over more than
//             CANDIDATE_CHUNK candidates, or 32 steps of the work item's binary search.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> slaves: array<u32>;
@group(0) @binding(4) var<storage, read> starts: array<u32>;
@group(0) @binding(5) var<storage, read> entries: array<u32>;
@group(0) @binding(6) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(8) var<storage, read> adjacency: array<u32>;
@group(0) @binding(9) var<storage, read_write> work: array<u32>;
@group(0) @binding(10) var<storage, read_write> best: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> args: array<u32>;

// Candidates one work item projects at most (Rust twin: CANDIDATE_CHUNK): large enough that
// a slave of an ordinary grid cell is one work item (the ties pass then costs nothing), far below
// the 65,535 iterations where Mesa stops a loop.
const CANDIDATE_CHUNK: u32 = 1024u;
// Workgroups per dimension of the indirect dispatch before folding into y (WebGPU's default).
const MAX_GROUPS_PER_DIM: u32 = 65535u;

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

// The candidates of a node: the written bin entries of its cell, then the spill.
struct Candidates {
    start: u32,   // first bin entry of the cell
    in_cell: u32, // written entries of the cell (those within entry_capacity)
    n: u32,       // in_cell + the spill
}

// The candidates of a node at p; none outside the grid (no facet within the radius there).
fn candidates(p: vec3<f32>) -> Candidates {
    var r: Candidates;
    r.start = 0u;
    r.in_cell = 0u;
    r.n = 0u;
    let g = (p - grid_lo(params)) * params.inv_cell_size;
    let inside = g.x >= 0.0 && g.y >= 0.0 && g.z >= 0.0
        && g.x < f32(params.dims_x) && g.y < f32(params.dims_y) && g.z < f32(params.dims_z);
    if (!inside) { return r; }
    let c = cell_index(params, vec3<u32>(u32(g.x), u32(g.y), u32(g.z)));
    let cap = params.entry_capacity;
    r.start = min(starts[c], cap);
    r.in_cell = min(starts[c + 1u], cap) - r.start;
    r.n = r.in_cell + entries[cap];
    return r;
}

// Candidate k of a node's candidates c: a facet id.
fn candidate(c: Candidates, k: u32) -> u32 {
    if (k < c.in_cell) { return entries[c.start + k]; }
    return entries[params.entry_capacity + 1u + k - c.in_cell];
}

// The slave of work item t: the largest i with work[i] ≤ t (work is its first item).
fn work_slave(t: u32) -> u32 {
    var lo = 0u;
    var hi = params.n_slaves; // work[lo] ≤ t < work[hi]
    for (var step = 0u; step < 32u && hi - lo > 1u; step++) {
        let mid = (lo + hi) / 2u;
        if (work[mid] <= t) { lo = mid; } else { hi = mid; }
    }
    return lo;
}

// The candidates work item t of slave i (candidates c) covers: at most CANDIDATE_CHUNK.
fn chunk_range(i: u32, t: u32, c: Candidates) -> vec2<u32> {
    let k0 = (t - work[i]) * CANDIDATE_CHUNK;
    return vec2<u32>(k0, min(c.n, k0 + CANDIDATE_CHUNK));
}

struct ChunkBest {
    d2: f32,
    f: u32,
}

// The nearest facet (within the radius, ties to the lowest id) of slave i among the candidates
// of its work item t.
fn chunk_best(i: u32, t: u32) -> ChunkBest {
    let slave = slaves[i];
    let p = nodes[slave].xyz;
    let c = candidates(p);
    let r = chunk_range(i, t, c);
    var b: ChunkBest;
    b.d2 = params.radius * params.radius;
    b.f = NO_FACET;
    for (var k = r.x; k < r.y; k++) {
        let f = candidate(c, k);
        if (excluded(slave, facets[f])) { continue; }
        let d2 = project_facet(p, facets[f]).dist2;
        if (d2 < b.d2 || (d2 == b.d2 && f < b.f)) {
            b.d2 = d2;
            b.f = f;
        }
    }
    return b;
}

@compute @workgroup_size(64)
fn nearest_count(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= params.n_slaves) { return; }
    if (i == 0u) { work[params.n_slaves] = 0u; }
    let count = candidates(nodes[slaves[i]].xyz).n;
    work[i] = (count + CANDIDATE_CHUNK - 1u) / CANDIDATE_CHUNK;
    atomicStore(&best[4u * i], bitcast<u32>(params.radius * params.radius));
    atomicStore(&best[4u * i + 1u], NO_FACET);
    atomicStore(&best[4u * i + 2u], 0u);
    atomicStore(&best[4u * i + 3u], count);
}

@compute @workgroup_size(1)
fn nearest_args() {
    let groups = (work[params.n_slaves] + ITEM_WORKGROUP - 1u) / ITEM_WORKGROUP;
    let x = min(groups, MAX_GROUPS_PER_DIM);
    args[0] = x;
    args[1] = select(0u, (groups + x - 1u) / max(x, 1u), x > 0u);
    args[2] = 1u;
}

@compute @workgroup_size(64)
fn nearest_chunks(@builtin(workgroup_id) wg: vec3<u32>,
                  @builtin(num_workgroups) nwg: vec3<u32>,
                  @builtin(local_invocation_index) li: u32) {
    let t = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (t >= work[params.n_slaves]) { return; }
    let i = work_slave(t);
    let b = chunk_best(i, t);
    if (b.f == NO_FACET) { return; }
    if (work[i + 1u] - work[i] == 1u) {
        atomicStore(&best[4u * i], bitcast<u32>(b.d2));
        atomicStore(&best[4u * i + 1u], b.f);
    } else {
        atomicMin(&best[4u * i], bitcast<u32>(b.d2));
    }
}

@compute @workgroup_size(64)
fn nearest_ties(@builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    let t = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (t >= work[params.n_slaves]) { return; }
    let i = work_slave(t);
    if (work[i + 1u] - work[i] == 1u) { return; }
    let b = chunk_best(i, t);
    if (b.f != NO_FACET && bitcast<u32>(b.d2) == atomicLoad(&best[4u * i])) {
        atomicMin(&best[4u * i + 1u], b.f);
    }
}

@compute @workgroup_size(64)
fn nearest_crowded(@builtin(workgroup_id) wg: vec3<u32>,
                   @builtin(num_workgroups) nwg: vec3<u32>,
                   @builtin(local_invocation_index) li: u32) {
    let t = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if ((params.flags & FLAG_SELF_CONTACT) == 0u || t >= work[params.n_slaves]) { return; }
    let i = work_slave(t);
    let best_f = atomicLoad(&best[4u * i + 1u]);
    if (best_f == NO_FACET) { return; }
    let slave = slaves[i];
    let p = nodes[slave].xyz;
    let c = candidates(p);
    let r = chunk_range(i, t, c);
    let r2 = params.radius * params.radius;
    for (var k = r.x; k < r.y; k++) {
        let f = candidate(c, k);
        if (f == best_f || excluded(slave, facets[f]) || share_node(facets[f], facets[best_f])) { continue; }
        // near and facing the slave (not merely beside it in its own plane)
        let pr = project_facet(p, facets[f]);
        let gap = dot(p - pr.point, pr.normal);
        if (pr.dist2 <= r2 && 4.0 * gap * gap > pr.dist2) {
            atomicStore(&best[4u * i + 2u], 1u);
            return;
        }
    }
}

@compute @workgroup_size(64)
fn nearest_facet(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= params.n_slaves) { return; }
    var hit: Hit;
    hit.facet = NO_FACET;
    hit.node = NO_NODE;
    hit.candidates = atomicLoad(&best[4u * i + 3u]);
    hit.slave = slaves[i];
    hit.point_gap = vec4<f32>(0.0);
    hit.normal_dist = vec4<f32>(0.0);
    hit.weights = vec4<f32>(0.0);
    let p = nodes[slaves[i]].xyz;
    let best_f = atomicLoad(&best[4u * i + 1u]);
    if (best_f != NO_FACET) {
        if (atomicLoad(&best[4u * i + 2u]) != 0u) { atomicAdd(&status[STATUS_CROWDED], 1u); }
        let fac = facets[best_f];
        let pr = project_facet(p, fac);
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
        hit.point_gap = vec4<f32>(pr.point, dot(p - pr.point, pr.normal));
        hit.normal_dist = vec4<f32>(pr.normal, sqrt(pr.dist2));
        hit.weights = pr.weights;
        if (beside_free_edge(best_f, fac, pr.weights, p, pr.point, pr.normal)) {
            hit.candidates |= HIT_BESIDE_FREE_EDGE;
        }
    }
    hits[i] = hit;
}
