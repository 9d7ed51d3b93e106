//! CPU mirror of `shaders/tree.wgsl`: the search tree's boxes, refitted level by level.

use rayon::prelude::*;

use super::common::{facet_collapsed, facet_node_count, node};
use super::PAR_MIN;
use crate::abi::boxes::{self, EMPTY};
use crate::abi::search::{SearchParams, TreeParams, NO_FACET};
use crate::abi::status::STATUS_COLLAPSED;

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
    let (l, h) = (
        |a: usize| boxes::code_lo(lo[a] - m, inv),
        |a: usize| boxes::code_hi(hi[a] + m, inv),
    );
    (boxes::pack([l(0), l(1), l(2)], [h(0), h(1), h(2)]), false)
}

/// One refit pass (WGSL: `tree_refit`): the boxes of level `tp.bottom`, the leaves' from their
/// facets (collapsed facets counted into `status`), any other level's the union of its
/// children's. `corners` gets the same boxes decoded (lower, upper corner; the lower corner's w
/// is 1 for an empty box): the CPU walk's boxes, with the bits the kernels' `box_bounds` gives.
/// An inner node's corners are the min/max of its children's, which is exactly the decoded
/// min/max of their codes (the decoding is exact and increasing).
pub fn tree_refit(
    params: &SearchParams,
    tp: &TreeParams,
    nodes: &[[f32; 4]],
    facets: &[[u32; 4]],
    order: &[u32],
    tree: &mut [[u32; 4]],
    corners: &mut [[[f32; 4]; 2]],
    status: &mut [u32],
) {
    let width = 1usize << tp.bottom;
    let step = boxes::box_step(params.box_margin).0;
    let level = &mut tree[width..2 * width];
    let (upper, lower) = corners.split_at_mut(2 * width);
    let level_corners = &mut upper[width..2 * width];
    if tp.bottom == params.tree_levels {
        let collapsed: u32 = level
            .par_iter_mut()
            .zip(level_corners.par_iter_mut())
            .enumerate()
            .with_min_len(PAR_MIN)
            .map(|(j, (b, c))| {
                let (bx, collapsed) = leaf_box(params, nodes, facets, order, j);
                *b = bx;
                *c = decoded(bx, step);
                u32::from(collapsed)
            })
            .sum();
        status[STATUS_COLLAPSED] += collapsed;
        return;
    }
    let children = &lower[..2 * width];
    let (tree_upper, tree_lower) = tree.split_at_mut(2 * width);
    let level = &mut tree_upper[width..2 * width];
    let child_boxes = &tree_lower[..2 * width];
    level
        .par_iter_mut()
        .zip(level_corners.par_iter_mut())
        .enumerate()
        .with_min_len(PAR_MIN)
        .for_each(|(i, (b, c))| {
            let (l, r) = (child_boxes[2 * i], child_boxes[2 * i + 1]);
            *b = union(l, r);
            let [ll, lh] = children[2 * i].map(glam::Vec4::from_array);
            let [rl, rh] = children[2 * i + 1].map(glam::Vec4::from_array);
            *c = [ll.min(rl).to_array(), lh.max(rh).to_array()];
        });
}

/// The union of two packed boxes: min of the lower codes, max of the upper ones (WGSL: the
/// refit's `box_pack(min(…), max(…))`).
fn union(l: [u32; 4], r: [u32; 4]) -> [u32; 4] {
    let (l_lo, l_hi) = boxes::codes(l);
    let (r_lo, r_hi) = boxes::codes(r);
    boxes::pack(
        [
            l_lo[0].min(r_lo[0]),
            l_lo[1].min(r_lo[1]),
            l_lo[2].min(r_lo[2]),
        ],
        [
            l_hi[0].max(r_hi[0]),
            l_hi[1].max(r_hi[1]),
            l_hi[2].max(r_hi[2]),
        ],
    )
}

/// A packed box decoded: lower and upper corner, the lower's w 1 when it is empty.
fn decoded(b: [u32; 4], step: f32) -> [[f32; 4]; 2] {
    let (lo, hi) = boxes::codes(b);
    let q = |c: u32| boxes::bound(c, step);
    let empty = if boxes::is_empty(b) { 1.0 } else { 0.0 };
    [
        [q(lo[0]), q(lo[1]), q(lo[2]), empty],
        [q(hi[0]), q(hi[1]), q(hi[2]), 0.0],
    ]
}
