// gather.wgsl — the contact force on every node of the pair, summed in a fixed order.
// CPU mirror: src/cpu/gather.rs.
//
// Bindings: 0 pp (uniform PenaltyParams), 1 pair_nodes (node, slave index, adjacency start,
//           end), 2 adjacency, 3 facets, 4 starts (facet → slaves, from contact_sort),
//           5 facet_slaves, 6 hits, 7 out (ContactOut), 8 forces (vec4 per pair node).
// Dispatch: one invocation per pair node, ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: a slave node gets its own contact force; a master node gets −w_j·f of every slave
//             in contact with one of its facets, in increasing facet then slave order, so the
//             sum has the same bits every run and Σ over the pair is zero to round-off.
//             forces.w: the node's row of the node-wise frequency bound, the sum of the shares
//             (bound_light, or bound_heavy where the spring marks the node heavy) of its own
//             spring and of every spring in contact on its facets, in the same order.

@group(0) @binding(0) var<uniform> pp: PenaltyParams;
@group(0) @binding(1) var<storage, read> pair_nodes: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> adjacency: array<u32>;
@group(0) @binding(3) var<storage, read> facets: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> starts: array<u32>;
@group(0) @binding(5) var<storage, read> facet_slaves: array<u32>;
@group(0) @binding(6) var<storage, read> hits: array<Hit>;
@group(0) @binding(7) var<storage, read> out: array<ContactOut>;
@group(0) @binding(8) var<storage, read_write> forces: array<vec4<f32>>;

@compute @workgroup_size(64)
fn gather(@builtin(workgroup_id) wg: vec3<u32>,
          @builtin(num_workgroups) nwg: vec3<u32>,
          @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= pp.n_pair_nodes) { return; }
    let pn = pair_nodes[i];
    var f = vec3<f32>(0.0);
    var row = 0.0;
    if (pn.y != NO_SLAVE) {
        f = out[pn.y].force.xyz;
        row = row_share(out[pn.y], HEAVY_SLAVE);
    }
    for (var a = pn.z; a < pn.w; a++) {
        let facet = adjacency[a];
        let fac = facets[facet];
        var slot = 0u;
        for (var j = 1u; j < 4u; j++) {
            if (fac[j] == pn.x) { slot = j; }
        }
        for (var k = starts[facet]; k < starts[facet + 1u]; k++) {
            let s = facet_slaves[k];
            f -= hits[s].weights[slot] * out[s].force.xyz;
            row += row_share(out[s], 1u << (HEAVY_SHIFT + slot));
        }
    }
    forces[i] = vec4<f32>(f, row);
}

// A spring's share of the bound at one of its nodes: heavy if its status has `bit`.
fn row_share(o: ContactOut, bit: u32) -> f32 {
    return select(o.bound_light, o.bound_heavy, (o.status & bit) != 0u);
}
