// tree.wgsl — the bounding-box tree of the global search, refitted at every global search.
// CPU mirror: src/cpu/tree.rs.
//
// The tree is a complete binary tree over the active facets (their placement in the leaf slots
// is the pair's constant, from the host: search::tree::leaf_order, median splits along the
// longest side), in heap layout: node 1 is the root, node k's children are 2k and 2k + 1, level
// l holds nodes 2^l .. 2^(l+1) − 1, and leaf slot j is node 2^L + j (L = params.tree_levels)
// holding facet order[j], or nothing when order[j] = NO_FACET.
// boxes[k] is node k's box, packed into one vec4<u32> (common.wgsl: 21-bit codes of its six
// bounds on a power-of-two grid, lower bounds rounded down and upper ones up; one load per box
// test). An empty box (no facet below, or only collapsed ones) has lo = +∞, hi = −∞.
//
// Bindings: 0 params (uniform SearchParams: tree_levels, box_margin), 1 tree (uniform
//           TreeParams of this pass), 2 nodes (local xyz), 3 facets, 4 order (active facet of
//           each leaf slot), 5 boxes (one packed vec4<u32> per node, 2^(L+1) nodes), 6 status
//           (STATUS_COLLAPSED counted).
// Dispatch: tree_refit one invocation per node of level `bottom` (2^bottom of them),
//           TREE_WORKGROUP per workgroup, folded into 2D; one pass per level, bottom = L first
//           (the leaves, from the facets), then up to the root (bottom = 0). Passes run in order, each after the last (separate
//           dispatches). No workgroup memory and no barrier: on a CPU adapter a barrier
//           switches between every SIMD group of the workgroup, and a reduction of six levels
//           per pass in workgroup memory cost 4 µs per workgroup (60 ms at 10^6 facets).
// Invariants: a leaf's box is its facet's nodes' box grown by box_margin (≥ 16 f32 ulps of the
//             frame's extent: the round-off of a closest point computed in f32) and rounded
//             outwards to the box grid, so a facet's computed distance from any point is never
//             below its box's; an inner node's box is the union of its children's (min/max of
//             the codes). Every operation is exact, so the boxes are the same bits on every
//             device and in the CPU mirror, whatever the order of execution. A facet
//             collapsed at these positions (facet_collapsed) gets an empty box (no slave finds
//             it) and is counted in STATUS_COLLAPSED. No loop.

// Rust twin: TreeParams (src/abi/search.rs), 16 bytes.
struct TreeParams {
    bottom: u32,  // the level this pass computes: the leaves from their facets, else from below
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<uniform> tree: TreeParams;
@group(0) @binding(2) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> order: array<u32>;
@group(0) @binding(5) var<storage, read_write> boxes: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read_write> status: array<atomic<u32>>;

// Invocations per workgroup (Rust twin: TREE_WORKGROUP).
const TREE_WORKGROUP: u32 = 64u;

// The codes of leaf slot j's box: its facet's nodes, grown by the margin; empty for a slot with
// no facet or a collapsed facet.
fn leaf_box(j: u32) -> array<vec3<u32>, 2> {
    var b = array<vec3<u32>, 2>(vec3<u32>(BOX_TOP), vec3<u32>(0u));
    if (order[j] == NO_FACET) { return b; }
    let fac = facets[order[j]];
    let n = facet_node_count(fac);
    let x0 = nodes[fac.x].xyz;
    let x1 = nodes[fac.y].xyz;
    var x2 = x1;
    var x3 = x1;
    if (n >= 3u) { x2 = nodes[fac.z].xyz; }
    if (n == 4u) { x3 = nodes[fac.w].xyz; }
    if (facet_collapsed(x0, x1, x2, x3, n)) {
        atomicAdd(&status[STATUS_COLLAPSED], 1u);
        return b;
    }
    let m = vec3<f32>(params.box_margin);
    let lo = min(min(x0, x1), min(x2, x3)) - m;
    let hi = max(max(x0, x1), max(x2, x3)) + m;
    let inv = box_step(params.box_margin).y;
    b[0] = vec3<u32>(box_code_lo(lo.x, inv), box_code_lo(lo.y, inv), box_code_lo(lo.z, inv));
    b[1] = vec3<u32>(box_code_hi(hi.x, inv), box_code_hi(hi.y, inv), box_code_hi(hi.z, inv));
    return b;
}

@compute @workgroup_size(64)
fn tree_refit(@builtin(workgroup_id) wg: vec3<u32>,
              @builtin(num_workgroups) nwg: vec3<u32>,
              @builtin(local_invocation_index) li: u32) {
    let j = folded_id(wg, nwg, li, TREE_WORKGROUP);
    let width = 1u << tree.bottom;  // nodes of level `bottom`: width .. 2·width − 1
    if (j >= width) { return; }
    let k = width + j;
    if (tree.bottom == params.tree_levels) {
        let b = leaf_box(j);
        boxes[k] = box_pack(b[0], b[1]);
    } else {
        let l = boxes[2u * k];
        let r = boxes[2u * k + 1u];
        boxes[k] = box_pack(min(box_codes_lo(l), box_codes_lo(r)), max(box_codes_hi(l), box_codes_hi(r)));
    }
}
