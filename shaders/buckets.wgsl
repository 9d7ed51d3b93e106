// buckets.wgsl — the seed's bucket search, beside the tree (FLAG_BUCKETS): the active facets
// binned by counting sort into a hashed grid of cells sized to the facets, and each slave's
// cells visited in rings outward, pruned by the best distance so far. Its walks write the same
// records as nearest_walk (nearest_facet.wgsl), whose chunk, tie, and hit passes finish them.
// CPU mirror: src/cpu/buckets.rs. Prelude: common.wgsl, search_common.wgsl.
//
// The grid: cells of 2^s box-grid steps (cell_shift: the largest power of two at or below
// params.bucket_cell), so a cell is a range of the leaf boxes' integer codes (common.wgsl),
// code >> s per axis; cell c lies in the bucket bucket_of(c) of 2^bucket_bits, and a facet
// spanning more than BIN_SPAN cells along an axis in the last bucket (2^bucket_bits), which
// every walk visits first. In 2D every cell has z = BOX_BIAS >> s (the plane z = 0).
//
// grid words: 0 ..= 2^bits the buckets' words (bucket_count: their counts; the scan
// (scan.wgsl, its levels after them): their starts; bucket_fill: their ends — bucket b holds
// entries grid[b − 1] (0 for b = 0) .. grid[b]); from params.bucket_entries the entries, two
// words each: the leaf slot (its box is boxes[2^L + slot]) and its facet.
//
// The passes, in order (after tree_refit's leaf level, which fills the leaf boxes):
//   bucket_clear    one invocation per bucket word: zeroed.
//   bucket_count    one invocation per leaf slot: its facet counted in each bucket of its cells.
//   (scan_blocks / scan_add on the bucket words)
//   bucket_fill     one invocation per leaf slot: its entries written where its buckets' words
//                   say (atomicAdd: the order within a bucket is the device's, and nothing
//                   below depends on it).
//   bucket_walk     one invocation per walk position (walk_start put the slaves' points in walk
//                   order): the last bucket, then the cells in rings outward; the nearest facet
//                   into `best_records`, the chunks left to the chunk passes into `work`, as
//                   nearest_walk.
//   bucket_crowded  one invocation per walk position, self-contact only: the crowding check
//                   (nearest_crowded's) over the cells within the radius.
//
// Bindings: 0 params, 1 nodes, 2 facets, 4 order, 5 boxes (the leaf boxes), 8 adjacency,
//           9 work, 10 best, 12 walk_points, 13 best_records (as in nearest_facet.wgsl),
//           14 grid (bucket_clear, bucket_count, bucket_fill), 15 grid_words (the same buffer
//           read only: bucket_walk, bucket_crowded). Each entry point binds at most 8 storage
//           buffers.
// Dispatch: bucket_clear one invocation per bucket word (2^bits + 1), bucket_count and
//           bucket_fill one per leaf slot, bucket_walk and bucket_crowded one per slave;
//           ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: a facet's box lies within the cells it is binned in, and a cell is skipped only
//             when its box is farther than the best distance by more than round-off
//             (PRUNE_SLACK), so every facet at the best distance is projected: the result is
//             the tree's and the brute force's (nearest within the tracking radius, ties to the
//             lowest id). Determinism: a bucket's entries are taken in two rounds that no
//             order decides (the nearest box first, ties to the lowest facet id; then the
//             others within the best distance after it), so the facets projected and counted
//             do not depend on the order bucket_fill left them in. Bounded: a walk
//             visits at most BUCKET_VISITS cells and entries; one that would go beyond leaves
//             every leaf slot to the chunks (as the tree's fallback, STATUS_FALLBACK), and a
//             crowding check cut off counts the slave as crowded.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> order: array<u32>;
@group(0) @binding(5) var<storage, read> boxes: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read> adjacency: array<u32>;
@group(0) @binding(9) var<storage, read_write> work: array<u32>;
@group(0) @binding(10) var<storage, read_write> best: array<atomic<u32>>;
@group(0) @binding(12) var<storage, read_write> walk_points: array<vec4<u32>>;
@group(0) @binding(13) var<storage, read_write> best_records: array<vec4<u32>>;
@group(0) @binding(14) var<storage, read_write> grid: array<atomic<u32>>;
// The same buffer read only, for the walks (plain loads).
@group(0) @binding(15) var<storage, read> grid_words: array<u32>;

// Cells and entries one walk visits at most (Rust twin: BUCKET_VISITS).
const BUCKET_VISITS: u32 = 2048u;
// Cells per axis a binned facet spans at most (Rust twin: BIN_SPAN).
const BIN_SPAN: u32 = 2u;
// Words of a slave's best record (Rust twin: BEST_WORDS).
const BEST_WORDS: u32 = 8u;

// Box-grid codes per cell as a shift (Rust twin: abi::buckets::cell_shift).
fn cell_shift() -> u32 {
    let e_cell = i32((bitcast<u32>(params.bucket_cell) >> 23u) & 0xffu) - 127;
    let e_step = clamp(i32((bitcast<u32>(params.box_margin) >> 23u) & 0xffu) - 127, -100, 100);
    return u32(clamp(e_cell - e_step, 0, 20));
}

// The bucket of cell c (Rust twin: abi::buckets::bucket_of).
fn bucket_of(c: vec3<u32>) -> u32 {
    let h = (c.x * 0x8da6b343u) ^ (c.y * 0xd8163841u) ^ (c.z * 0xcb1ab31fu);
    return (h * 0x9e3779b1u) >> (32u - params.bucket_bits);
}

// The last bucket: the facets too large to bin.
fn overflow_bucket() -> u32 {
    return 1u << params.bucket_bits;
}

// The cells of a packed leaf box: lower and upper cell per axis (z both BOX_BIAS >> s in 2D).
fn box_cells(b: vec4<u32>, s: u32) -> array<vec3<u32>, 2> {
    var lo = box_codes_lo(b) >> vec3<u32>(s);
    var hi = box_codes_hi(b) >> vec3<u32>(s);
    if (params.dim == 2u) {
        lo.z = u32(BOX_BIAS) >> s;
        hi.z = lo.z;
    }
    return array<vec3<u32>, 2>(lo, hi);
}

// Whether a box spanning cells lo..hi is binned (else it goes to the last bucket).
fn binned(lo: vec3<u32>, hi: vec3<u32>) -> bool {
    return all(hi - lo < vec3<u32>(BIN_SPAN));
}

// The bucket of cell k (0 .. 7) of the box spanning cells lo..hi (hi − lo at most 1 per axis),
// or 0xffffffff when the box has no such cell.
fn bin_cell(lo: vec3<u32>, hi: vec3<u32>, k: u32) -> u32 {
    let d = vec3<u32>(k & 1u, (k >> 1u) & 1u, (k >> 2u) & 1u);
    if (any(lo + d > hi)) { return 0xffffffffu; }
    return bucket_of(lo + d);
}

@compute @workgroup_size(64)
fn bucket_clear(@builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i > overflow_bucket()) { return; }
    atomicStore(&grid[i], 0u);
}

@compute @workgroup_size(64)
fn bucket_count(@builtin(workgroup_id) wg: vec3<u32>,
                @builtin(num_workgroups) nwg: vec3<u32>,
                @builtin(local_invocation_index) li: u32) {
    let j = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    let leaves = 1u << params.tree_levels;
    if (j >= leaves) { return; }
    let b = boxes[leaves + j];
    if (box_empty(b)) { return; } // no facet, or collapsed
    let c = box_cells(b, cell_shift());
    if (!binned(c[0], c[1])) {
        atomicAdd(&grid[overflow_bucket()], 1u);
        return;
    }
    for (var k = 0u; k < 8u; k++) {
        let bk = bin_cell(c[0], c[1], k);
        if (bk != 0xffffffffu) { atomicAdd(&grid[bk], 1u); }
    }
}

@compute @workgroup_size(64)
fn bucket_fill(@builtin(workgroup_id) wg: vec3<u32>,
               @builtin(num_workgroups) nwg: vec3<u32>,
               @builtin(local_invocation_index) li: u32) {
    let j = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    let leaves = 1u << params.tree_levels;
    if (j >= leaves) { return; }
    let b = boxes[leaves + j];
    if (box_empty(b)) { return; }
    let c = box_cells(b, cell_shift());
    let f = order[j];
    let at = params.bucket_entries;
    if (!binned(c[0], c[1])) {
        let e = atomicAdd(&grid[overflow_bucket()], 1u);
        atomicStore(&grid[at + 2u * e], j);
        atomicStore(&grid[at + 2u * e + 1u], f);
        return;
    }
    for (var k = 0u; k < 8u; k++) {
        let bk = bin_cell(c[0], c[1], k);
        if (bk != 0xffffffffu) {
            let e = atomicAdd(&grid[bk], 1u);
            atomicStore(&grid[at + 2u * e], j);
            atomicStore(&grid[at + 2u * e + 1u], f);
        }
    }
}

// The entries of bucket b: first, end.
fn bucket_range(b: u32) -> vec2<u32> {
    var first = 0u;
    if (b > 0u) { first = grid_words[b - 1u]; }
    return vec2<u32>(first, grid_words[b]);
}

// A walk over the cells around a slave's cell in rings outward (Rust twin:
// abi::buckets::Ring): ring r is the cells at Chebyshev distance r, taken layer by layer along
// z (one layer in 2D), row by row along y, and along x every cell of a row on the ring's
// boundary in y or z, the two ends of the others. No division (on a software adapter an
// integer division is a loop over the SIMD lanes).
struct Ring {
    r: i32,
    d: vec3<i32>,   // the current cell's offset from the centre cell
}

fn ring_row_start(g: Ring) -> bool {
    return g.d.x == -g.r;
}

fn ring_layer_start(g: Ring) -> bool {
    return g.d.x == -g.r && g.d.y == -g.r;
}

// To the next row (layer, ring); true when that starts a new ring.
fn ring_next_row(g: ptr<function, Ring>) -> bool {
    let r = (*g).r;
    (*g).d.x = -r;
    (*g).d.y += 1;
    if ((*g).d.y <= r) { return false; }
    (*g).d.y = -r;
    (*g).d.z += 1;
    if (params.dim != 2u && (*g).d.z <= r) { return false; }
    (*g).r = r + 1;
    (*g).d = vec3<i32>(-r - 1, -r - 1, select(-r - 1, 0, params.dim == 2u));
    return true;
}

// To the next layer (ring); true when that starts a new ring.
fn ring_next_layer(g: ptr<function, Ring>) -> bool {
    (*g).d.y = (*g).r;
    return ring_next_row(g);
}

// To the next cell (row, layer, ring); true when that starts a new ring.
fn ring_next_cell(g: ptr<function, Ring>) -> bool {
    let r = (*g).r;
    let edge = abs((*g).d.y) == r || (params.dim != 2u && abs((*g).d.z) == r);
    if ((*g).d.x < r) {
        (*g).d.x = select(r, (*g).d.x + 1, edge);
        return false;
    }
    return ring_next_row(g);
}

// The distance² from the box point to the slab of cells c along axis a.
fn slab_d2(o: Origin, c: i32, a: u32) -> f32 {
    let lo = box_bounds(vec3<u32>(u32(c) << o.s), o.step).x;
    let hi = box_bounds(vec3<u32>(u32(c + 1) << o.s), o.step).x;
    let e = max(max(lo - o.q[a], o.q[a] - hi), 0.0);
    return e * e;
}

// One step of a ring walk within distance² `bound`: at the start of a layer or a row that holds
// no master cell within it, that layer or row skipped (0, or 2 when the rings end there);
// else 1: the caller visits the current cell, then calls ring_next_cell.
fn ring_step(o: Origin, g: ptr<function, Ring>, bound: f32) -> u32 {
    let c = o.cell + (*g).d;
    let limit = bound * PRUNE_SLACK;
    if (params.dim != 2u && ring_layer_start(*g)) {
        if (c.z < o.lo.z || c.z > o.hi.z || slab_d2(o, c.z, 2u) > limit) {
            return select(0u, 2u, ring_next_layer(g) && !ring_near(o, u32((*g).r), bound));
        }
    }
    if (ring_row_start(*g)) {
        var far = c.y < o.lo.y || c.y > o.hi.y;
        var yz = slab_d2(o, c.y, 1u);
        if (params.dim != 2u) {
            far = far || c.z < o.lo.z || c.z > o.hi.z;
            yz += slab_d2(o, c.z, 2u);
        }
        if (far || yz > limit) {
            return select(0u, 2u, ring_next_row(g) && !ring_near(o, u32((*g).r), bound));
        }
    }
    return 1u;
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

// Where a slave's rings are measured from: its box point q, its cell (clamped into the
// master's), and the master's cells (every binned facet lies in them).
struct Origin {
    q: vec3<f32>,
    cell: vec3<i32>,
    s: u32,
    step: f32,
    lo: vec3<i32>,   // the master's cells: the box of this global search grown by the margin
    hi: vec3<i32>,
    d2: f32,         // distance² from q to that box
}

fn origin(p: vec3<f32>) -> Origin {
    var o: Origin;
    let bs = box_step(params.box_margin);
    o.step = bs.x;
    o.s = cell_shift();
    o.q = box_point(p, o.step);
    let sv = vec3<u32>(o.s);
    let code = vec3<u32>(box_code_lo(o.q.x, bs.y), box_code_lo(o.q.y, bs.y), box_code_lo(o.q.z, bs.y));
    o.cell = vec3<i32>(code >> sv);
    let m = params.box_margin;
    let mlo = params.master_lo.xyz - vec3<f32>(m);
    let mhi = params.master_hi.xyz + vec3<f32>(m);
    let clo = vec3<u32>(box_code_lo(mlo.x, bs.y), box_code_lo(mlo.y, bs.y), box_code_lo(mlo.z, bs.y));
    let chi = vec3<u32>(box_code_hi(mhi.x, bs.y), box_code_hi(mhi.y, bs.y), box_code_hi(mhi.z, bs.y));
    o.lo = vec3<i32>(clo >> sv);
    o.hi = vec3<i32>(chi >> sv);
    var e = max(max(box_bounds(clo, o.step) - o.q, o.q - box_bounds(chi, o.step)), vec3<f32>(0.0));
    if (params.dim == 2u) {
        let z = i32(u32(BOX_BIAS) >> o.s);
        o.cell.z = z;
        o.lo.z = z;
        o.hi.z = z;
        e.z = 0.0;
    }
    o.d2 = dot(e, e);
    // rings around the nearest of the master's cells: none of them is wasted beyond its side
    o.cell = clamp(o.cell, o.lo, o.hi);
    return o;
}

// Distance² from the origin's box point to cell c, or −1 when c lies outside the master's
// cells (no facet is binned there).
fn cell_d2(o: Origin, c: vec3<i32>) -> f32 {
    if (any(c < o.lo) || any(c > o.hi)) { return -1.0; }
    let lo = box_bounds(vec3<u32>(c) << vec3<u32>(o.s), o.step);
    let hi = box_bounds(vec3<u32>(c + vec3<i32>(1)) << vec3<u32>(o.s), o.step);
    var e = max(max(lo - o.q, o.q - hi), vec3<f32>(0.0));
    if (params.dim == 2u) { e.z = 0.0; }
    return dot(e, e);
}

// Whether ring r (r ≥ 1) may hold a cell of the master's within distance² `bound`: the least
// distance from the box point out of the cube of rings below it, over the sides where ring r
// has master cells.
fn ring_near(o: Origin, r: u32, bound: f32) -> bool {
    let ri = i32(r);
    var d = 3.4e38;
    let axes = select(3u, 2u, params.dim == 2u);
    for (var a = 0u; a < axes; a++) {
        let c = o.cell[a];
        if (c - ri >= o.lo[a]) {
            let lo = box_bounds(vec3<u32>(u32(c - ri + 1) << o.s), o.step).x;
            d = min(d, max(o.q[a] - lo, 0.0));
        }
        if (c + ri <= o.hi[a]) {
            let hi = box_bounds(vec3<u32>(u32(c + ri) << o.s), o.step).x;
            d = min(d, max(hi - o.q[a], 0.0));
        }
    }
    return d < 3.4e38 && d * d <= bound * PRUNE_SLACK;
}

struct BucketWalk {
    d2: f32,
    f: u32,
    projections: u32,
    cut: bool,   // the visit cap cut it off: the chunks take every leaf slot
}

// Projects facet f for the walk `w` of the slave at p unless excluded.
fn walk_project(w: ptr<function, BucketWalk>, f: u32, p: vec3<f32>, slave: u32) {
    let fac = facets[f];
    if (excluded(slave, fac)) { return; }
    let d2 = project_facet(p, fac).dist2;
    (*w).projections += 1u;
    if (d2 < (*w).d2 || (d2 == (*w).d2 && f < (*w).f)) {
        (*w).d2 = d2;
        (*w).f = f;
    }
}

// The entries of bucket b for the walk `w` of the slave at p (box point q), in two rounds that
// do not depend on the entries' order: first the one whose box is nearest (ties to the lowest
// facet id), then each other whose box is within the best distance as it stood after it. The
// best facet from before the bucket is not projected again.
fn walk_bucket(w: ptr<function, BucketWalk>, b: u32, p: vec3<f32>, q: vec3<f32>, slave: u32,
               step: f32, visits: ptr<function, u32>) {
    let range = bucket_range(b);
    if (*visits + 2u * (range.y - range.x) > BUCKET_VISITS) {
        (*w).cut = true;
        return;
    }
    *visits += 2u * (range.y - range.x);
    let before = (*w).f;
    let leaves = 1u << params.tree_levels;
    let at = params.bucket_entries;
    var first = NO_FACET;
    var first_d2 = (*w).d2 * PRUNE_SLACK;
    for (var e = range.x; e < min(range.y, range.x + BUCKET_VISITS); e++) {
        let f = grid_words[at + 2u * e + 1u];
        if (f == before) { continue; }
        let d2 = packed_box_d2(boxes[leaves + grid_words[at + 2u * e]], q, step);
        if (d2 < first_d2 || (d2 == first_d2 && f < first)) {
            first_d2 = d2;
            first = f;
        }
    }
    if (first == NO_FACET) { return; }
    walk_project(w, first, p, slave);
    let bound = (*w).d2 * PRUNE_SLACK;
    for (var e = range.x; e < min(range.y, range.x + BUCKET_VISITS); e++) {
        let f = grid_words[at + 2u * e + 1u];
        if (f == before || f == first) { continue; }
        if (packed_box_d2(boxes[leaves + grid_words[at + 2u * e]], q, step) > bound) { continue; }
        walk_project(w, f, p, slave);
    }
}

// The nearest facet within the tracking radius of the slave at walk position t: the last
// bucket, then its cells ring by ring, each cell skipped when farther than the best; the rings
// end where none can be nearer.
fn bucket_walk_of(t: u32) -> BucketWalk {
    let wp = walk_point(t);
    let o = origin(wp.p);
    var w: BucketWalk;
    w.d2 = track_radius2();
    w.f = NO_FACET;
    w.projections = 0u;
    w.cut = false;
    if (o.d2 > w.d2 * PRUNE_SLACK) { return w; } // the master is farther than the radius
    var visits = 1u;
    walk_bucket(&w, overflow_bucket(), wp.p, o.q, wp.node, o.step, &visits);
    var g = Ring(0, vec3<i32>(0));
    var more = true;
    for (; more && visits < BUCKET_VISITS && !w.cut; visits++) {
        let k = ring_step(o, &g, w.d2);
        if (k == 2u) { more = false; }
        if (k != 1u) { continue; }
        let c = o.cell + g.d;
        let d2 = cell_d2(o, c);
        if (d2 >= 0.0 && d2 <= w.d2 * PRUNE_SLACK) {
            walk_bucket(&w, bucket_of(vec3<u32>(c)), wp.p, o.q, wp.node, o.step, &visits);
        }
        if (ring_next_cell(&g) && !ring_near(o, u32(g.r), w.d2)) { more = false; }
    }
    if (more && visits >= BUCKET_VISITS) { w.cut = true; }
    return w;
}

@compute @workgroup_size(64)
fn bucket_walk(@builtin(workgroup_id) wg: vec3<u32>,
               @builtin(num_workgroups) nwg: vec3<u32>,
               @builtin(local_invocation_index) li: u32) {
    let t = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (t >= params.n_slaves) { return; }
    if (t == 0u) { work[params.n_slaves] = 0u; }
    let w = bucket_walk_of(t);
    let leaves = 1u << params.tree_levels;
    let start = select(leaves, 0u, w.cut);
    let rest = leaves - start;
    work[t] = (rest + CANDIDATE_CHUNK - 1u) / CANDIDATE_CHUNK;
    best_records[2u * t] = vec4<u32>(bitcast<u32>(w.d2), NO_FACET, 0u, w.projections + rest);
    best_records[2u * t + 1u] = vec4<u32>(w.f, start, bitcast<u32>(w.d2), 0u);
}

// Candidates one work item projects at most (Rust twin: CANDIDATE_CHUNK).
const CANDIDATE_CHUNK: u32 = 1024u;

// The winner of walk position i's record (nearest_facet.wgsl's `winner`).
fn winner(i: u32) -> u32 {
    let b = BEST_WORDS * i;
    let walk_f = atomicLoad(&best[b + 4u]);
    let chunk_f = atomicLoad(&best[b + 1u]);
    if (walk_f != NO_FACET && atomicLoad(&best[b + 6u]) == atomicLoad(&best[b]) && walk_f < chunk_f) {
        return walk_f;
    }
    return chunk_f;
}

// Whether an entry of bucket b is a facet within the radius, other than best_f and sharing no
// node with it, that faces the slave at p (nearest_facet.wgsl's `crowded`).
fn crowded_in(b: u32, p: vec3<f32>, q: vec3<f32>, slave: u32, best_f: u32, step: f32) -> bool {
    let range = bucket_range(b);
    let r2 = params.radius * params.radius;
    let leaves = 1u << params.tree_levels;
    let at = params.bucket_entries;
    for (var e = range.x; e < min(range.y, range.x + BUCKET_VISITS); e++) {
        let j = grid_words[at + 2u * e];
        let f = grid_words[at + 2u * e + 1u];
        if (f == best_f || packed_box_d2(boxes[leaves + j], q, step) > r2 * PRUNE_SLACK) { continue; }
        let fac = facets[f];
        if (excluded(slave, fac) || share_node(fac, facets[best_f])) { continue; }
        let pr = project_facet(p, fac);
        let gap = dot(p - pr.point, pr.normal);
        if (pr.dist2 <= r2 && 4.0 * gap * gap > pr.dist2) { return true; }
    }
    return false;
}

// Self-contact: whether the slave at walk position i has a facet within the radius, other than
// its nearest best_f and sharing no node with it, that faces it; a check cut off by the cap
// says yes.
fn bucket_crowded_of(i: u32, best_f: u32) -> bool {
    let wp = walk_point(i);
    let o = origin(wp.p);
    let r2 = params.radius * params.radius;
    if (o.d2 > r2 * PRUNE_SLACK) { return false; }
    var visits = 1u;
    let over = bucket_range(overflow_bucket());
    if (visits + (over.y - over.x) > BUCKET_VISITS) { return true; }
    visits += over.y - over.x;
    if (crowded_in(overflow_bucket(), wp.p, o.q, wp.node, best_f, o.step)) { return true; }
    var g = Ring(0, vec3<i32>(0));
    for (; visits < BUCKET_VISITS; visits++) {
        let k = ring_step(o, &g, r2);
        if (k == 2u) { return false; }
        if (k != 1u) { continue; }
        let c = o.cell + g.d;
        let d2 = cell_d2(o, c);
        if (d2 >= 0.0 && d2 <= r2 * PRUNE_SLACK) {
            let b = bucket_of(vec3<u32>(c));
            let range = bucket_range(b);
            if (visits + (range.y - range.x) > BUCKET_VISITS) { return true; }
            visits += range.y - range.x;
            if (crowded_in(b, wp.p, o.q, wp.node, best_f, o.step)) { return true; }
        }
        if (ring_next_cell(&g) && !ring_near(o, u32(g.r), r2)) { return false; }
    }
    return true;
}

@compute @workgroup_size(64)
fn bucket_crowded(@builtin(workgroup_id) wg: vec3<u32>,
                  @builtin(num_workgroups) nwg: vec3<u32>,
                  @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if ((params.flags & FLAG_SELF_CONTACT) == 0u || i >= params.n_slaves) { return; }
    let f = winner(i);
    if (f != NO_FACET && bucket_crowded_of(i, f)) { atomicStore(&best[BEST_WORDS * i + 2u], 1u); }
}
