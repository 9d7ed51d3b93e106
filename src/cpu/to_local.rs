//! CPU mirror of `shaders/to_local.wgsl`: model-frame f32 positions into the local frame.

use crate::search::layout::{FrameParams, SearchParams, STATUS_FRAME_STALE};

/// One "invocation" per model node; keeps each node's mass (w) and flags a master node outside
/// the grid's box.
pub fn to_local(
    params: &SearchParams,
    frame: &FrameParams,
    positions: &[[f32; 4]],
    nodes: &mut [[f32; 4]],
    adjacency: &[u32],
    status: &mut [u32],
) {
    let top = [
        params.dims_x as f32 * params.cell_size,
        params.dims_y as f32 * params.cell_size,
        params.dims_z as f32 * params.cell_size,
    ];
    for i in 0..frame.n_nodes as usize {
        for a in 0..3 {
            nodes[i][a] = positions[i][a] - frame.origin[a];
        }
        if adjacency[i] != adjacency[i + 1]
            && !(0..3).all(|a| nodes[i][a] >= 0.0 && nodes[i][a] <= top[a])
        {
            status[STATUS_FRAME_STALE] = 1;
        }
    }
}
