// nearest_facet.wgsl — step 2: the globally nearest active facet of each slave node, by a walk
// of the bounding-box tree (tree.wgsl) pruned by the best distance found so far, with work per
// invocation bounded however the data lies. CPU mirror: src/cpu/nearest_facet.rs.
// Prelude: common.wgsl, search_common.wgsl (projection, self-contact exclusion, free edges).
//
// The passes, in order:
//   walk_gather      one invocation per slave: its position and node id copied into
//                    `walk_points` in the order the walks take the slaves (Morton order of their
//                    start positions), so that the walk reads them in sequence instead of one
//                    scattered read per slave; every later pass keeps its per-slave record (work,
//                    best) at this walk position t, and only nearest_facet maps it back to the
//                    caller's order.
//   nearest_walk     one invocation per slave: a depth-first walk of the tree, the nearer child
//                    first, skipping every subtree whose box is farther than the best facet
//                    found so far (at first the radius), at most WALK_VISITS nodes. Its best
//                    facet goes into `best`; a walk cut off by the cap leaves the leaf slots
//                    from the lowest one it had not finished on to the chunk passes (every
//                    facet it did not reach is among them), cut into chunks of
//                    CANDIDATE_CHUNK: their count into `work` (then scanned by scan.wgsl into
//                    each slave's first work item).
//   nearest_args     one invocation: the indirect dispatch of the work items (folded into 2D).
//   nearest_chunks   one invocation per work item (indirect): the chunk's nearest facet; a slave
//                    of one chunk stores it when not farther than the walk's, a slave of several
//                    lowers its best distance (atomicMin on the bits of a non-negative f32,
//                    which order as the values).
//   nearest_ties     per work item (indirect), slaves of several chunks only: a chunk whose nearest
//                    facet is at the best distance offers its id (atomicMin): the lowest id wins.
//   nearest_crowded  one invocation per slave, self-contact only: the crowding check (a second
//                    walk, bounded by the radius) into the record.
//   nearest_facet    one invocation per slave: the winner, the hit from it, the counts
//                    (STATUS_FALLBACK, STATUS_CROWDED).
//
// Dispatch: walk_gather, nearest_walk, nearest_crowded and nearest_facet one invocation per slave,
//           nearest_args one, the chunk passes one per work item through the indirect
//           arguments; ITEM_WORKGROUP per workgroup, folded into 2D.
// Bindings: 0 params, 1 nodes, 2 facets, 3 slaves (node id per slave, then the slaves' indices
//           in Morton order of their start positions: walk position t is slave
//           slaves[n_slaves + t], so neighbouring invocations walk the same branches and read
//           the same boxes), 4 order (active facet of each leaf slot), 5 boxes (the tree's,
//           tree.wgsl), 6 status (fallbacks and self-contact crowding counted), 7 hits (one Hit
//           per slave, caller's order), 8 adjacency (as in local_search.wgsl; self-contact and
//           free edges), 9 work (chunk counts per walk position, scanned to first work items;
//           word n_slaves: total), 10 best (BEST_WORDS per walk position, below), 11 args (the
//           indirect dispatch: x, y, z), 12 walk_points (per walk position: the slave's
//           grid-local position as f32 bits, xyz, and its node id, w). Each entry point binds
//           the subset it uses, at most 8 storage buffers (WebGPU's default limit).
// Invariants: the walk skips a subtree only when its box is farther than the best distance by
//             more than round-off (PRUNE_SLACK; boxes are grown by the frame's round-off), so
//             every facet at the best distance is projected and the result is the brute
//             force's: the nearest facet within the radius, ties to the lowest facet id,
//             decided by comparison; the tracked node is the facet node nearest the slave
//             node, ties to the lowest node id. No facet within the radius: facet = NO_FACET.
//             The walk's visits follow the slave's gap, not the radius. With FLAG_SELF_CONTACT
//             a slave's own facets and the facets touching them are skipped, and a slave with
//             another facet within the radius that shares no node with its nearest and faces it
//             (its gap is more than half its distance: not a neighbour in the same plane) is
//             counted in STATUS_CROWDED (the schedule then searches globally more often); a
//             crowding walk cut off by the cap counts the slave as crowded (the safe side). A
//             slave nearest to a free edge or corner of the master and off to its side gets
//             HIT_BESIDE_FREE_EDGE in its candidates word: the master ends there. Candidates:
//             the facets projected (walk and chunks). No loop runs over more than WALK_VISITS
//             nodes, CANDIDATE_CHUNK candidates or 32 steps of a binary search or climb.
//
// best record of walk position t, words BEST_WORDS·t + : 0 best distance² bits (atomicMin), 1 facet at
// it from the chunks (atomicMin), 2 crowded (self-contact), 3 candidates, 4 the walk's facet,
// 5 the first leaf slot left to the chunks, 6 the walk's distance² bits, 7 unused.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> slaves: array<u32>;
@group(0) @binding(4) var<storage, read> order: array<u32>;
@group(0) @binding(5) var<storage, read> boxes: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> hits: array<Hit>;
@group(0) @binding(8) var<storage, read> adjacency: array<u32>;
@group(0) @binding(9) var<storage, read_write> work: array<u32>;
@group(0) @binding(10) var<storage, read_write> best: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> args: array<u32>;
@group(0) @binding(12) var<storage, read_write> walk_points: array<vec4<u32>>;

// Candidates one work item projects at most (Rust twin: CANDIDATE_CHUNK), far below the 65,535
// iterations where Mesa stops a loop.
const CANDIDATE_CHUNK: u32 = 1024u;
// Tree nodes one walk visits at most (Rust twin: WALK_VISITS).
const WALK_VISITS: u32 = 2048u;
// Words of a slave's best record (Rust twin: BEST_WORDS).
const BEST_WORDS: u32 = 8u;
// A subtree is skipped when its box's distance² exceeds the bound by this factor: more than
// the round-off of a distance² computed in f32 (Rust twin: PRUNE_SLACK).
const PRUNE_SLACK: f32 = 1.0001;
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

// Whether tree node k holds nothing within distance² `bound` of p (an empty box never does).
fn far(k: u32, p: vec3<f32>, bound: f32) -> bool {
    return box_d2(k, p) > bound * PRUNE_SLACK;
}

// The node a depth-first walk visits after the subtree of node k; 0 when none is left.
fn next_node(k: u32) -> u32 {
    var n = k;
    for (var s = 0u; s < 32u && (n & 1u) == 1u; s++) { n = n >> 1u; }
    if (n == 0u) { return 0u; }
    return n + 1u;
}

// The first leaf slot under node k (k ≥ 1).
fn first_leaf(k: u32) -> u32 {
    let depth = firstLeadingBit(k);
    return (k << (params.tree_levels - depth)) - (1u << params.tree_levels);
}

struct Walk {
    d2: f32,
    f: u32,
    next: u32,        // 0: finished; else 1 + the first leaf slot left to the chunks
    projections: u32,
}

// Distance² from p to tree node k's box; +∞ for an empty box (never within a bound).
fn box_d2(k: u32, p: vec3<f32>) -> f32 {
    return packed_box_d2(boxes[k], p, box_step(params.box_margin).x);
}

// The slave at walk position t: grid-local position, model node id.
struct WalkPoint {
    p: vec3<f32>,
    node: u32,
}

fn walk_point(t: u32) -> WalkPoint {
    let w = walk_points[t];
    return WalkPoint(bitcast<vec3<f32>>(w.xyz), w.w);
}

// The nearest facet of the slave at walk position t a depth-first walk from tree node `start`
// finds within WALK_VISITS nodes. Each visit tests the two children of one inner node (two
// loads: on a software adapter a load is a loop over the SIMD lanes, the walk's main cost) and
// goes to the nearer one whose box is within the best distance found so far, leaving the other
// pending; when neither is, the walk returns to the deepest pending subtree, untested (its
// children's boxes lie within its own, so the next visit prunes it if it is far by then; a
// pending leaf is tested before it is projected). No stack in memory: the pending subtrees are
// one bit per depth (`pending`, bit d: the sibling of the walk's ancestor at depth d), and the
// ancestors are those of the node the walk was last at (heap layout: parent k/2, sibling k^1).
// A walk cut off by the cap leaves `next` at the lowest first leaf slot of the subtrees still
// pending.
fn walk(t: u32, start: u32) -> Walk {
    let wp = walk_point(t);
    let slave = wp.node;
    let p = wp.p;
    let leaves = 1u << params.tree_levels;
    var pending = 0u;
    var last = 1u;
    var w: Walk;
    w.d2 = params.radius * params.radius;
    w.f = NO_FACET;
    w.next = 0u;
    w.projections = 0u;
    var k = start;
    last = max(start, 1u);
    var v = 0u;
    // whether the leaf k was reached from a pending return (its box not yet tested)
    var untested = true;
    let step = box_step(params.box_margin).x;
    for (var leaf = 0u; leaf < WALK_VISITS; leaf++) {
        // every iteration tests the two children of one inner node: a return to a pending
        // sibling goes to it untested (its children's boxes lie within its own)
        for (; v < WALK_VISITS; v++) {
            if (k == 0u) {
                if (pending == 0u) { break; }
                let depth = firstLeadingBit(pending);
                pending &= ~(1u << depth);
                last = (last >> (firstLeadingBit(last) - depth)) ^ 1u;
                k = last;
                untested = true;
            }
            if (k >= leaves) { break; }
            let bound = w.d2 * PRUNE_SLACK;
            let bl = boxes[2u * k];
            let br = boxes[2u * k + 1u];
            let lo_l = box_bounds(box_codes_lo(bl), step);
            let hi_l = box_bounds(box_codes_hi(bl), step);
            let lo_r = box_bounds(box_codes_lo(br), step);
            let hi_r = box_bounds(box_codes_hi(br), step);
            let el = max(max(lo_l - p, p - hi_l), vec3<f32>(0.0));
            let er = max(max(lo_r - p, p - hi_r), vec3<f32>(0.0));
            let dl = dot(el, el);
            let dr = dot(er, er);
            let near_l = dl <= bound;
            let near_r = dr <= bound;
            untested = false;
            if (near_l && near_r) {
                let cl = 0.5 * (lo_l + hi_l) - p;
                let cr = 0.5 * (lo_r + hi_r) - p;
                let right_first = dr < dl || (dr == dl && dot(cr, cr) < dot(cl, cl));
                pending |= 1u << (firstLeadingBit(k) + 1u);
                k = select(2u * k, 2u * k + 1u, right_first);
            } else if (near_l) {
                k = 2u * k;
            } else if (near_r) {
                k = 2u * k + 1u;
            } else {
                last = k;
                k = 0u;
            }
        }
        if (v >= WALK_VISITS || k < leaves) { break; }
        // the leaf
        v++;
        if (!untested || box_d2(k, p) <= w.d2 * PRUNE_SLACK) {
            let f = order[k - leaves];
            if (!excluded(slave, facets[f])) {
                let d2 = project_facet(p, facets[f]).dist2;
                w.projections += 1u;
                if (d2 < w.d2 || (d2 == w.d2 && f < w.f)) {
                    w.d2 = d2;
                    w.f = f;
                }
            }
        }
        untested = false;
        last = k;
        k = 0u;
    }
    if (k != 0u || pending != 0u) {
        // cut off: the chunks take every leaf slot from the lowest one still pending
        var lowest = 0xffffffffu;
        var at = last;
        if (k != 0u) {
            lowest = first_leaf(k);
            at = k;
        }
        for (var s = 0u; s < 32u && pending != 0u; s++) {
            let depth = firstLeadingBit(pending);
            pending &= ~(1u << depth);
            lowest = min(lowest, first_leaf((at >> (firstLeadingBit(at) - depth)) ^ 1u));
        }
        w.next = lowest + 1u;
    }
    return w;
}

// The walk position of work item t: the largest s with work[s] ≤ t (work is its first item).
fn work_slave(t: u32) -> u32 {
    var lo = 0u;
    var hi = params.n_slaves; // work[lo] ≤ t < work[hi]
    for (var step = 0u; step < 32u && hi - lo > 1u; step++) {
        let mid = (lo + hi) / 2u;
        if (work[mid] <= t) { lo = mid; } else { hi = mid; }
    }
    return lo;
}

struct ChunkBest {
    d2: f32,
    f: u32,
}

// The nearest facet (within the radius, ties to the lowest id) of the slave at walk position i
// among the leaf slots of its work item t: slots start + (t − work[i])·CANDIDATE_CHUNK onwards
// (empty ones skipped).
fn chunk_best(i: u32, t: u32) -> ChunkBest {
    let wp = walk_point(i);
    let slave = wp.node;
    let p = wp.p;
    let leaves = 1u << params.tree_levels;
    let j0 = atomicLoad(&best[BEST_WORDS * i + 5u]) + (t - work[i]) * CANDIDATE_CHUNK;
    let j1 = min(leaves, j0 + CANDIDATE_CHUNK);
    var b: ChunkBest;
    b.d2 = params.radius * params.radius;
    b.f = NO_FACET;
    for (var j = j0; j < j1; j++) {
        let k = leaves + j;
        if ((boxes[k].x & BOX_TOP) == BOX_TOP) { continue; } // no facet, or collapsed: empty
        let f = order[j];
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
fn walk_gather(@builtin(workgroup_id) wg: vec3<u32>,
               @builtin(num_workgroups) nwg: vec3<u32>,
               @builtin(local_invocation_index) li: u32) {
    let t = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (t >= params.n_slaves) { return; }
    let slave = slaves[slaves[params.n_slaves + t]];
    walk_points[t] = vec4<u32>(bitcast<vec3<u32>>(nodes[slave].xyz), slave);
}

@compute @workgroup_size(64)
fn nearest_walk(@builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    let t = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (t >= params.n_slaves) { return; }
    if (t == 0u) { work[params.n_slaves] = 0u; }
    let w = walk(t, 1u);
    let leaves = 1u << params.tree_levels;
    var start = leaves;
    if (w.next != 0u) { start = min(w.next - 1u, leaves); }
    let rest = leaves - start;
    work[t] = (rest + CANDIDATE_CHUNK - 1u) / CANDIDATE_CHUNK;
    let b = BEST_WORDS * t;
    atomicStore(&best[b], bitcast<u32>(w.d2));
    atomicStore(&best[b + 1u], NO_FACET);
    atomicStore(&best[b + 2u], 0u);
    atomicStore(&best[b + 3u], w.projections + rest);
    atomicStore(&best[b + 4u], w.f);
    atomicStore(&best[b + 5u], start);
    atomicStore(&best[b + 6u], bitcast<u32>(w.d2));
    atomicStore(&best[b + 7u], 0u);
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
    let bits = bitcast<u32>(b.d2);
    if (work[i + 1u] - work[i] == 1u) {
        // the slave's only chunk: no other invocation writes its record
        if (bits <= atomicLoad(&best[BEST_WORDS * i])) {
            atomicStore(&best[BEST_WORDS * i], bits);
            atomicStore(&best[BEST_WORDS * i + 1u], b.f);
        }
    } else {
        atomicMin(&best[BEST_WORDS * i], bits);
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
    if (b.f != NO_FACET && bitcast<u32>(b.d2) == atomicLoad(&best[BEST_WORDS * i])) {
        atomicMin(&best[BEST_WORDS * i + 1u], b.f);
    }
}

// The winner of walk position i's record: the chunks' facet at the best distance, or the walk's when it
// is at that distance with a lower id.
fn winner(i: u32) -> u32 {
    let b = BEST_WORDS * i;
    let f = atomicLoad(&best[b + 1u]);
    let walk_f = atomicLoad(&best[b + 4u]);
    if (walk_f != NO_FACET && atomicLoad(&best[b + 6u]) == atomicLoad(&best[b]) && walk_f < f) {
        return walk_f;
    }
    return f;
}

// Self-contact: whether the slave at walk position i has a facet within the radius, other than
// its nearest best_f and sharing no node with it, that faces it; a walk cut off by the cap says
// yes.
fn crowded(i: u32, best_f: u32) -> bool {
    let wp = walk_point(i);
    let slave = wp.node;
    let p = wp.p;
    let leaves = 1u << params.tree_levels;
    let r2 = params.radius * params.radius;
    var k = 1u;
    for (var v = 0u; v < WALK_VISITS; v++) {
        if (k == 0u) { return false; }
        if (far(k, p, r2)) {
            k = next_node(k);
        } else if (k >= leaves) {
            let f = order[k - leaves];
            if (f != best_f && !excluded(slave, facets[f]) && !share_node(facets[f], facets[best_f])) {
                // near and facing the slave (not merely beside it in its own plane)
                let pr = project_facet(p, facets[f]);
                let gap = dot(p - pr.point, pr.normal);
                if (pr.dist2 <= r2 && 4.0 * gap * gap > pr.dist2) { return true; }
            }
            k = next_node(k);
        } else {
            k = 2u * k;
        }
    }
    return k != 0u;
}

@compute @workgroup_size(64)
fn nearest_crowded(@builtin(workgroup_id) wg: vec3<u32>,
                   @builtin(num_workgroups) nwg: vec3<u32>,
                   @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if ((params.flags & FLAG_SELF_CONTACT) == 0u || i >= params.n_slaves) { return; }
    let f = winner(i);
    if (f != NO_FACET && crowded(i, f)) { atomicStore(&best[BEST_WORDS * i + 2u], 1u); }
}

@compute @workgroup_size(64)
fn nearest_facet(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    // invocation i: walk position i, written to the hit of slave slaves[n_slaves + i]
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= params.n_slaves) { return; }
    let wp = walk_point(i);
    var hit: Hit;
    hit.facet = NO_FACET;
    hit.node = NO_NODE;
    let b = BEST_WORDS * i;
    hit.candidates = atomicLoad(&best[b + 3u]);
    hit.slave = wp.node;
    hit.point_gap = vec4<f32>(0.0);
    hit.normal_dist = vec4<f32>(0.0);
    hit.weights = vec4<f32>(0.0);
    let p = wp.p;
    if (atomicLoad(&best[b + 5u]) < (1u << params.tree_levels)) { atomicAdd(&status[STATUS_FALLBACK], 1u); }
    let best_f = winner(i);
    if (best_f != NO_FACET) {
        if (atomicLoad(&best[b + 2u]) != 0u) { atomicAdd(&status[STATUS_CROWDED], 1u); }
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
    hits[slaves[params.n_slaves + i]] = hit;
}
