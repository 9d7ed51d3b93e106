// active.wgsl — the active slaves of a pair: after each global search, the slaves it left
// tracked (a master node to walk from: a facet within the tracking radius, radius + budget)
// compacted in slave order into the active list (the status buffer's words from
// ACTIVE_LIST), which the local increments' slave passes
// (local_search, penalty_active, scatter_forces_active) visit through an indirect dispatch.
// CPU mirror: src/cpu/active.rs.
//
// Why that set: an untracked slave was farther than radius + budget from every facet, and the
// motion budget asks for a global search before it and the master together can have closed
// `budget`; so until the next global search it stays beyond the radius — its hit (no facet),
// its penalty state and output (open) are what the global increment wrote, and visiting it
// again would write the same bits.
//
// Bindings: 0 params (uniform SearchParams: n_slaves, flags), 1 hits (the global search's),
//           2 work (the nearest facet's work items, free after its chunks: n_slaves + 1
//           words at offset 0, scanned in place by scan.wgsl between the two passes),
//           3 status (from word ACTIVE_LIST: the count, then the slave indices; the status
//           words before it are not touched), 4 slaves (model node ids), 5 reference (the
//           motion budget's, set_reference's just before: active_mark writes the w of each
//           slave's, its tracking state, which motion.wgsl reads in node order).
// Dispatch: active_mark and active_compact one invocation per slave, ITEM_WORKGROUP per
//           workgroup, folded into 2D, from the global slots (global increments only, after
//           nearest_facet); the work levels' scan between them.
// Invariants: active_mark writes work[i] = 1 for a slave to visit (tracked, or every slave with
//             FLAG_EVERY_SLAVE) and 0 otherwise, work[n_slaves] = 0, and the slave's state
//             (slave_state) into its own node's reference (a node set lists a node once, so
//             no two invocations write one word); after the exclusive scan,
//             active_compact writes slave i at status[ACTIVE_LIST + 1 + work[i]] (slave order:
//             the same bits every run) and the count at status[ACTIVE_LIST], from which the
//             schedule sizes ACTIVE_SLOT in the local increments that follow. No loop.

@group(0) @binding(0) var<uniform> params: SearchParams;
@group(0) @binding(1) var<storage, read> hits: array<Hit>;
@group(0) @binding(2) var<storage, read_write> work: array<u32>;
@group(0) @binding(3) var<storage, read_write> status: array<u32>;
@group(0) @binding(4) var<storage, read> slaves: array<u32>;
@group(0) @binding(5) var<storage, read_write> reference: array<vec4<f32>>;

fn visited(i: u32) -> bool {
    return (params.flags & FLAG_EVERY_SLAVE) != 0u || hits[i].node != NO_NODE;
}

@compute @workgroup_size(64)
fn active_mark(@builtin(workgroup_id) wg: vec3<u32>,
               @builtin(num_workgroups) nwg: vec3<u32>,
               @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= params.n_slaves) { return; }
    work[i] = select(0u, 1u, visited(i));
    reference[slaves[i]].w = slave_state(hits[i]);
    if (i == 0u) { work[params.n_slaves] = 0u; }
}

@compute @workgroup_size(64)
fn active_compact(@builtin(workgroup_id) wg: vec3<u32>,
                  @builtin(num_workgroups) nwg: vec3<u32>,
                  @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= params.n_slaves) { return; }
    if (visited(i)) { status[ACTIVE_LIST + 1u + work[i]] = i; }
    if (i == 0u) { status[ACTIVE_LIST] = work[params.n_slaves]; }
}
