// nearest_facet.wgsl — step 2: the globally nearest active facet of each slave node, by a walk
// of the bounding-box tree (tree.wgsl) pruned by the best distance found so far, with work per
// invocation bounded however the data lies. CPU mirror: src/cpu/nearest_facet.rs.
// Prelude: common.wgsl, search_common.wgsl (projection, self-contact exclusion, free edges).
//
// The passes, in order:
//   walk_start       one invocation per group of WALK_GROUP walk positions (neighbours in Morton
//                    order of the slaves' start positions, so near each other). First their
//                    slaves' positions and node ids are copied into `walk_points` in walk
//                    order, so that the walks read them in sequence instead of one scattered
//                    read per slave (every later pass keeps its per-slave record, work and
//                    best, at the walk position t, and only nearest_facet maps it back to the
//                    caller's order). Then from the root down while exactly one child's box is
//                    within the radius of the group's box, to the node every walk of the group
//                    would reach by itself (above it each has one near child per level, the
//                    same for all), or to none (no facet within the radius of any of them):
//                    into `work` at each position, the walk's start node (0: none). A SIMD
//                    group of walks skips the levels above it together.
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
// Dispatch: nearest_walk, nearest_crowded and nearest_facet one invocation per slave, walk_start
//           one per group of WALK_GROUP slaves, nearest_args one, the chunk passes one per work
//           item through the indirect arguments; ITEM_WORKGROUP per workgroup, folded into 2D.
// Bindings: 0 params, 1 nodes, 2 facets, 3 slaves (node id per slave, then the slaves' indices
//           in Morton order of their start positions: walk position t is slave
//           slaves[n_slaves + t], so neighbouring invocations walk the same branches and read
//           the same boxes), 4 order (active facet of each leaf slot), 5 boxes (the tree's,
//           tree.wgsl), 6 status (fallbacks and self-contact crowding counted), 7 hits (one Hit
//           per slave, caller's order), 8 adjacency (as in local_search.wgsl; self-contact and
//           free edges), 9 work (per walk position the walk's start node from walk_start,
//           then its chunk counts, scanned to first work items; word n_slaves: total), 10 best
//           (BEST_WORDS per walk position, below), 11 args (the indirect dispatch: x, y, z),
//           12 walk_points (per walk position: the slave's grid-local position as f32 bits,
//           xyz, and its node id, w), 13 best_records (the buffer of `best` as two vec4 per
//           record: nearest_walk writes and nearest_facet reads whole records through it, the
//           passes between single words through `best`). Each entry point binds the subset it
//           uses, at most 8 storage buffers (WebGPU's default limit).
// Invariants: the walk skips a subtree only when its box is farther than the best distance by
//             more than round-off (PRUNE_SLACK; boxes are grown by the frame's round-off and
//             rounded outwards to the box grid, distances taken from the box point), so
//             every facet at the best distance is projected and the result is the brute
//             force's: the nearest facet within the radius, ties to the lowest facet id,
//             decided by comparison; the tracked node is the facet node nearest the slave
//             node, ties to the lowest node id. No facet within the radius: facet = NO_FACET.
//             The walks look as far as the tracking radius, radius + budget
//             (`track_radius2`): a slave whose nearest facet lies beyond the radius but within
//             it is tracked (hit.node set, facet = NO_FACET), so that the local search finds it
//             the increment it comes within the radius — the motion budget asks for a global
//             search before an untracked slave can come that far (active.wgsl).
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
// The same buffer as `best`, two vec4 per record: the walk writes a record and nearest_facet
// reads it whole (two loads or stores where word by word they would be eight), the passes
// between update single words atomically through `best`.
@group(0) @binding(13) var<storage, read_write> best_records: array<vec4<u32>>;

// Candidates one work item projects at most (Rust twin: CANDIDATE_CHUNK), far below the 65,535
// iterations where Mesa stops a loop.
const CANDIDATE_CHUNK: u32 = 1024u;
// Tree nodes one walk visits at most (Rust twin: WALK_VISITS).
const WALK_VISITS: u32 = 2048u;
// Walk positions per group whose walks start together at one tree node (Rust twin: WALK_GROUP):
// a SIMD group's width on a CPU adapter (8 lanes of 32 bits in AVX2).
const WALK_GROUP: u32 = 8u;
// Words of a slave's best record (Rust twin: BEST_WORDS).
const BEST_WORDS: u32 = 8u;

// Workgroups per dimension of the indirect dispatch before folding into y (WebGPU's default).
const MAX_GROUPS_PER_DIM: u32 = 65535u;

// Whether tree node k holds nothing within distance² `bound` of the point whose box point
// (box_point) is q: its box is empty or farther.
fn far(k: u32, q: vec3<f32>, bound: f32) -> bool {
    let b = boxes[k];
    return box_empty(b) || packed_box_d2(b, q, box_step(params.box_margin).x) > bound * PRUNE_SLACK;
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

// The slave at walk position t: position in the frame, model node id.
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
    w.d2 = track_radius2();
    w.f = NO_FACET;
    w.next = 0u;
    w.projections = 0u;
    var k = start;
    last = max(start, 1u);
    var v = 0u;
    // whether node k was reached untested: the start node, or a return to a pending subtree
    var untested = true;
    let step = box_step(params.box_margin).x;
    let q = box_point(p, step);
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
            let el = max(max(lo_l - q, q - hi_l), vec3<f32>(0.0));
            let er = max(max(lo_r - q, q - hi_r), vec3<f32>(0.0));
            let dl = dot(el, el);
            let dr = dot(er, er);
            let near_l = !box_empty(bl) && dl <= bound;
            let near_r = !box_empty(br) && dr <= bound;
            untested = false;
            if (near_l && near_r) {
                let cl = 0.5 * (lo_l + hi_l) - q;
                let cr = 0.5 * (lo_r + hi_r) - q;
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
        if (!untested || !far(k, q, w.d2)) {
            let f = order[k - leaves];
            let fac = facets[f];
            if (!excluded(slave, fac)) {
                let d2 = project_facet(p, fac).dist2;
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
    b.d2 = track_radius2();
    b.f = NO_FACET;
    for (var j = j0; j < j1; j++) {
        let k = leaves + j;
        if (box_empty(boxes[k])) { continue; } // no facet, or collapsed
        let f = order[j];
        let fac = facets[f];
        if (excluded(slave, fac)) { continue; }
        let d2 = project_facet(p, fac).dist2;
        if (d2 < b.d2 || (d2 == b.d2 && f < b.f)) {
            b.d2 = d2;
            b.f = f;
        }
    }
    return b;
}

// Whether tree node k's box is within distance² `bound` of the box [glo, ghi] (not empty).
fn group_near(k: u32, glo: vec3<f32>, ghi: vec3<f32>, bound: f32, step: f32) -> bool {
    let b = boxes[k];
    let lo = box_bounds(box_codes_lo(b), step);
    let hi = box_bounds(box_codes_hi(b), step);
    let d = max(max(lo - ghi, glo - hi), vec3<f32>(0.0));
    return !box_empty(b) && dot(d, d) <= bound;
}

@compute @workgroup_size(64)
fn walk_start(@builtin(workgroup_id) wg: vec3<u32>,
              @builtin(num_workgroups) nwg: vec3<u32>,
              @builtin(local_invocation_index) li: u32) {
    // invocation g: the walk positions g·WALK_GROUP onwards
    let t0 = folded_id(wg, nwg, li, ITEM_WORKGROUP) * WALK_GROUP;
    if (t0 >= params.n_slaves) { return; }
    let t1 = min(t0 + WALK_GROUP, params.n_slaves);
    let step = box_step(params.box_margin).x;
    var glo = vec3<f32>(0.0);
    var ghi = vec3<f32>(0.0);
    for (var t = t0; t < t1; t++) {
        // the slave at walk position t, gathered
        let slave = slaves[slaves[params.n_slaves + t]];
        let x = nodes[slave].xyz;
        walk_points[t] = vec4<u32>(bitcast<vec3<u32>>(x), slave);
        let q = box_point(x, step);
        if (t == t0) {
            glo = q;
            ghi = q;
        }
        glo = min(glo, q);
        ghi = max(ghi, q);
    }
    let bound = track_radius2() * PRUNE_SLACK;
    let leaves = 1u << params.tree_levels;
    // the bucket search (buckets.wgsl) has leaf boxes alone, and no start node
    let tree = (params.flags & FLAG_BUCKETS) == 0u;
    var k = select(0u, 1u, tree && group_near(1u, glo, ghi, bound, step));
    for (var s = 0u; s < 32u && k != 0u && k < leaves; s++) {
        let near_l = group_near(2u * k, glo, ghi, bound, step);
        let near_r = group_near(2u * k + 1u, glo, ghi, bound, step);
        if (near_l && near_r) { break; }
        k = select(select(0u, 2u * k + 1u, near_r), 2u * k, near_l);
    }
    for (var t = t0; t < t1; t++) { work[t] = k; }
}

@compute @workgroup_size(64)
fn nearest_walk(@builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    let t = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (t >= params.n_slaves) { return; }
    if (t == 0u) { work[params.n_slaves] = 0u; }
    let w = walk(t, work[t]);
    let leaves = 1u << params.tree_levels;
    var start = leaves;
    if (w.next != 0u) { start = min(w.next - 1u, leaves); }
    let rest = leaves - start;
    work[t] = (rest + CANDIDATE_CHUNK - 1u) / CANDIDATE_CHUNK;
    best_records[2u * t] = vec4<u32>(bitcast<u32>(w.d2), NO_FACET, 0u, w.projections + rest);
    best_records[2u * t + 1u] = vec4<u32>(w.f, start, bitcast<u32>(w.d2), 0u);
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

// The winner of a record (words 0..3, 4..7): the chunks' facet at the best distance, or the
// walk's when it is at that distance with a lower id.
fn record_winner(r0: vec4<u32>, r1: vec4<u32>) -> u32 {
    let walk_f = r1.x;
    if (walk_f != NO_FACET && r1.z == r0.x && walk_f < r0.y) {
        return walk_f;
    }
    return r0.y;
}

// The winner of walk position i's record, read word by word (the passes that bind `best`).
fn winner(i: u32) -> u32 {
    let b = BEST_WORDS * i;
    let r0 = vec4<u32>(atomicLoad(&best[b]), atomicLoad(&best[b + 1u]), 0u, 0u);
    let r1 = vec4<u32>(atomicLoad(&best[b + 4u]), 0u, atomicLoad(&best[b + 6u]), 0u);
    return record_winner(r0, r1);
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
    let q = box_point(p, box_step(params.box_margin).x);
    var k = 1u;
    for (var v = 0u; v < WALK_VISITS; v++) {
        if (k == 0u) { return false; }
        if (far(k, q, r2)) {
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
    let r0 = best_records[2u * i];
    let r1 = best_records[2u * i + 1u];
    var hit: Hit;
    hit.facet = NO_FACET;
    hit.node = NO_NODE;
    hit.candidates = r0.w;
    hit.slave = wp.node;
    hit.point_gap = vec4<f32>(0.0);
    hit.normal_dist = vec4<f32>(0.0);
    hit.weights = vec4<f32>(0.0);
    let p = wp.p;
    if (r1.y < (1u << params.tree_levels)) { atomicAdd(&status[STATUS_FALLBACK], 1u); }
    let best_f = record_winner(r0, r1);
    if (best_f != NO_FACET) {
        if (r0.z != 0u) { atomicAdd(&status[STATUS_CROWDED], 1u); }
        let fac = facets[best_f];
        // the facet's nodes loaded once, for the projection and the nearest node
        let x = facet_points(fac);
        let pr = project_points(p, x);
        // the nearest of them, ties to the lowest node id
        var best_node = fac.x;
        var best_nd2 = dot(x.x0 - p, x.x0 - p);
        let d1 = dot(x.x1 - p, x.x1 - p);
        if (d1 < best_nd2 || (d1 == best_nd2 && fac.y < best_node)) { best_node = fac.y; best_nd2 = d1; }
        if (x.n >= 3u) {
            let d2 = dot(x.x2 - p, x.x2 - p);
            if (d2 < best_nd2 || (d2 == best_nd2 && fac.z < best_node)) { best_node = fac.z; best_nd2 = d2; }
        }
        if (x.n == 4u) {
            let d3 = dot(x.x3 - p, x.x3 - p);
            if (d3 < best_nd2 || (d3 == best_nd2 && fac.w < best_node)) { best_node = fac.w; best_nd2 = d3; }
        }
        hit.node = best_node;
        if (pr.dist2 <= params.radius * params.radius) {
            hit.facet = best_f;
            hit.point_gap = vec4<f32>(pr.point, dot(p - pr.point, pr.normal));
            hit.normal_dist = vec4<f32>(pr.normal, sqrt(pr.dist2));
            hit.weights = pr.weights;
            if (beside_free_edge(best_f, fac, pr.weights, p, pr.point, pr.normal)) {
                hit.candidates |= HIT_BESIDE_FREE_EDGE;
            }
        }
    }
    hits[slaves[params.n_slaves + i]] = hit;
}
