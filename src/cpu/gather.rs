//! CPU mirror of `shaders/gather.wgsl`: the contact force on every node of the pair.

use crate::penalty::layout::{
    ContactOut, PairNode, PenaltyParams, HEAVY_SHIFT, HEAVY_SLAVE, NO_SLAVE,
};
use crate::search::layout::GpuHit;

/// One "invocation" per pair node, summing in increasing facet then slave order.
#[allow(clippy::too_many_arguments)]
pub fn gather(
    pp: &PenaltyParams,
    pair_nodes: &[PairNode],
    adjacency: &[u32],
    facets: &[[u32; 4]],
    starts: &[u32],
    facet_slaves: &[u32],
    hits: &[GpuHit],
    out: &[ContactOut],
    forces: &mut [[f32; 4]],
) {
    for (i, pn) in pair_nodes[..pp.n_pair_nodes as usize].iter().enumerate() {
        let mut f = [0.0f32; 3];
        let mut row = 0.0f32;
        if pn.slave != NO_SLAVE {
            let o = out[pn.slave as usize].force;
            f = [o[0], o[1], o[2]];
            row = row_share(&out[pn.slave as usize], HEAVY_SLAVE);
        }
        for a in pn.adj_start..pn.adj_end {
            let facet = adjacency[a as usize] as usize;
            let fac = facets[facet];
            let slot = (1..4).filter(|&j| fac[j] == pn.node).last().unwrap_or(0);
            for k in starts[facet]..starts[facet + 1] {
                let s = facet_slaves[k as usize] as usize;
                let w = hits[s].weights[slot];
                let o = out[s].force;
                for c in 0..3 {
                    f[c] -= w * o[c];
                }
                row += row_share(&out[s], 1 << (HEAVY_SHIFT + slot as u32));
            }
        }
        forces[i] = [f[0], f[1], f[2], row];
    }
}

/// A spring's share of the node-wise bound at one of its nodes: heavy if its status has `bit`
/// (WGSL: `row_share`).
fn row_share(o: &ContactOut, bit: u32) -> f32 {
    if o.status & bit != 0 {
        o.bound_heavy
    } else {
        o.bound_light
    }
}
