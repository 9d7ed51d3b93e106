//! CPU mirror of `shaders/nodal_normals.wgsl`: smoothed nodal normals of the master nodes
//! (every one, or those the springs read this increment).

use super::common::{facet_node_count, node};
use crate::abi::penalty::{PairNode, PenaltyParams, NEED_NORMAL, PENALTY_SLAVES_APART};
use crate::abi::search::GpuHit;
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

/// Pair node `pn`'s normal, if it is on a facet.
fn node_normal(
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    pn: &PairNode,
    adjacency: &[u32],
    normals: &mut [[f32; 4]],
) {
    if pn.adj_start == pn.adj_end {
        return;
    }
    let mut sum = V3::zero();
    for a in pn.adj_start..pn.adj_end {
        sum = sum + facet_area_normal(nodes, facets[adjacency[a as usize] as usize]);
    }
    let n = sum.normalize_or_zero();
    normals[pn.node as usize] = [n.x, n.y, n.z, 0.0];
}

/// The first pair node that may have a normal: after the slaves where no slave is a master
/// node (WGSL: `apart_slave`).
fn first_master(pp: &PenaltyParams) -> usize {
    if pp.flags & PENALTY_SLAVES_APART != 0 {
        (pp.n_slaves as usize).min(pp.n_pair_nodes as usize)
    } else {
        0
    }
}

/// One "invocation" per pair node; writes `normals[node]` for nodes on at least one facet: every
/// one (`need` `None`: WGSL `nodal_normals`, small sliding), or those marked `NEED_NORMAL` in
/// `need` (WGSL: `nodal_normals_needed`).
pub fn nodal_normals(
    pp: &PenaltyParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    pair_nodes: &[PairNode],
    adjacency: &[u32],
    normals: &mut [[f32; 4]],
    need: Option<&[u32]>,
) {
    for i in first_master(pp)..pp.n_pair_nodes as usize {
        if need.is_none_or(|need| need[i] & NEED_NORMAL != 0) {
            node_normal(nodes, facets, &pair_nodes[i], adjacency, normals);
        }
    }
}

/// One "invocation" per active slave (`active`: the count, then the slave indices): the facet
/// nodes of one with a facet marked `NEED_NORMAL` in `need` (WGSL: `need_normals`).
pub fn need_normals(
    pp: &PenaltyParams,
    hits: &[GpuHit],
    active: &[u32],
    facet_nodes: &[[u32; 4]],
    need: &mut [u32],
) {
    let count = active.first().map_or(0, |&c| c as usize);
    for &i in active.get(1..1 + count).unwrap_or(&[]) {
        let facet = hits[i as usize].facet;
        if facet >= pp.n_facets {
            continue;
        }
        let fac = facet_nodes[facet as usize];
        for &node in fac.iter().take(facet_node_count(fac)) {
            need[node as usize] |= NEED_NORMAL;
        }
    }
}
