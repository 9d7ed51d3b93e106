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
//           tracking state for motion.wgsl), 8 skins (per slave: its position relative to the
//           reference node at its last settled walk, xyz, and the margin that walk left, w).
// Dispatch: one invocation per active slave (the slaves the last global search left tracked),
//           ITEM_WORKGROUP per workgroup, folded into 2D, indirect from the plan's ACTIVE_SLOT.
// Invariants: a slave looks only at the facets attached to its tracked master node (with
//             FLAG_WIDE_LOCAL, also at the facets around every node of the nearest of those,
//             which finds the nearest facet where it touches no node nearest the slave, as with
//             obtuse triangles), takes the nearest
//             (ties: lowest id), moves the tracked node to that facet's node nearest the slave
//             (ties: lowest id), and repeats until the tracked node stays, at most
//             max_local_iterations times; the most iterations taken and the number of slaves
//             that hit the cap are reduced into the status words (in the workgroup first, then
//             one global atomic per word and workgroup). A slave beyond the radius
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
//             counted (in the walk's last step) and the steps are those of projecting every facet
//             every step.
//
// The skin: a settled walk that ends on facet F keeps, in the slave's skin, the least distance
// from the slave to the box of the nodes of any other facet that step examined (a lower bound
// of that facet's distance whatever the projection's round-off: a facet lies within its
// nodes' box) less how far the master nodes had moved since the last global search
// (STATUS_MASTER_MOTION, relative to the reference node), and the slave's position relative to
// the reference node. A distance moves no more than its ends: in a later increment every other
// facet is still at least that bound less the slave's motion since the walk and the master's
// since the global search. While F's distance now, plus those motions and the round-off
// (SKIN_ROUNDOFF of the coordinates), stays below it, and F's nearest node is still the
// tracked one, the walk from that node would take F again and stay: the slave is projected on
// F alone (the walk's own first projection), with the walk's bits, the facets counted carried
// from the walk's last step. The walk's result does not depend on the skin: a skin that does
// not hold only costs the walk. A step that passed over a collapsed facet, or whose wider
// search (FLAG_WIDE_LOCAL) started from another facet than F, leaves no skin (HIT_WALKED
// clear), nor does one that would not hold even without motion (a slave far above several
// facets at nearly its distance); the global search's hits leave none either.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> slaves: array<u32>;
@group(0) @binding(4) var<storage, read> adjacency: array<u32>;
@group(0) @binding(5) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(7) var<storage, read_write> reference: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> skins: array<vec4<f32>>;

// A skin's margin is shrunk by this fraction of the coordinates' scale: more than the round-off
// of a projection or a distance in f32 (Rust twin: SKIN_ROUNDOFF, 2^-14).
const SKIN_ROUNDOFF: f32 = 0.00006103515625;

struct Best {
    facet: u32,
    d2: f32,
    pr: Projection,
    candidates: u32,
    lb2: f32,        // the best's box distance² (a lower bound of its distance)
    second: f32,     // the least lower bound² of the other facets this step examined
    collapsed: bool, // this step passed over a collapsed facet
}

// Facet f around the slave at p: counted as examined unless excluded or collapsed; projected
// unless its nodes' box is farther than the best by more than round-off (PRUNE_SLACK: such a
// facet cannot be nearer, nor tie, so skipping it changes nothing but the time); kept when
// nearer than the best (ties: lowest id). The best facet itself is counted and not projected
// again: the same positions give the same projection. Every other facet's box distance² (a
// lower bound of its distance, whatever the projection's round-off) lowers the step's second.
fn consider(b: ptr<function, Best>, s: u32, p: vec3<f32>, f: u32) {
    let fac = facets[f];
    if (excluded(s, fac)) { return; }
    let pts = facet_points(fac);
    if (facet_collapsed(pts.x0, pts.x1, pts.x2, pts.x3, pts.n)) {
        (*b).collapsed = true;
        return;
    }
    (*b).candidates += 1u;
    if (f == (*b).facet) { return; }
    let box_d2 = points_box_d2(p, pts);
    if ((*b).facet != NO_FACET && box_d2 > (*b).d2 * PRUNE_SLACK) {
        (*b).second = min((*b).second, box_d2);
        return;
    }
    let pr = project_points(p, pts);
    if ((*b).facet == NO_FACET || pr.dist2 < (*b).d2 || (pr.dist2 == (*b).d2 && f < (*b).facet)) {
        if ((*b).facet != NO_FACET) { (*b).second = min((*b).second, (*b).lb2); }
        (*b).facet = f;
        (*b).d2 = pr.dist2;
        (*b).pr = pr;
        (*b).lb2 = box_d2;
    } else {
        (*b).second = min((*b).second, box_d2);
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

// The node of facet fac nearest p (ties: lowest id).
fn nearest_node(fac: vec4<u32>, p: vec3<f32>) -> u32 {
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
    return next;
}

// The largest absolute coordinate of x.
fn max_abs(x: vec3<f32>) -> f32 {
    return max(max(abs(x.x), abs(x.y)), abs(x.z));
}

// Slave i's hit (slave node s at p, tracked node `tracked`, facets counted `candidates` with
// its flags): facet f with projection pr when f is one within the radius, else none. Its
// tracking state is written where it crossed the radius (from `last`).
fn write_hit(i: u32, s: u32, p: vec3<f32>, tracked: u32, f: u32, pr: Projection,
             candidates: u32, last: u32) {
    var hit: Hit;
    hit.facet = NO_FACET;
    hit.node = tracked;
    hit.candidates = candidates;
    hit.slave = s;
    hit.point_gap = vec4<f32>(0.0);
    hit.normal_dist = vec4<f32>(0.0);
    hit.weights = vec4<f32>(0.0);
    if (f != NO_FACET && pr.dist2 <= params.radius * params.radius) {
        hit.facet = f;
        hit.point_gap = vec4<f32>(pr.point, dot(p - pr.point, pr.normal));
        hit.normal_dist = vec4<f32>(pr.normal, sqrt(pr.dist2));
        hit.weights = pr.weights;
        if (beside_free_edge(f, facets[f], pr.weights, p, pr.point, pr.normal)) {
            hit.candidates |= HIT_BESIDE_FREE_EDGE;
        }
    } else {
        hit.candidates &= ~HIT_WALKED;
    }
    hits[i] = hit;
    // the state (tracked; with a facet within the radius or not) changes only where the slave
    // crossed the radius: written there alone, not a scattered write by node for every slave
    if ((hit.facet != NO_FACET) != (last != NO_FACET)) {
        reference[s].w = slave_state(hit);
    }
}

// The walk's status words, reduced in the workgroup first, then raised with one global atomic
// per word and workgroup: the most steps of a walk (max), the slaves walked and those stopped
// at the cap (added). Integer operations: the words do not depend on the order.
const WG_ITERATIONS: u32 = 0u; // STATUS_LOCAL_ITERATIONS
const WG_WALKS: u32 = 1u;      // STATUS_LOCAL_WALKS
const WG_CAPPED: u32 = 2u;     // STATUS_LOCAL_CAPPED
var<workgroup> wg_words: array<atomic<u32>, 3>;

@compute @workgroup_size(64)
fn local_search(@builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    let k = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (li < 3u) { atomicStore(&wg_words[li], 0u); }
    // every invocation reaches both barriers (uniform control flow)
    workgroupBarrier();
    track_slave(k);
    workgroupBarrier();
    if (li < 3u) {
        let v = atomicLoad(&wg_words[li]);
        if (v != 0u) {
            if (li == WG_ITERATIONS) {
                atomicMax(&status[STATUS_LOCAL_ITERATIONS], v);
            } else if (li == WG_WALKS) {
                atomicAdd(&status[STATUS_LOCAL_WALKS], v);
            } else {
                atomicAdd(&status[STATUS_LOCAL_CAPPED], v);
            }
        }
    }
}

// Active slave k's hit: from its skin, or by the walk from its tracked node.
fn track_slave(k: u32) {
    if (k >= atomicLoad(&status[ACTIVE_LIST])) { return; }
    if (atomicLoad(&status[STATUS_BUDGET_EXCEEDED]) != 0u) { return; }
    let i = atomicLoad(&status[ACTIVE_LIST + 1u + k]);
    // of the last hit, the walk reads its tracked node, facet and count word (12 of its 64 bytes)
    var tracked = hits[i].node;
    if (tracked == NO_NODE) { return; }
    let last = hits[i].facet;
    let counted = hits[i].candidates;
    let s = slaves[i];
    let p = nodes[s].xyz;
    let r = nodes[params.ref_node].xyz;
    // how far the master nodes moved since the global search, relative to the reference node
    let masters = bitcast<f32>(atomicLoad(&status[STATUS_MASTER_MOTION]));
    let roundoff = SKIN_ROUNDOFF * (max(max_abs(p), max_abs(r)) + params.radius);
    var b: Best;
    b.facet = NO_FACET;
    b.d2 = 0.0;
    b.lb2 = 0.0;
    // the first projection: the facet the last search found, when it is one around the tracked
    // node (examined and counted there), so that the box test can skip the others from the start
    if (has_node(last, tracked)) {
        let fac = facets[last];
        let pts = facet_points(fac);
        if (!excluded(s, fac) && !facet_collapsed(pts.x0, pts.x1, pts.x2, pts.x3, pts.n)) {
            b.facet = last;
            b.pr = project_points(p, pts);
            b.d2 = b.pr.dist2;
            b.lb2 = points_box_d2(p, pts);
            if ((counted & HIT_WALKED) != 0u) {
                // within the skin: the walk would take the same facet and stay (see the header)
                let skin = skins[i];
                let moved = length((p - r) - skin.xyz) + masters;
                if (sqrt(b.d2) + moved + roundoff < skin.w && nearest_node(fac, p) == tracked) {
                    atomicMax(&wg_words[WG_ITERATIONS], 1u);
                    write_hit(i, s, p, tracked, last, b.pr, counted & (HIT_COUNT | HIT_WALKED), last);
                    return;
                }
            }
        }
    }
    var it = 0u;
    var settled = false;
    var wide_from = NO_FACET;
    loop {
        // a step: the facets counted and the skin's bounds are the last step's
        b.candidates = 0u;
        b.second = EMPTY_LO;
        b.collapsed = false;
        // the best so far carries over: it has the new tracked node, so it is among the facets
        // examined next, and the walk's result is the nearest of those whatever the order
        for (var k = adjacency[tracked]; k < adjacency[tracked + 1u]; k++) {
            consider(&b, s, p, adjacency[k]);
        }
        wide_from = b.facet;
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
        let next = nearest_node(facets[b.facet], p);
        if (next == tracked) { settled = true; break; }
        tracked = next;
        if (it >= params.max_local_iterations) { break; }
    }
    atomicMax(&wg_words[WG_ITERATIONS], it);
    atomicAdd(&wg_words[WG_WALKS], 1u);
    if (!settled) { atomicAdd(&wg_words[WG_CAPPED], 1u); }
    var candidates = b.candidates;
    // a skin that would not hold even without motion is not left (its read would be wasted)
    let margin = sqrt(b.second) - masters;
    let within = b.d2 <= params.radius * params.radius;
    if (settled && b.facet != NO_FACET && within && !b.collapsed && wide_from == b.facet
        && sqrt(b.d2) + roundoff < margin) {
        skins[i] = vec4<f32>(p - r, margin);
        candidates |= HIT_WALKED;
    }
    write_hit(i, s, p, tracked, b.facet, b.pr, candidates, last);
}
