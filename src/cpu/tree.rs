//! CPU mirror of `shaders/tree.wgsl`: the search tree's boxes, refitted level by level.

use rayon::prelude::*;

use super::common::{facet_collapsed, facet_node_count, node};
use super::PAR_MIN;
use crate::search::layout::{SearchParams, TreeParams, EMPTY_LO, NO_FACET, STATUS_COLLAPSED};

/// The lower and upper corner of an empty box.
const EMPTY: [[f32; 4]; 2] = [
    [EMPTY_LO, EMPTY_LO, EMPTY_LO, 0.0],
    [-EMPTY_LO, -EMPTY_LO, -EMPTY_LO, 0.0],
];

/// Words (vec4) of the boxes of a tree of `levels` levels: two per heap node, nodes
/// 0..2^(levels+1) (node 0 unused).
pub fn box_words(levels: u32) -> usize {
    4usize << levels
}

/// The box of leaf slot `j` (WGSL: `leaf_box`) and whether its facet collapsed.
fn leaf_box(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    order: &[u32],
    j: usize,
) -> ([[f32; 4]; 2], bool) {
    if order[j] == NO_FACET {
        return (EMPTY, false);
    }
    let fac = facets[order[j] as usize];
    if facet_collapsed(nodes, fac) {
        return (EMPTY, true);
    }
    let n = facet_node_count(fac);
    let m = params.box_margin;
    let mut lo = [f32::MAX; 3];
    let mut hi = [f32::MIN; 3];
    for &id in &fac[..n] {
        let x = node(nodes, id).to_array();
        for a in 0..3 {
            lo[a] = lo[a].min(x[a]);
            hi[a] = hi[a].max(x[a]);
        }
    }
    (
        [
            [lo[0] - m, lo[1] - m, lo[2] - m, 0.0],
            [hi[0] + m, hi[1] + m, hi[2] + m, 0.0],
        ],
        false,
    )
}

/// One refit pass (WGSL: `tree_refit`): the boxes of level `tp.bottom` (computed from the facets
/// at the leaves, else as the previous pass left them), then `tp.levels` levels above it, each
/// node's box the union of its children's. Collapsed facets are counted into `status`.
pub fn tree_refit(
    params: &SearchParams,
    tp: &TreeParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    order: &[u32],
    boxes: &mut [[f32; 4]],
    status: &mut [u32],
) {
    let width = 1usize << tp.bottom;
    if tp.bottom == params.tree_levels {
        let level = &mut boxes[2 * width..4 * width];
        let collapsed: u32 = level
            .par_chunks_mut(2)
            .enumerate()
            .with_min_len(PAR_MIN)
            .map(|(j, b)| {
                let (bx, c) = leaf_box(params, nodes, facets, order, j);
                b.copy_from_slice(&bx);
                u32::from(c)
            })
            .sum();
        status[STATUS_COLLAPSED] += collapsed;
    }
    for s in 0..tp.levels {
        let w = width >> (s + 1); // nodes of the level being computed: w..2w
        let (upper, lower) = boxes.split_at_mut(4 * w);
        let parents = &mut upper[2 * w..4 * w];
        let children = &lower[..4 * w];
        parents
            .par_chunks_mut(2)
            .enumerate()
            .with_min_len(PAR_MIN)
            .for_each(|(i, b)| {
                let (l, r) = (&children[4 * i..4 * i + 2], &children[4 * i + 2..4 * i + 4]);
                for a in 0..3 {
                    b[0][a] = l[0][a].min(r[0][a]);
                    b[1][a] = l[1][a].max(r[1][a]);
                }
                b[0][3] = 0.0;
                b[1][3] = 0.0;
            });
    }
}
