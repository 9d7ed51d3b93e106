// contact_sort.wgsl — group the slave nodes in contact by master facet, in slave order, so that
// the gather can sum each master node's forces in a fixed order (no float atomics).
// CPU mirror: src/cpu/contact_sort.rs. The prefix sum between count_by_facet and
// scatter_by_facet is scan.wgsl, run on the facet counts.
//
// Bindings: 0 pp (uniform PenaltyParams), 1 hits, 2 out (ContactOut), 3 counts/starts
//           (n_facets + 1 words: counts, then exclusive starts after the scan), 4 cursor
//           (a copy of the starts, bumped atomically), 5 facet_slaves (n_slaves words).
// Dispatch: count_by_facet and scatter_by_facet one invocation per slave, sort_by_facet one per
//           facet; ITEM_WORKGROUP per workgroup, folded into 2D.
// Invariants: only slaves whose status is not open are grouped; facet_slaves holds at most
//             n_slaves entries, so nothing can overflow; after sort_by_facet each facet's slaves
//             are in increasing slave order whatever the scatter's scheduling.

@group(0) @binding(0) var<uniform> pp: PenaltyParams;
@group(0) @binding(1) var<storage, read> hits: array<Hit>;
@group(0) @binding(2) var<storage, read> out: array<ContactOut>;
@group(0) @binding(3) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read_write> cursor: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read_write> facet_slaves: array<u32>;

@compute @workgroup_size(64)
fn count_by_facet(@builtin(workgroup_id) wg: vec3<u32>,
                  @builtin(num_workgroups) nwg: vec3<u32>,
                  @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= pp.n_slaves) { return; }
    if ((out[i].status & CSTATUS_MASK) == CSTATUS_OPEN) { return; }
    atomicAdd(&counts[hits[i].facet], 1u);
}

@compute @workgroup_size(64)
fn scatter_by_facet(@builtin(workgroup_id) wg: vec3<u32>,
                    @builtin(num_workgroups) nwg: vec3<u32>,
                    @builtin(local_invocation_index) li: u32) {
    let i = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (i >= pp.n_slaves) { return; }
    if ((out[i].status & CSTATUS_MASK) == CSTATUS_OPEN) { return; }
    let slot = atomicAdd(&cursor[hits[i].facet], 1u);
    facet_slaves[slot] = i;
}

@compute @workgroup_size(64)
fn sort_by_facet(@builtin(workgroup_id) wg: vec3<u32>,
                 @builtin(num_workgroups) nwg: vec3<u32>,
                 @builtin(local_invocation_index) li: u32) {
    let f = folded_id(wg, nwg, li, ITEM_WORKGROUP);
    if (f >= pp.n_facets) { return; }
    let s = atomicLoad(&counts[f]);
    let e = atomicLoad(&counts[f + 1u]);
    for (var i = s + 1u; i < e; i++) {
        let key = facet_slaves[i];
        var j = i;
        while (j > s && facet_slaves[j - 1u] > key) {
            facet_slaves[j] = facet_slaves[j - 1u];
            j--;
        }
        facet_slaves[j] = key;
    }
}
