//! CPU mirror of `shaders/motion.wgsl` (but `to_local`, in `to_local.rs`): the motion nodes
//! into the frame and the motion budget since the last global search.

use super::common::node;
use super::to_local::check_node;
use crate::abi::search::{
    FrameParams, SearchParams, FLAG_EVERY_SLAVE, FLAG_SLAVES_APART, SLAVE_TRACKED, SLAVE_WITHIN,
};
use crate::abi::status::{STATUS_BUDGET_EXCEEDED, STATUS_MASTER_MOTION, STATUS_MOTION};
use crate::geometry::V3;

/// Model node `id`'s position in the frame (WGSL: `in_frame`).
fn in_frame(frame: &FrameParams, positions: &[[f32; 4]], id: u32) -> V3<f32> {
    let p = positions[id as usize];
    V3::new(
        p[0] - frame.origin[0],
        p[1] - frame.origin[1],
        p[2] - frame.origin[2],
    )
}

/// One "invocation" per motion node (WGSL: `motion`): the node into the frame where the local
/// passes read it (every master node, and every slave they visit: tracked, or all with
/// `FLAG_EVERY_SLAVE`), named if not finite, boxed if a master node; then its motion against
/// the budget, except for a slave with a facet within the radius at the last increment that is
/// not a master node. A slave's state is the w of its reference. Each displacement since the
/// reference is taken relative to the pair's reference master node's (`params.ref_node`).
#[allow(clippy::too_many_arguments)]
pub fn motion(
    params: &SearchParams,
    frame: &FrameParams,
    positions: &[[f32; 4]],
    nodes: &mut [[f32; 4]],
    reference: &[[f32; 4]],
    motion_nodes: &[u32],
    status: &mut [u32],
    adjacency: &[u32],
) {
    let on_master = |id: u32| adjacency[id as usize + 1] > adjacency[id as usize];
    let apart = params.flags & FLAG_SLAVES_APART != 0;
    let every = params.flags & FLAG_EVERY_SLAVE != 0;
    for (k, &id) in motion_nodes[..params.n_motion_nodes as usize]
        .iter()
        .enumerate()
    {
        let x = in_frame(frame, positions, id);
        let (master, write, counts) = if k < params.n_slaves as usize {
            let master = !apart && on_master(id);
            let state = reference[id as usize][3];
            (
                master,
                master || state >= SLAVE_TRACKED || every,
                master || state < SLAVE_WITHIN,
            )
        } else {
            (on_master(id), true, true)
        };
        if write {
            let n = &mut nodes[id as usize];
            *n = [x.x, x.y, x.z, n[3]];
        }
        check_node(status, id, [x.x, x.y, x.z], master);
        if counts {
            let r = params.ref_node;
            let base = in_frame(frame, positions, r) - node(reference, r);
            let d = ((x - node(reference, id)) - base).length2().sqrt();
            status[STATUS_MOTION] = status[STATUS_MOTION].max(d.to_bits());
            if master {
                status[STATUS_MASTER_MOTION] = status[STATUS_MASTER_MOTION].max(d.to_bits());
            }
            if 2.0 * d >= params.budget {
                status[STATUS_BUDGET_EXCEEDED] = 1;
            }
        }
    }
}

/// One "invocation" per motion node: its position becomes the budget's reference, a slave's
/// state untracked until `active_mark` writes it (WGSL: `set_reference`).
pub fn set_reference(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    reference: &mut [[f32; 4]],
    motion_nodes: &[u32],
) {
    for &id in &motion_nodes[..params.n_motion_nodes as usize] {
        let n = nodes[id as usize];
        reference[id as usize] = [n[0], n[1], n[2], 0.0];
    }
}
