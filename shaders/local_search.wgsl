// local_search.wgsl — finite-sliding tracking between global searches (seed: "Local contact
// searches"). CPU mirror: src/cpu/local_search.rs.
// Prelude: common.wgsl, search_common.wgsl (projection, self-contact exclusion, free edges).
//
// Bindings: 0 params (uniform SearchParams), 1 nodes (in the frame of the last
//           global search), 2 facets, 3 slaves, 4 adjacency (words 0..=n_nodes: start of each
//           model node's active facets within this same buffer; then the lists, increasing),
//           5 status (atomic words; from ACTIVE_LIST the active slaves: active.wgsl),
//           6 hits (read: the tracked node; written: the result), 7 reference (the motion
//           budget's; written, where the slave crossed the radius: the w of the slave's, its
//           tracking state for motion.wgsl).
// Dispatch: one invocation per active slave (the slaves the last global search left tracked),
//           ITEM_WORKGROUP per workgroup, folded into 2D, indirect from the plan's ACTIVE_SLOT.
// Invariants: a slave looks only at the facets attached to its tracked master node (with
//             FLAG_WIDE_LOCAL, also at the facets around every node of the nearest of those,
//             which finds the nearest facet where it touches no node nearest the slave, as with
//             obtuse triangles), takes the nearest
//             (ties: lowest id), moves the tracked node to that facet's node nearest the slave
//             (ties: lowest id), and repeats until the tracked node stays, at most
//             max_local_iterations times; the most iterations taken and the number of slaves
//             that hit the cap are reduced into the status words. A slave beyond the radius
//             keeps its tracked node (facet = NO_FACET) so tracking resumes when it comes back;
//             a slave with no tracked node (every slave is visited with FLAG_EVERY_SLAVE) keeps
//             the global search's hit: it is beyond radius + budget, and the motion budget
//             asks for a global search before it can come within the radius. Nothing runs when
//             the motion budget is exceeded (the increment is run again with a global search).
//             A slave nearest to a free edge or corner of the master and off to its side gets
//             HIT_BESIDE_FREE_EDGE in its candidates word (as in nearest_facet.wgsl). A facet
//             collapsed at the current positions is passed over (facet_collapsed). Projections
//             start from the facet the last search found; a facet whose nodes' box is farther
//             than the best by more than round-off (PRUNE_SLACK) is counted, not projected, and
//             the best carries from one step of the walk to the next: the hit, the facets
//             counted and the steps are those of projecting every facet every step.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> slaves: array<u32>;
@group(0) @binding(4) var<storage, read> adjacency: array<u32>;
@group(0) @binding(5) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(7) var<storage, read_write> reference: array<vec4<f32>>;

struct Best {
    facet: u32,
    d2: f32,
    pr: Projection,
    candidates: u32,
}

// Facet f around the slave at p: counted as examined unless excluded or collapsed; projected
// unless its nodes' box is farther than the best by more than round-off (PRUNE_SLACK: such a
// facet cannot be nearer, nor tie, so skipping it changes nothing but the time); kept when
// nearer than the best (ties: lowest id). The best facet itself is counted and not projected
// again: the same positions give the same projection.
fn consider(b: ptr<function, Best>, s: u32, p: vec3<f32>, f: u32) {
    let fac = facets[f];
    if (excluded(s, fac)) { return; }
    let pts = facet_points(fac);
    if (facet_collapsed(pts.x0, pts.x1, pts.x2, pts.x3, pts.n)) { return; }
    (*b).candidates += 1u;
    if ((*b).facet != NO_FACET && (f == (*b).facet || points_box_d2(p, pts) > (*b).d2 * PRUNE_SLACK)) {
        return;
    }
    let pr = project_points(p, pts);
    if ((*b).facet == NO_FACET || pr.dist2 < (*b).d2 || (pr.dist2 == (*b).d2 && f < (*b).facet)) {
        (*b).facet = f;
        (*b).d2 = pr.dist2;
        (*b).pr = pr;
    }
}

// Whether facet f (an active facet id, or NO_FACET) has node `node`.
fn has_node(f: u32, node: u32) -> bool {
    if (f >= params.n_facets) { return false; }
    let fac = facets[f];
    let n = facet_node_count(fac);
    for (var j = 0u; j < n; j++) {
        if (fac[j] == node) { return true; }
    }
    return false;
}

@compute @workgroup_size(64)
fn local_search(@builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    let k = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (k >= atomicLoad(&status[ACTIVE_LIST])) { return; }
    if (atomicLoad(&status[STATUS_BUDGET_EXCEEDED]) != 0u) { return; }
    let i = atomicLoad(&status[ACTIVE_LIST + 1u + k]);
    // of the last hit, the walk reads its tracked node and facet alone (8 of its 64 bytes)
    var tracked = hits[i].node;
    if (tracked == NO_NODE) { return; }
    let last = hits[i].facet;
    let s = slaves[i];
    let p = nodes[s].xyz;
    var hit: Hit;
    hit.facet = NO_FACET;
    hit.candidates = 0u;
    hit.slave = s;
    hit.point_gap = vec4<f32>(0.0);
    hit.normal_dist = vec4<f32>(0.0);
    hit.weights = vec4<f32>(0.0);
    var b: Best;
    b.facet = NO_FACET;
    b.d2 = 0.0;
    // the first projection: the facet the last search found, when it is one around the tracked
    // node (examined and counted there), so that the box test can skip the others from the start
    if (has_node(last, tracked)) {
        let pts = facet_points(facets[last]);
        if (!excluded(s, facets[last]) && !facet_collapsed(pts.x0, pts.x1, pts.x2, pts.x3, pts.n)) {
            b.facet = last;
            b.pr = project_points(p, pts);
            b.d2 = b.pr.dist2;
        }
    }
    var it = 0u;
    var settled = false;
    loop {
        // the best so far carries over: it has the new tracked node, so it is among the facets
        // examined next, and the walk's result is the nearest of those whatever the order
        for (var k = adjacency[tracked]; k < adjacency[tracked + 1u]; k++) {
            consider(&b, s, p, adjacency[k]);
        }
        if ((params.flags & FLAG_WIDE_LOCAL) != 0u && b.facet != NO_FACET) {
            // the wider search: also the facets around every node of the nearest one
            let near = facets[b.facet];
            let n = facet_node_count(near);
            for (var j = 0u; j < n; j++) {
                let node = near[j];
                if (node == tracked) { continue; }
                for (var q = adjacency[node]; q < adjacency[node + 1u]; q++) {
                    consider(&b, s, p, adjacency[q]);
                }
            }
        }
        it += 1u;
        if (b.facet == NO_FACET) { settled = true; break; }
        let fac = facets[b.facet];
        let n = facet_node_count(fac);
        var next = NO_NODE;
        var nd2 = 0.0;
        for (var j = 0u; j < n; j++) {
            let node = fac[j];
            let d = nodes[node].xyz - p;
            let d2 = dot(d, d);
            if (next == NO_NODE || d2 < nd2 || (d2 == nd2 && node < next)) {
                next = node;
                nd2 = d2;
            }
        }
        if (next == tracked) { settled = true; break; }
        tracked = next;
        if (it >= params.max_local_iterations) { break; }
    }
    atomicMax(&status[STATUS_LOCAL_ITERATIONS], it);
    if (!settled) { atomicAdd(&status[STATUS_LOCAL_CAPPED], 1u); }
    hit.candidates = b.candidates;
    hit.node = tracked;
    if (b.facet != NO_FACET && b.d2 <= params.radius * params.radius) {
        hit.facet = b.facet;
        hit.point_gap = vec4<f32>(b.pr.point, dot(p - b.pr.point, b.pr.normal));
        hit.normal_dist = vec4<f32>(b.pr.normal, sqrt(b.d2));
        hit.weights = b.pr.weights;
        if (beside_free_edge(b.facet, facets[b.facet], b.pr.weights, p, b.pr.point, b.pr.normal)) {
            hit.candidates |= HIT_BESIDE_FREE_EDGE;
        }
    }
    hits[i] = hit;
    // the state (tracked; with a facet within the radius or not) changes only where the slave
    // crossed the radius: written there alone, not a scattered write by node for every slave
    if ((hit.facet != NO_FACET) != (last != NO_FACET)) {
        reference[s].w = slave_state(hit);
    }
}
