//! CPU mirror of `to_local` in `shaders/motion.wgsl`: model-frame f32 positions into the local
//! frame (small sliding: every model node).

use crate::abi::search::{ordered_bits, FrameParams};
use crate::abi::status::{STATUS_BOX, STATUS_NONFINITE};

/// One "invocation" per model node; keeps each node's mass (w), widens the master box and
/// names the lowest non-finite node (status words).
pub fn to_local(
    frame: &FrameParams,
    positions: &[[f32; 4]],
    nodes: &mut [[f32; 4]],
    adjacency: &[u32],
    status: &mut [u32],
) {
    for i in 0..frame.n_nodes as usize {
        for a in 0..3 {
            nodes[i][a] = positions[i][a] - frame.origin[a];
        }
        let x = nodes[i];
        check_node(
            status,
            i as u32,
            [x[0], x[1], x[2]],
            adjacency[i] != adjacency[i + 1],
        );
    }
}

/// Node `id` at `x` (in the frame): named in `STATUS_NONFINITE` if a coordinate is not finite,
/// else, a master node, in the box (WGSL: `check_node`, with the workgroup's box folded in).
pub fn check_node(status: &mut [u32], id: u32, x: [f32; 3], master: bool) {
    if x.iter().any(|v| !v.is_finite()) {
        status[STATUS_NONFINITE] = status[STATUS_NONFINITE].min(id);
    } else if master {
        for a in 0..3 {
            status[STATUS_BOX + a] = status[STATUS_BOX + a].min(ordered_bits(x[a]));
            status[STATUS_BOX + 3 + a] = status[STATUS_BOX + 3 + a].max(ordered_bits(x[a]));
        }
    }
}
