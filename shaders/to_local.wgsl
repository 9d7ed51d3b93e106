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
//             point). Every master node widens STATUS_BOX (atomicMin/Max on order-preserving
//             bits, so the box does not depend on the order): the box a global search takes
//             (schedule.wgsl). A node with a NaN or
//             infinite coordinate is named in STATUS_NONFINITE (the lowest such node) and left
//             out of the box.

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

@compute @workgroup_size(64)
fn to_local(@builtin(workgroup_id) wg: vec3<u32>,
            @builtin(num_workgroups) nwg: vec3<u32>,
            @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= frame.n_nodes) { return; }
    let x = positions[i].xyz - frame.origin.xyz;
    nodes[i] = vec4<f32>(x, nodes[i].w);
    if (non_finite(x.x) || non_finite(x.y) || non_finite(x.z)) {
        atomicMin(&status[STATUS_NONFINITE], i);
        return;
    }
    if (adjacency[i] != adjacency[i + 1u]) {
        for (var a = 0u; a < 3u; a++) {
            atomicMin(&status[STATUS_BOX + a], ordered_bits(x[a]));
            atomicMax(&status[STATUS_BOX + 3u + a], ordered_bits(x[a]));
        }
    }
}
