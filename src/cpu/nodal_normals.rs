//! CPU mirror of `shaders/nodal_normals.wgsl`: smoothed nodal normals of the master nodes.

use super::common::{facet_node_count, node};
use crate::abi::penalty::{PairNode, PenaltyParams, PENALTY_SLAVES_APART};
use crate::geometry::V3;

/// Area vector of a facet (WGSL: `facet_area_normal`).
pub fn facet_area_normal(nodes: &[[f32; 4]], fac: [u32; 4]) -> V3<f32> {
    let x0 = node(nodes, fac[0]);
    let x1 = node(nodes, fac[1]);
    let n = facet_node_count(fac);
    if n == 2 {
        let t = x1 - x0;
        return V3::new(t.y, -t.x, 0.0);
    }
    let x2 = node(nodes, fac[2]);
    if n == 3 {
        return (x1 - x0).cross(x2 - x0) * 0.5;
    }
    (x2 - x0).cross(node(nodes, fac[3]) - x1) * 0.5
}

/// One "invocation" per pair node; writes `normals[node]` for nodes on at least one facet.
pub fn nodal_normals(
    pp: &PenaltyParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    pair_nodes: &[PairNode],
    adjacency: &[u32],
    normals: &mut [[f32; 4]],
) {
    // a pair whose slaves are no master nodes: the slaves (the first pair nodes) have no normal
    let first = if pp.flags & PENALTY_SLAVES_APART != 0 {
        pp.n_slaves as usize
    } else {
        0
    };
    for pn in &pair_nodes[first.min(pp.n_pair_nodes as usize)..pp.n_pair_nodes as usize] {
        if pn.adj_start == pn.adj_end {
            continue;
        }
        let mut sum = V3::zero();
        for a in pn.adj_start..pn.adj_end {
            sum = sum + facet_area_normal(nodes, facets[adjacency[a as usize] as usize]);
        }
        let n = sum.normalize_or_zero();
        normals[pn.node as usize] = [n.x, n.y, n.z, 0.0];
    }
}
