//! CPU mirror of `shaders/motion.wgsl`: the motion budget since the last global search.

use super::common::node;
use crate::abi::search::{GpuHit, SearchParams, NO_FACET};
use crate::abi::status::{STATUS_BUDGET_EXCEEDED, STATUS_MOTION};

/// One "invocation" per motion node; slaves with a facet within the radius at the last
/// increment that are not master nodes (no active facet in `adjacency`) are skipped. Each displacement since the reference is taken relative
/// to the pair's reference master node's (`params.ref_node`).
pub fn motion(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    reference: &[[f32; 4]],
    motion_nodes: &[u32],
    status: &mut [u32],
    hits: &[GpuHit],
    adjacency: &[u32],
) {
    for (k, &id) in motion_nodes[..params.n_motion_nodes as usize]
        .iter()
        .enumerate()
    {
        let master = adjacency[id as usize + 1] > adjacency[id as usize];
        if k < params.n_slaves as usize && hits[k].facet != NO_FACET && !master {
            continue;
        }
        let base = node(nodes, params.ref_node) - node(reference, params.ref_node);
        let d = ((node(nodes, id) - node(reference, id)) - base)
            .length2()
            .sqrt();
        status[STATUS_MOTION] = status[STATUS_MOTION].max(d.to_bits());
        if 2.0 * d >= params.budget {
            status[STATUS_BUDGET_EXCEEDED] = 1;
        }
    }
}

/// One "invocation" per motion node: its position becomes the budget's reference
/// (WGSL: `set_reference`).
pub fn set_reference(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    reference: &mut [[f32; 4]],
    motion_nodes: &[u32],
) {
    for &id in &motion_nodes[..params.n_motion_nodes as usize] {
        reference[id as usize] = nodes[id as usize];
    }
}
