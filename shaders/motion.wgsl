// motion.wgsl — the caller's positions into the search's frame, and the motion budget: how far
// the pair's nodes moved since the last global search.
// CPU mirrors: src/cpu/to_local.rs (to_local), src/cpu/motion.rs (the others).
//
// Bindings: 0 params (uniform SearchParams), 1 nodes (in the search's frame; w, the mass, is
//           kept), 2 reference (xyz: positions at the last global search, same frame; w of a
//           slave: its tracking state at the last increment, SLAVE_TRACKED and SLAVE_WITHIN in
//           common.wgsl, written by active_mark and local_search), 3 motion_nodes (the slave
//           nodes in node order, then the master surface's other nodes in node order), 4 status
//           (the master box, the first non-finite node and the budget are raised here),
//           6 adjacency (as in local_search.wgsl: a node with active facets is a master node),
//           7 frame (uniform FrameParams: the frame origin), 8 positions (the caller's buffer:
//           one vec4<f32> per model node, model frame, w ignored).
// Dispatch: one invocation per node, ITEM_WORKGROUP per workgroup, folded into 2D — to_local per
//           model node (small sliding: every increment; otherwise global increments, indirect
//           from the plan, before the search); motion per motion node, every increment;
//           set_reference per motion node, indirect from the plan (global increments).
// Invariants: nothing is read back; the subtraction is in f32 (the caller's positions are f32
//             already, so a model far from its origin should keep them relative to a nearby
//             point), the same in every entry point, so a node has the same bits whichever wrote
//             it. Every master node widens STATUS_BOX (min/max on order-preserving bits,
//             gathered per workgroup, then raised by three invocations: the box does not depend
//             on the order) — the box a global search takes (schedule.wgsl). A node with a NaN or
//             infinite coordinate is named in STATUS_NONFINITE (the lowest such node) and left out
//             of the box. Every invocation reaches the two workgroup barriers.
//
// The motion budget: a slave with a facet within the radius at the last increment is followed by
// the local search whatever it moves, so only the other slaves (untracked: no facet within the
// tracking radius at the last global search; or tracked from beyond the radius, whose walk may
// have far to go) and the master nodes count — a slave in contact that is also a master node
// (self-contact) counts as a master node: other slaves may be closing on it. Displacements are
// relative to the pair's reference master node's (params.ref_node): |d_s − d_m| ≤ |d_s − d_r| +
// |d_m − d_r| for any common d_r, so the bound holds and a contact model travelling as a whole
// uses none of the budget. If twice one of them reaches the budget — an untracked slave and the
// master could together have closed it — STATUS_BUDGET_EXCEEDED is set and the increment runs
// again with a global search. The largest such displacement is reduced with atomicMax on its bits
// (positive floats order as their bits), in the workgroup first, then once per workgroup.
//
// What motion writes: the node of every master node and of every slave the local increments visit
// (tracked, or every slave with FLAG_EVERY_SLAVE) — the nodes the local search and the penalty
// read. An untracked slave of a pair whose slaves are on no master facet (FLAG_SLAVES_APART) is
// read for the budget (its position and reference, whose w is its state: 36 bytes with its id)
// and not written: nothing reads its node before the next global search, whose to_local writes
// every node first. A non-finite coordinate of a node that is no motion node is named by that
// to_local: at the next global search.
//
// Node order: the motion nodes are visited in node order, and a slave's state is read beside its
// reference, by node, not from its hit (by slave: in Morton order, a scattered read per slave).
// The caller's positions, the references and the frame's nodes are then read in node order
// whatever order the pair keeps its slaves in.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read_write> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> reference: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> motion_nodes: array<u32>;
@group(0) @binding(4) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read> adjacency: array<u32>;
@group(0) @binding(7) var<uniform> frame: FrameParams;
@group(0) @binding(8) var<storage, read> positions: array<vec4<f32>>;

// Rust twin: FrameParams (src/abi/search.rs), 32 bytes.
struct FrameParams {
    origin: vec4<f32>,
    n_nodes: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// The workgroup's master box (order-preserving bits: lo xyz, hi xyz), gathered by workgroup
// atomics so that one invocation per workgroup, not every master node, raises STATUS_BOX: 6
// global atomics per 64 nodes instead of 6 per master node, which all go to the same six words.
var<workgroup> wg_box: array<atomic<u32>, 6>;

// The workgroup's largest motion counted by the budget (bits of non-negative f32, integer max):
// of every node the budget counts (STATUS_MOTION, slot 0) and of the master nodes alone
// (STATUS_MASTER_MOTION, slot 1), raised once per workgroup like the box.
var<workgroup> wg_motion: array<atomic<u32>, 2>;

// Model node id's position in the frame.
fn in_frame(id: u32) -> vec3<f32> {
    return positions[id].xyz - frame.origin.xyz;
}

// An empty box: nothing below the highest bits, nothing above the lowest.
fn box_start(li: u32) {
    if (li < 3u) {
        atomicStore(&wg_box[li], 0xffffffffu);
        atomicStore(&wg_box[3u + li], 0u);
    }
}

// Node id at x: named if not finite, else (a master node) in the workgroup's box.
fn check_node(id: u32, x: vec3<f32>, master: bool) {
    if (non_finite(x.x) || non_finite(x.y) || non_finite(x.z)) {
        atomicMin(&status[STATUS_NONFINITE], id);
    } else if (master) {
        for (var a = 0u; a < 3u; a++) {
            atomicMin(&wg_box[a], ordered_bits(x[a]));
            atomicMax(&wg_box[3u + a], ordered_bits(x[a]));
        }
    }
}

// The workgroup's box into STATUS_BOX.
fn box_finish(li: u32) {
    if (li < 3u) {
        let lo = atomicLoad(&wg_box[li]);
        let hi = atomicLoad(&wg_box[3u + li]);
        if (lo <= hi) {
            atomicMin(&status[STATUS_BOX + li], lo);
            atomicMax(&status[STATUS_BOX + 3u + li], hi);
        }
    }
}

// Every model node into the frame: small sliding (the anchors read any of them), and global
// increments before the search (there it raises the same box again after the schedule took
// motion's: harmless, read by no one, and it names a non-finite node in no pair).
@compute @workgroup_size(64)
fn to_local(@builtin(workgroup_id) wg: vec3<u32>,
            @builtin(num_workgroups) nwg: vec3<u32>,
            @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    box_start(li);
    // every invocation reaches both barriers (uniform control flow)
    workgroupBarrier();
    if (i < frame.n_nodes) {
        let x = in_frame(i);
        nodes[i] = vec4<f32>(x, nodes[i].w);
        check_node(i, x, adjacency[i] != adjacency[i + 1u]);
    }
    workgroupBarrier();
    box_finish(li);
}

// Every increment: each motion node into the frame where the local passes read it, checked and
// boxed, and its motion against the budget.
@compute @workgroup_size(64)
fn motion(@builtin(workgroup_id) wg: vec3<u32>,
          @builtin(num_workgroups) nwg: vec3<u32>,
          @builtin(local_invocation_index) li: u32) {
    let k = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    box_start(li);
    if (li < 2u) { atomicStore(&wg_motion[li], 0u); }
    workgroupBarrier();
    if (k < params.n_motion_nodes) {
        let id = motion_nodes[k];
        let x = in_frame(id);
        var master = true;
        var write = true;
        var counts = true;
        if (k < params.n_slaves) {
            let apart = (params.flags & FLAG_SLAVES_APART) != 0u;
            master = !apart && adjacency[id] != adjacency[id + 1u];
            let state = reference[id].w;
            write = master || state >= SLAVE_TRACKED || (params.flags & FLAG_EVERY_SLAVE) != 0u;
            // untracked, or tracked with no facet within the radius
            counts = master || state < SLAVE_WITHIN;
        } else {
            master = adjacency[id] != adjacency[id + 1u];
        }
        if (write) { nodes[id] = vec4<f32>(x, nodes[id].w); }
        check_node(id, x, master);
        if (counts) {
            let r = params.ref_node;
            let base = in_frame(r) - reference[r].xyz;
            let d = length((x - reference[id].xyz) - base);
            atomicMax(&wg_motion[0], bitcast<u32>(d));
            if (master) { atomicMax(&wg_motion[1], bitcast<u32>(d)); }
            if (2.0 * d >= params.budget) {
                atomicStore(&status[STATUS_BUDGET_EXCEEDED], 1u);
            }
        }
    }
    workgroupBarrier();
    box_finish(li);
    if (li < 2u) {
        let d = atomicLoad(&wg_motion[li]);
        if (d != 0u) {
            atomicMax(&status[select(STATUS_MOTION, STATUS_MASTER_MOTION, li == 1u)], d);
        }
    }
}

// Global increments: each motion node's position becomes the budget's reference, a slave's state
// untracked until active_mark, which runs next, writes it from the new hit.
@compute @workgroup_size(64)
fn set_reference(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    let k = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (k >= params.n_motion_nodes) { return; }
    let id = motion_nodes[k];
    reference[id] = vec4<f32>(nodes[id].xyz, 0.0);
}
