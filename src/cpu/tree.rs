//! CPU mirror of `shaders/tree.wgsl`: the search tree's boxes, refitted level by level.

use rayon::prelude::*;

use super::common::{facet_collapsed, facet_node_count, node};
use super::PAR_MIN;
use crate::search::layout::{SearchParams, TreeParams, NO_FACET, STATUS_COLLAPSED};
use crate::search::tree::boxes::{self, EMPTY};

/// Packed boxes (`[u32; 4]`, `search::tree::boxes`) of a tree of `levels` levels: one per heap
/// node, nodes 0..2^(levels+1) (node 0 unused).
pub fn box_words(levels: u32) -> usize {
    2usize << levels
}

/// The packed box of leaf slot `j` (WGSL: `leaf_box`) and whether its facet collapsed.
fn leaf_box(
    params: &SearchParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    order: &[u32],
    j: usize,
) -> ([u32; 4], bool) {
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
    let inv = boxes::box_step(m).1;
    (
        boxes::pack(
            [0, 1, 2].map(|a| boxes::code_lo(lo[a] - m, inv)),
            [0, 1, 2].map(|a| boxes::code_hi(hi[a] + m, inv)),
        ),
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
    tree: &mut [[u32; 4]],
    status: &mut [u32],
) {
    let width = 1usize << tp.bottom;
    if tp.bottom == params.tree_levels {
        let level = &mut tree[width..2 * width];
        let collapsed: u32 = level
            .par_iter_mut()
            .enumerate()
            .with_min_len(PAR_MIN)
            .map(|(j, b)| {
                let (bx, c) = leaf_box(params, nodes, facets, order, j);
                *b = bx;
                u32::from(c)
            })
            .sum();
        status[STATUS_COLLAPSED] += collapsed;
    }
    for s in 0..tp.levels {
        let w = width >> (s + 1); // nodes of the level being computed: w..2w
        let (upper, lower) = tree.split_at_mut(2 * w);
        let parents = &mut upper[w..2 * w];
        let children = &lower[..2 * w];
        parents
            .par_iter_mut()
            .enumerate()
            .with_min_len(PAR_MIN)
            .for_each(|(i, b)| {
                let (l_lo, l_hi) = boxes::codes(children[2 * i]);
                let (r_lo, r_hi) = boxes::codes(children[2 * i + 1]);
                *b = boxes::pack(
                    [0, 1, 2].map(|a| l_lo[a].min(r_lo[a])),
                    [0, 1, 2].map(|a| l_hi[a].max(r_hi[a])),
                );
            });
    }
}

/// Decodes every packed box into its lower and upper corner (`corners`, resized), with the
/// bits the kernels' `box_bounds` gives: the CPU walk's boxes. An empty box's lower corner has
/// w = 1 (its bounds are meaningless).
pub fn decode(params: &SearchParams, tree: &[[u32; 4]], corners: &mut Vec<[[f32; 4]; 2]>) {
    let step = boxes::box_step(params.box_margin).0;
    corners.resize(tree.len(), [[0.0; 4]; 2]);
    corners
        .par_iter_mut()
        .zip(tree)
        .with_min_len(PAR_MIN)
        .for_each(|(c, &b)| {
            let (lo, hi) = boxes::unpack(b, step);
            let empty = if boxes::is_empty(b) { 1.0 } else { 0.0 };
            *c = [[lo[0], lo[1], lo[2], empty], [hi[0], hi[1], hi[2], 0.0]];
        });
}
