// motion.wgsl — the motion budget: how far the pair's nodes moved since the last global search.
// CPU mirror: src/cpu/motion.rs.
//
// Bindings: 0 params (uniform SearchParams), 1 nodes (in the frame of the last global
//           search), 2 reference (positions at the last global search, same frame),
//           3 motion_nodes (the slave nodes, in slave order, then the master surface's other
//           nodes), 4 status, 5 hits (each slave's facet at the last increment), 6 adjacency (as in
//           local_search.wgsl: a node with active facets is a master node).
// Dispatch: motion and set_reference one invocation per motion node, ITEM_WORKGROUP per
//           workgroup, folded into 2D (set_reference indirect from the plan: global increments
//           of a device-resident increment make their positions the new reference).
// Invariants: a slave with a facet within the radius at the last increment is followed by the
//             local search whatever it moves, so only the other slaves (untracked: no facet
//             within the tracking radius at the last global search; or tracked from beyond the
//             radius, whose walk may have far to go) and the master nodes count — a slave in
//             contact that is also a master node (self-contact) counts as a master node: other
//             slaves may be closing on it. Displacements are relative to the pair's reference master
//             node's (params.ref_node, itself a watched node): |d_s − d_m| ≤ |d_s − d_r| +
//             |d_m − d_r| for any common d_r, so the bound holds and a contact model travelling
//             as a whole uses none of the budget. If twice one of them reaches the budget —
//             an untracked slave and the master could together have closed it —
//             STATUS_BUDGET_EXCEEDED is set and the increment runs again with a global search.
//             The largest such displacement is reduced with atomicMax on its bits (positive
//             floats order as their bits).

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> nodes: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> reference: array<vec4<f32>>;
@group(0) @binding(3) var<storage, read> motion_nodes: array<u32>;
@group(0) @binding(4) var<storage, read_write> status: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read> hits: array<Hit>;
@group(0) @binding(6) var<storage, read> adjacency: array<u32>;

@compute @workgroup_size(64)
fn motion(@builtin(workgroup_id) wg: vec3<u32>,
          @builtin(num_workgroups) nwg: vec3<u32>,
          @builtin(local_invocation_index) li: u32) {
    let k = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (k >= params.n_motion_nodes) { return; }
    let id = motion_nodes[k];
    if (k < params.n_slaves && hits[k].facet != NO_FACET && adjacency[id + 1u] == adjacency[id]) {
        return;
    }
    let r = params.ref_node;
    let base = nodes[r].xyz - reference[r].xyz;
    let d = length((nodes[id].xyz - reference[id].xyz) - base);
    atomicMax(&status[STATUS_MOTION], bitcast<u32>(d));
    if (2.0 * d >= params.budget) {
        atomicStore(&status[STATUS_BUDGET_EXCEEDED], 1u);
    }
}

@compute @workgroup_size(64)
fn set_reference(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    let k = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (k >= params.n_motion_nodes) { return; }
    let id = motion_nodes[k];
    reference[id] = nodes[id];
}
