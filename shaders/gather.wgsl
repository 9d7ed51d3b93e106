// gather.wgsl — the contact force on every node of the pair, summed exactly in fixed point so that
// the result has the same bits every run whatever the order of the additions (no float atomics,
// no sort, and no loop whose length the data decides).
// CPU mirror: src/cpu/gather.rs.
//
// Fixed point: each sum is a 64-bit two's-complement integer held as two u32 words (low, high),
// added with two 32-bit atomics and a carry. Integer addition is associative, so the sum does not
// depend on the order in which invocations run. The scale 2^E is chosen per increment from the
// largest magnitude the penalty pass met (status words STATUS_FORCE_SCALE, STATUS_ROW_SCALE) and
// the number of terms, so that no sum can leave ±2^62: see `fixed_exponent`.
//
// Bindings: 0 pp (uniform PenaltyParams), 1 pair_nodes (node, slave index, adjacency start,
//           end), 2 facet_nodes (pair-node index of each active facet's nodes, NO_NODE padded),
//           3 hits, 4 out (ContactOut), 5 status (read: the two scale words; from ACTIVE_LIST the
//           active slaves, active.wgsl), 6 acc (8 words per
//           pair node: fx, fy, fz, row as (low, high) pairs; zero before scatter_forces: the
//           buffer starts zeroed and gather zeroes what it reads),
//           7 forces (vec4 per pair node), 8 host_forces (the caller's force buffer: vec4<f32>
//           per model node, xyz summed into, w left alone), 9 rows (f32 per model node: the
//           node-wise bound's rows summed over the pairs of the increment), 10 stats (the
//           increment's statistics: add_forces raises STAT_OMEGA2, the largest row),
//           11 need (NEED_* bits per pair node and rigid slot: scatter sets NEED_FORCE where it
//           adds, add_forces clears the word; nodal_normals.wgsl sets NEED_NORMAL).
// Dispatch: scatter_forces one invocation per slave (global increments, small sliding),
//           scatter_forces_active one per active slave (local increments, indirect from the
//           plan's ACTIVE_SLOT), gather and add_forces one per pair node
//           (add_forces: device-resident increments, after gather), gather_active and
//           add_forces_active (local increments of a pair with PENALTY_SLAVES_APART) one per
//           active slave and per other pair node, indirect from the plan's
//           ACTIVE_NODES_SLOT (two items more than the pair may have); ITEM_WORKGROUP per
//           workgroup, folded into 2D. Each invocation does at most 4 × 4 atomic pairs (scatter)
//           or reads 8 words (gather): bounded whatever the number of slaves on one facet.
// Invariants: a slave node gets its own contact force; a master node gets −w_j·f of every slave
//             in contact with one of its facets (j its slot in the facet), summed exactly at the
//             fixed-point resolution (2^−E, at most 2^−58 of the largest possible sum) and rounded
//             once to f32, so Σ over the pair is zero to f32 round-off and two identical
//             increments give the same bits. forces.w: the node's row of the node-wise frequency
//             bound, the sum of the shares (bound_light, or bound_heavy where the spring marks the
//             node heavy) of its own spring and of every spring in contact on its facets whose
//             weight at the node is not zero (a node the contact point does not weigh is not in
//             that spring; giving it a share would make the bound jump with round-off).
//             A pair node with nothing to add is left by gather and add_forces after one word
//             (no_force: a slave with no facet in a pair with PENALTY_SLAVES_APART, a master
//             node or rigid slot no spring scattered onto): the caller's force is not touched
//             where nothing is added, and a node far from every contact costs a word.
//             Nothing is scattered when the search overflowed or the motion budget was used up
//             (the penalty pass did not run, the increment runs again).

@group(0) @binding(0) var<uniform> pp: PenaltyParams;
@group(0) @binding(1) var<storage, read> pair_nodes: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> facet_nodes: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> hits: array<Hit>;
@group(0) @binding(4) var<storage, read> out: array<ContactOut>;
@group(0) @binding(5) var<storage, read> status: array<u32>;
@group(0) @binding(6) var<storage, read_write> acc: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> forces: array<vec4<f32>>;
@group(0) @binding(8) var<storage, read_write> host_forces: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> rows: array<f32>;
@group(0) @binding(10) var<storage, read_write> stats: array<atomic<u32>>;
@group(0) @binding(11) var<storage, read_write> need: array<atomic<u32>>;

// Bits below the sign that a fixed-point sum may use (2 bits of headroom for weights up to 4).
const FIXED_BITS: i32 = 60;
const TWO_32: f32 = 4294967296.0;

// 2^e for e in [−126, 127], built from its bits (exact; the mirror builds it the same way).
fn pow2(e: i32) -> f32 {
    return bitcast<f32>(u32(e + 127) << 23u);
}

// The exponent E of the fixed-point scale for sums of at most 4·n_terms terms, each at most the
// f32 whose bits are max_bits in magnitude: 4·n_terms · max · 2^E ≤ 2^FIXED_BITS.
fn fixed_exponent(max_bits: u32, n_terms: u32) -> i32 {
    let e = i32((max_bits >> 23u) & 0xffu) - 126; // max < 2^e
    let k = i32(32u - countLeadingZeros(max(n_terms, 1u) - 1u)) + 2; // 4·n_terms ≤ 2^k
    return clamp(FIXED_BITS - e - k, -126, 126);
}

// −a in 64-bit two's complement.
fn negate(a: vec2<u32>) -> vec2<u32> {
    let lo = ~a.x + 1u;
    return vec2<u32>(lo, ~a.y + select(0u, 1u, lo == 0u));
}

// v · scale as a 64-bit integer (low, high), truncated toward zero; |v · scale| < 2^62.
fn to_fixed(v: f32, scale: f32) -> vec2<u32> {
    let x = min(abs(v) * scale, 4.0e18);
    let hi = floor(x * (1.0 / TWO_32));
    let lo = x - hi * TWO_32; // exact: the bits of x below 2^32
    var r = vec2<u32>(u32(lo), u32(hi));
    if (v < 0.0) { r = negate(r); }
    return r;
}

// The 64-bit integer a divided by the scale (inv_scale = 1 / scale), rounded to f32.
fn from_fixed(a: vec2<u32>, inv_scale: f32) -> f32 {
    let neg = (a.y & 0x80000000u) != 0u;
    var m = a;
    if (neg) { m = negate(a); }
    let x = (f32(m.y) * TWO_32 + f32(m.x)) * inv_scale;
    return select(x, -x, neg);
}

// Adds a to the sum at words 2w, 2w + 1: the low word's wrap, seen by the one addition that
// caused it, carries into the high word.
fn add_fixed(w: u32, a: vec2<u32>) {
    let old = atomicAdd(&acc[2u * w], a.x);
    let carry = select(0u, 1u, old + a.x < old);
    atomicAdd(&acc[2u * w + 1u], a.y + carry);
}

// What scatter and gather read of a spring's output: its force, status and shares of the bound
// (the first 32 bytes of its ContactOut, one memory sector; field by field, so no more is read).
struct OutForce {
    force: vec3<f32>,
    status: u32,
    bound_light: f32,
    bound_heavy: f32,
}

fn out_force(i: u32) -> OutForce {
    return OutForce(out[i].force.xyz, out[i].status, out[i].bound_light, out[i].bound_heavy);
}

// A spring's share of the bound at one of its nodes: heavy if its status has `bit`.
fn row_share(o: OutForce, bit: u32) -> f32 {
    return select(o.bound_light, o.bound_heavy, (o.status & bit) != 0u);
}

@compute @workgroup_size(64)
fn scatter_forces(@builtin(workgroup_id) wg: vec3<u32>,
                  @builtin(num_workgroups) nwg: vec3<u32>,
                  @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= pp.n_slaves) { return; }
    scatter(i);
}

// Local increments: the active slaves only (an untracked slave is open: nothing to scatter).
@compute @workgroup_size(64)
fn scatter_forces_active(@builtin(workgroup_id) wg: vec3<u32>,
                         @builtin(num_workgroups) nwg: vec3<u32>,
                         @builtin(local_invocation_index) li: u32) {
    let k = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (k >= status[ACTIVE_LIST]) { return; }
    scatter(status[ACTIVE_LIST + 1u + k]);
}

// Slave i's reaction onto its facet's nodes.
fn scatter(i: u32) {
    // the penalty pass did not run (the increment will run again): its outputs are stale
    if (status[STATUS_BUDGET_EXCEEDED] != 0u) { return; }
    let o = out_force(i);
    // of the hit, its facet, and for a spring its weights (20 of its first 32 bytes)
    let facet = hits[i].facet;
    if ((o.status & CSTATUS_MASK) == CSTATUS_OPEN || facet >= pp.n_facets) { return; }
    let weights = hits[i].weights;
    let fac = facet_nodes[facet];
    let n = facet_node_count(fac);
    let sf = pow2(fixed_exponent(status[STATUS_FORCE_SCALE], pp.n_slaves));
    let sr = pow2(fixed_exponent(status[STATUS_ROW_SCALE], pp.n_slaves));
    let rigid_master = pp.body_slots.x != NO_SLAVE;
    for (var j = 0u; j < n; j++) {
        let w = weights[j];
        let base = 4u * fac[j];
        atomicOr(&need[fac[j]], NEED_FORCE);
        add_fixed(base, to_fixed(-w * o.force.x, sf));
        add_fixed(base + 1u, to_fixed(-w * o.force.y, sf));
        add_fixed(base + 2u, to_fixed(-w * o.force.z, sf));
        // a node the contact point does not weigh (w = 0) is not in the spring: no share; a
        // rigid master's nodes are one body, whose row is its slot's
        let share = select(0.0, row_share(o, 1u << (HEAVY_SHIFT + j)), w != 0.0 && !rigid_master);
        add_fixed(base + 3u, to_fixed(share, sr));
    }
    if (rigid_master) {
        atomicOr(&need[pp.body_slots.x], NEED_FORCE);
        add_fixed(4u * pp.body_slots.x + 3u, to_fixed(row_share(o, 1u << HEAVY_SHIFT), sr));
    }
    if (pp.body_slots.y != NO_SLAVE) {
        atomicOr(&need[pp.body_slots.y], NEED_FORCE);
        add_fixed(4u * pp.body_slots.y + 3u, to_fixed(row_share(o, HEAVY_SLAVE), sr));
    }
}

// Pair node i has no force and no row this increment, so gather and add_forces leave it (its
// `forces` row is stale, and read by no one): a slave with no facet in a pair whose slaves are
// no master nodes — its own spring wrote nothing but zeros (penalty.wgsl) and no spring
// scattered onto it — for one word of its hit; a master node or rigid slot no spring scattered
// onto (its sums are zero), for its need word. `need` is the word read (0 for a slave).
fn no_force(i: u32, need_word: u32) -> bool {
    if (i < pp.n_slaves) {
        return (pp.flags & PENALTY_SLAVES_APART) != 0u && hits[i].facet == NO_FACET;
    }
    return (need_word & NEED_FORCE) == 0u;
}

// Local increments of a pair whose slaves are no master nodes (PENALTY_SLAVES_APART): item k
// of gather_active and add_forces_active is the active slave k, then, past the active count,
// the pair's master nodes and rigid slots in order; a pair node past them (the slot counts two
// rigid slots whatever the pair has) is NO_SLAVE. A slave that is not active has no facet (it
// was untracked at the global search: beyond radius + budget), so gather and add_forces would
// leave it after its hit word: leaving it out changes no bit.
fn active_pair_node(k: u32) -> u32 {
    let n_active = status[ACTIVE_LIST];
    if (k < n_active) { return status[ACTIVE_LIST + 1u + k]; }
    let i = pp.n_slaves + (k - n_active);
    return select(NO_SLAVE, i, i < pp.n_pair_nodes + pp.body_slots.z);
}

@compute @workgroup_size(64)
fn gather(@builtin(workgroup_id) wg: vec3<u32>,
          @builtin(num_workgroups) nwg: vec3<u32>,
          @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= pp.n_pair_nodes + pp.body_slots.z) { return; }
    gather_node(i);
}

// Local increments, PENALTY_SLAVES_APART: the active slaves and the other pair nodes only.
@compute @workgroup_size(64)
fn gather_active(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    let i = active_pair_node(folded_id(wg, nwg, li, ITEM_WORKGROUP));
    if (i == NO_SLAVE) { return; }
    gather_node(i);
}

// Pair node i's force and row from its own spring and its sums (the sums zeroed).
fn gather_node(i: u32) {
    var need_word = 0u;
    if (i >= pp.n_slaves) { need_word = atomicLoad(&need[i]); }
    if (no_force(i, need_word)) { return; }
    let pn = pair_nodes[i];
    var f = vec3<f32>(0.0);
    var row = 0.0;
    if (pn.y != NO_SLAVE) {
        let o = out_force(pn.y);
        f = o.force;
        // a rigid slave part's springs add up in its slot (scatter_forces)
        if (pp.body_slots.y == NO_SLAVE) { row = row_share(o, HEAVY_SLAVE); }
    }
    let inv_f = pow2(-fixed_exponent(status[STATUS_FORCE_SCALE], pp.n_slaves));
    let inv_r = pow2(-fixed_exponent(status[STATUS_ROW_SCALE], pp.n_slaves));
    var sum: array<f32, 4>;
    for (var c = 0u; c < 4u; c++) {
        let w = 2u * (4u * i + c);
        // read and zeroed: the sums start from zero at the next increment's scatter
        let a = vec2<u32>(atomicExchange(&acc[w], 0u), atomicExchange(&acc[w + 1u], 0u));
        sum[c] = from_fixed(a, select(inv_f, inv_r, c == 3u));
    }
    forces[i] = vec4<f32>(f + vec3<f32>(sum[0], sum[1], sum[2]), row + sum[3]);
}

// The workgroup's largest row written (bits of non-negative floats order as the values).
var<workgroup> top_row: array<u32, 64>;

// Adds each pair node's force into the caller's buffer and its bound row into `rows`: one
// invocation per pair node and rigid part slot, and a node is one pair node of a pair, so no two
// invocations of a dispatch touch the same node (a part's slot writes its lowest node's row,
// whose own row is then zero and not written; the pairs' passes run one after another: a fixed
// order). The largest row written is reduced in the workgroup, then raised with one atomicMax:
// one atomic per 64 nodes on the one statistics word, not one per node in contact.
@compute @workgroup_size(64)
fn add_forces(@builtin(workgroup_id) wg: vec3<u32>,
              @builtin(num_workgroups) nwg: vec3<u32>,
              @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    var row_bits = 0u;
    if (i < pp.n_pair_nodes + pp.body_slots.z) { row_bits = add_node(i); }
    raise_top_row(li, row_bits);
}

// Local increments, PENALTY_SLAVES_APART: the active slaves and the other pair nodes only (the
// pair nodes left out have nothing to add, and their need words were never set).
@compute @workgroup_size(64)
fn add_forces_active(@builtin(workgroup_id) wg: vec3<u32>,
                     @builtin(num_workgroups) nwg: vec3<u32>,
                     @builtin(local_invocation_index) li: u32) {
    let i = active_pair_node(folded_id(wg, nwg, li, ITEM_WORKGROUP));
    var row_bits = 0u;
    if (i != NO_SLAVE) { row_bits = add_node(i); }
    raise_top_row(li, row_bits);
}

// The workgroup's largest row (`row_bits` of invocation li) raised into STAT_OMEGA2; every
// invocation of the workgroup calls it (uniform control flow: it has barriers).
fn raise_top_row(li: u32, row_bits: u32) {
    top_row[li] = row_bits;
    workgroupBarrier();
    for (var s = 32u; s > 0u; s = s >> 1u) {
        if (li < s) { top_row[li] = max(top_row[li], top_row[li + s]); }
        workgroupBarrier();
    }
    if (li == 0u && top_row[0] != 0u) { atomicMax(&stats[STAT_OMEGA2], top_row[0]); }
}

// Pair node i's force into the caller's buffer and its row into `rows`; the bits of the row
// written (0 when none). The largest row: rows only grow within an increment (no share is
// negative), so the largest value written is the largest row once every pair has added its own.
fn add_node(i: u32) -> u32 {
    // the need word read and cleared for the next increment (a slave of a pair whose slaves are
    // no master nodes is never marked)
    var need_word = 0u;
    if (i >= pp.n_slaves || (pp.flags & PENALTY_SLAVES_APART) == 0u) {
        need_word = atomicLoad(&need[i]);
        if (need_word != 0u) { atomicStore(&need[i], 0u); }
    }
    if (no_force(i, need_word)) { return 0u; }
    let node = pair_nodes[i].x;
    let f = forces[i];
    // a rigid part's slot (after the pair's nodes) carries no force, only its row, to the
    // part's lowest node, whose own row in the pair is zero: only one of them writes
    if (i < pp.n_pair_nodes) {
        host_forces[node] = host_forces[node] + vec4<f32>(f.xyz, 0.0);
    }
    if (f.w == 0.0) { return 0u; }
    let r = rows[node] + f.w;
    rows[node] = r;
    return bitcast<u32>(max(r, 0.0));
}
