// to_local.wgsl — positions the caller keeps on the device, into the search's local frame.
// CPU mirror: src/cpu/to_local.rs.
//
// Bindings: 1 frame (uniform FrameParams: the frame origin),
//           2 positions (the caller's buffer: one vec4<f32> per model node, model frame, w
//           ignored), 3 nodes (the search's nodes in its frame; w, the mass, is kept),
//           4 adjacency (as in local_search.wgsl: tells master nodes), 5 status (the master box
//           and the first non-finite node are raised here).
// Dispatch: one invocation per model node, ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: nothing is read back; the subtraction is in f32 (the caller's positions are f32
//             already, so a model far from its origin should keep them relative to a nearby
//             point). Every master node widens STATUS_BOX (min/max on order-preserving bits,
//             gathered per workgroup, then raised by three invocations: the box does not
//             depend on the order): the box a global search takes (schedule.wgsl). Every
//             invocation reaches the two workgroup barriers. A node with
//             a NaN or infinite coordinate is named in STATUS_NONFINITE (the lowest such node)
//             and left out of the box.

// Rust twin: FrameParams (src/abi/search.rs), 32 bytes.
struct FrameParams {
    origin: vec4<f32>,
    n_nodes: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(1) var<uniform> frame: FrameParams;
@group(0) @binding(2) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read_write> nodes: array<vec4<f32>>;
@group(0) @binding(4) var<storage, read> adjacency: array<u32>;
@group(0) @binding(5) var<storage, read_write> status: array<atomic<u32>>;

// The workgroup's master box (order-preserving bits: lo xyz, hi xyz), gathered by workgroup
// atomics so that one invocation per workgroup, not every master node, raises STATUS_BOX: 6
// global atomics per 64 nodes instead of 6 per master node, which all go to the same six words.
var<workgroup> wg_box: array<atomic<u32>, 6>;

@compute @workgroup_size(64)
fn to_local(@builtin(workgroup_id) wg: vec3<u32>,
            @builtin(num_workgroups) nwg: vec3<u32>,
            @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    // an empty box: nothing below the highest bits, nothing above the lowest
    if (li < 3u) {
        atomicStore(&wg_box[li], 0xffffffffu);
        atomicStore(&wg_box[3u + li], 0u);
    }
    // every invocation reaches both barriers (uniform control flow)
    workgroupBarrier();
    if (i < frame.n_nodes) {
        let x = positions[i].xyz - frame.origin.xyz;
        nodes[i] = vec4<f32>(x, nodes[i].w);
        if (non_finite(x.x) || non_finite(x.y) || non_finite(x.z)) {
            atomicMin(&status[STATUS_NONFINITE], i);
        } else if (adjacency[i] != adjacency[i + 1u]) {
            for (var a = 0u; a < 3u; a++) {
                atomicMin(&wg_box[a], ordered_bits(x[a]));
                atomicMax(&wg_box[3u + a], ordered_bits(x[a]));
            }
        }
    }
    workgroupBarrier();
    if (li < 3u) {
        let lo = atomicLoad(&wg_box[li]);
        let hi = atomicLoad(&wg_box[3u + li]);
        if (lo <= hi) {
            atomicMin(&status[STATUS_BOX + li], lo);
            atomicMax(&status[STATUS_BOX + 3u + li], hi);
        }
    }
}
