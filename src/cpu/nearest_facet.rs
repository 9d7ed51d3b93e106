//! CPU mirror of `shaders/nearest_facet.wgsl`: the nearest active facet of each slave node, by
//! a pruned walk of the search tree, finished in bounded chunks where the walk's cap cut it off.
//!
//! Long file: it mirrors one 531-line shader with seven entry points, function for function,
//! so that each can be read beside its WGSL.

use rayon::prelude::*;

use super::common::{excluded, facet_node_count, node, share_node};
use super::PAR_MIN;
use crate::abi::boxes;
use crate::abi::search::BEST_WORDS;
use crate::abi::search::{
    GpuHit, SearchParams, FLAG_BUCKETS, FLAG_SELF_CONTACT, HIT_BESIDE_FREE_EDGE, NO_FACET,
    WALK_GROUP,
};
use crate::abi::status::{STATUS_CROWDED, STATUS_FALLBACK};
use crate::geometry::{closest_on_quad, closest_on_segment, closest_on_triangle, Projection, V3};

/// Nearest point on a padded facet (WGSL: `project`).
pub fn project(nodes: &[[f32; 4]], p: V3<f32>, fac: [u32; 4]) -> Projection<f32> {
    let n = facet_node_count(fac);
    let x0 = node(nodes, fac[0]);
    let x1 = node(nodes, fac[1]);
    if n == 2 {
        return closest_on_segment(p, x0, x1);
    }
    let x2 = node(nodes, fac[2]);
    if n == 3 {
        return closest_on_triangle(p, x0, x1, x2);
    }
    closest_on_quad(p, [x0, x1, x2, node(nodes, fac[3])])
}

/// Candidates one work item projects at most (WGSL: `CANDIDATE_CHUNK`).
pub const CANDIDATE_CHUNK: u32 = 1024;

/// Tree nodes one walk visits at most (WGSL: `WALK_VISITS`).
pub const WALK_VISITS: u32 = 2048;

/// A subtree is skipped when its box's distance² exceeds the bound by this factor
/// (WGSL: `PRUNE_SLACK`).
pub const PRUNE_SLACK: f32 = 1.0001;

/// The slave at walk position t (WGSL: `walk_point`): position in the frame and node id.
pub(super) fn walk_point(c: &Candidates<'_>, t: usize) -> (V3<f32>, u32) {
    let w = c.walk_points[t];
    (
        V3::new(
            f32::from_bits(w[0]),
            f32::from_bits(w[1]),
            f32::from_bits(w[2]),
        ),
        w[3],
    )
}

/// The inputs every pass reads.
#[derive(Clone, Copy)]
pub struct Candidates<'a> {
    /// Uniform parameters.
    pub params: &'a SearchParams,
    /// Grid-local node positions.
    pub nodes: &'a [[f32; 4]],
    /// Active facets, padded.
    pub facets: &'a [[u32; 4]],
    /// Node id per slave.
    pub slaves: &'a [u32],
    /// The slaves in the order the walks take them (Morton order of their start positions).
    pub walk_order: &'a [u32],
    /// Per walk position: the slave's position (f32 bits, xyz) and node id (w), from
    /// [`walk_start`].
    pub walk_points: &'a [[u32; 4]],
    /// Active facet of each leaf slot of the tree.
    pub order: &'a [u32],
    /// The tree's packed boxes (one per heap node, `abi::boxes`).
    pub boxes: &'a [[u32; 4]],
    /// The same boxes decoded: lower and upper corner (w 0) per heap node.
    pub corners: &'a [[[f32; 4]; 2]],
    /// Node→facet adjacency.
    pub adjacency: &'a [u32],
}

impl Candidates<'_> {
    /// Whether tree node k holds nothing within distance² `bound` of the point whose box point
    /// is q (WGSL: `far`): its box is empty or farther.
    fn far(&self, k: u32, q: glam::Vec4, bound: f32) -> bool {
        let (lo, hi) = corners(self, k);
        lo.w != 0.0 || box_d2_of(lo, hi, q) > bound * PRUNE_SLACK
    }

    /// The point box tests measure from (WGSL: `box_point`): p clamped into the box grid's
    /// finite range, w = 0.
    pub(super) fn box_point(&self, p: V3<f32>) -> glam::Vec4 {
        let step = boxes::box_step(self.params.box_margin).0;
        glam::Vec4::new(
            boxes::point(p.x, step),
            boxes::point(p.y, step),
            boxes::point(p.z, step),
            0.0,
        )
    }

    /// Leaf slot count 2^L.
    pub(super) fn leaves(&self) -> u32 {
        1 << self.params.tree_levels
    }

    pub(super) fn excluded(&self, slave: u32, f: u32) -> bool {
        excluded(
            self.params,
            self.facets,
            self.adjacency,
            slave,
            self.facets[f as usize],
        )
    }
}

/// The node a depth-first walk visits after the subtree of node k; 0 when none is left
/// (WGSL: `next_node`).
pub fn next_node(k: u32) -> u32 {
    let mut n = k;
    let mut s = 0;
    while s < 32 && n & 1 == 1 {
        n >>= 1;
        s += 1;
    }
    if n == 0 {
        0
    } else {
        n + 1
    }
}

/// The first leaf slot under node k ≥ 1 of a tree of `levels` levels (WGSL: `first_leaf`).
pub fn first_leaf(k: u32, levels: u32) -> u32 {
    let depth = 31 - k.leading_zeros();
    (k << (levels - depth)) - (1 << levels)
}

/// What a walk found (WGSL: `Walk`).
struct Walk {
    d2: f32,
    f: u32,
    next: u32,
    projections: u32,
}

/// Tree node k's lower and upper corner, decoded (WGSL: `box_bounds(box_codes_lo(b), step)`,
/// `box_bounds(box_codes_hi(b), step)` of its packed box); the lower corner's w is 1 when the
/// box is empty.
#[inline]
fn corners(c: &Candidates<'_>, k: u32) -> (glam::Vec4, glam::Vec4) {
    let [lo, hi] = c.corners[k as usize];
    (glam::Vec4::from_array(lo), glam::Vec4::from_array(hi))
}

/// The decoded boxes of inner node k's two children (lower and upper corner of each; one
/// bounds check for the pair).
#[inline]
fn children(c: &Candidates<'_>, k: u32) -> [glam::Vec4; 4] {
    let b: &[[[f32; 4]; 2]; 2] = c.corners[2 * k as usize..2 * k as usize + 2]
        .try_into()
        .expect("two boxes");
    [b[0][0], b[0][1], b[1][0], b[1][1]].map(glam::Vec4::from_array)
}

/// Distance² from the box point q (w = 0) to the non-empty box [lo, hi] (WGSL:
/// `packed_box_d2`, the same operations in the same order: the components in SIMD lanes, the
/// sum in x, y, z order).
#[inline]
pub(super) fn box_d2_of(lo: glam::Vec4, hi: glam::Vec4, p: glam::Vec4) -> f32 {
    let d = (lo - p).max(p - hi).max(glam::Vec4::ZERO);
    let d = d * d;
    d.x + d.y + d.z
}

/// Distance² from the box point q (w = 0) to the centre of the box [lo, hi] (WGSL: the walk's
/// `cl`, `cr`).
#[inline]
fn centre_d2_of(lo: glam::Vec4, hi: glam::Vec4, p: glam::Vec4) -> f32 {
    let d = 0.5 * (lo + hi) - p;
    let d = d * d;
    d.x + d.y + d.z
}

/// The depth of heap node k ≥ 1 (WGSL: `firstLeadingBit(k)`).
fn depth(k: u32) -> u32 {
    31 - k.leading_zeros()
}

/// The ancestor of heap node `at` at depth `d` ≤ its own depth.
fn ancestor(at: u32, d: u32) -> u32 {
    at >> (depth(at) - d)
}

/// The square of the tracking radius, radius + budget: how far the walks look (WGSL:
/// `track_radius2`). A slave whose nearest facet lies beyond the radius but within it is
/// tracked (its hit has the node, no facet).
pub fn track_radius2(params: &SearchParams) -> f32 {
    let r = params.radius + params.budget;
    r * r
}

/// The nearest facet of the slave at walk position t a depth-first walk finds within
/// `WALK_VISITS` nodes, the nearer child first, the pending siblings one bit per depth
/// (WGSL: `walk`).
fn walk(c: &Candidates<'_>, t: usize, start: u32) -> Walk {
    let (p, slave) = walk_point(c, t);
    let leaves = c.leaves();
    // bit d: the sibling of the walk's ancestor at depth d is still to visit
    let mut pending = 0u32;
    // the node the walk was last at: its ancestors are the walk's path
    let mut last = 1u32;
    let mut w = Walk {
        d2: track_radius2(c.params),
        f: NO_FACET,
        next: 0,
        projections: 0,
    };
    let q = c.box_point(p);
    let mut k = start;
    last = last.max(start);
    let mut v = 0;
    // whether node k was reached untested: the start node, or a return to a pending subtree
    let mut untested = true;
    // two loops as in the shader (its SIMD lanes project together)
    for _leaf in 0..WALK_VISITS {
        // one inner node's two children per iteration, until a leaf, the end or the cap; a
        // return to a pending sibling goes to it untested (its children lie within its box)
        while v < WALK_VISITS {
            if k == 0 {
                if pending == 0 {
                    break;
                }
                let d = depth(pending);
                pending &= !(1 << d);
                last = ancestor(last, d) ^ 1;
                k = last;
                untested = true;
                if k < leaves && c.far(k, q, w.d2) {
                    // the shader tests its two children and finds both farther (they lie in
                    // its box): the same state after one visit, for one box test instead of two
                    k = 0;
                    v += 1;
                    continue;
                }
            }
            if k >= leaves {
                break;
            }
            let bound = w.d2 * PRUNE_SLACK;
            let (l, r) = (2 * k, 2 * k + 1);
            let [lo_l, hi_l, lo_r, hi_r] = children(c, k);
            let (dl, dr) = (box_d2_of(lo_l, hi_l, q), box_d2_of(lo_r, hi_r, q));
            untested = false;
            match (lo_l.w == 0.0 && dl <= bound, lo_r.w == 0.0 && dr <= bound) {
                (true, true) => {
                    let right_first = dr < dl
                        || (dr == dl && centre_d2_of(lo_r, hi_r, q) < centre_d2_of(lo_l, hi_l, q));
                    pending |= 1 << (depth(k) + 1);
                    k = if right_first { r } else { l };
                }
                (true, false) => k = l,
                (false, true) => k = r,
                (false, false) => {
                    last = k;
                    k = 0;
                }
            }
            v += 1;
        }
        if v >= WALK_VISITS || k < leaves {
            break;
        }
        // the leaf
        v += 1;
        if !untested || !c.far(k, q, w.d2) {
            let f = c.order[(k - leaves) as usize];
            if !c.excluded(slave, f) {
                let d2 = project(c.nodes, p, c.facets[f as usize]).dist2;
                w.projections += 1;
                if d2 < w.d2 || (d2 == w.d2 && f < w.f) {
                    w.d2 = d2;
                    w.f = f;
                }
            }
        }
        untested = false;
        last = k;
        k = 0;
    }
    if k != 0 || pending != 0 {
        let levels = c.params.tree_levels;
        let (mut lowest, at) = if k != 0 {
            (first_leaf(k, levels), k)
        } else {
            (u32::MAX, last)
        };
        while pending != 0 {
            let d = depth(pending);
            pending &= !(1 << d);
            lowest = lowest.min(first_leaf(ancestor(at, d) ^ 1, levels));
        }
        w.next = lowest + 1;
    }
    w
}

/// The nearest facet (distance², id) of the slave at walk position i among the leaf slots of its
/// work item t, within the radius, ties to the lowest id (WGSL: `chunk_best`).
fn chunk_best(c: &Candidates<'_>, work: &[u32], b: &[u32], i: usize, t: u32) -> (f32, u32) {
    let (p, slave) = walk_point(c, i);
    let leaves = c.leaves();
    let j0 = b[5] + (t - work[i]) * CANDIDATE_CHUNK;
    let j1 = leaves.min(j0 + CANDIDATE_CHUNK);
    let mut best = (track_radius2(c.params), NO_FACET);
    for j in j0..j1 {
        let k = (leaves + j) as usize;
        if boxes::is_empty(c.boxes[k]) {
            continue; // no facet, or collapsed
        }
        let f = c.order[j as usize];
        if c.excluded(slave, f) {
            continue;
        }
        let d2 = project(c.nodes, p, c.facets[f as usize]).dist2;
        if d2 < best.0 || (d2 == best.0 && f < best.1) {
            best = (d2, f);
        }
    }
    best
}

/// One "invocation" per group of `WALK_GROUP` walk positions (WGSL: `walk_start`): walk
/// position t gets the position and node id of slave `walk_order[t]` in `walk_points`, and the
/// tree node where the group's walks start goes into `work` at each of its positions (0: no
/// facet within the radius of any of them). `corners`: the tree's decoded boxes.
pub fn walk_start(
    params: &SearchParams,
    corners: &[[[f32; 4]; 2]],
    nodes: &[[f32; 4]],
    slaves: &[u32],
    walk_order: &[u32],
    walk_points: &mut [[u32; 4]],
    work: &mut [u32],
) {
    let n = params.n_slaves as usize;
    let leaves = 1u32 << params.tree_levels;
    let bound = track_radius2(params) * PRUNE_SLACK;
    let step = boxes::box_step(params.box_margin).0;
    // whether node k's box is within the bound of the box [glo, ghi] (WGSL: `group_near`)
    let near = |k: u32, glo: glam::Vec4, ghi: glam::Vec4| {
        let [lo, hi] = corners[k as usize].map(glam::Vec4::from_array);
        let d = (lo - ghi).max(glo - hi).max(glam::Vec4::ZERO);
        let d = d * d;
        lo.w == 0.0 && d.x + d.y + d.z <= bound
    };
    let group = WALK_GROUP as usize;
    walk_points[..n]
        .par_chunks_mut(group)
        .zip(work[..n].par_chunks_mut(group))
        .zip(walk_order.par_chunks(group))
        .with_min_len(PAR_MIN / group)
        .for_each(|((points, starts), order)| {
            let mut glo = glam::Vec4::ZERO;
            let mut ghi = glam::Vec4::ZERO;
            for (j, (w, &i)) in points.iter_mut().zip(order).enumerate() {
                let slave = slaves[i as usize];
                let x = nodes[slave as usize];
                *w = [x[0].to_bits(), x[1].to_bits(), x[2].to_bits(), slave];
                let q = glam::Vec4::new(
                    boxes::point(x[0], step),
                    boxes::point(x[1], step),
                    boxes::point(x[2], step),
                    0.0,
                );
                if j == 0 {
                    (glo, ghi) = (q, q);
                }
                glo = glo.min(q);
                ghi = ghi.max(q);
            }
            // the bucket search has leaf boxes alone, and no start node
            let tree = params.flags & FLAG_BUCKETS == 0;
            let mut k = if tree && near(1, glo, ghi) { 1 } else { 0 };
            let mut s = 0;
            while s < 32 && k != 0 && k < leaves {
                let (l, r) = (near(2 * k, glo, ghi), near(2 * k + 1, glo, ghi));
                if l && r {
                    break;
                }
                k = if l {
                    2 * k
                } else if r {
                    2 * k + 1
                } else {
                    0
                };
                s += 1;
            }
            starts.fill(k);
        });
}

/// One "invocation" per walk position t: the tree walk from the start node in `work[t]`, its
/// best facet into `best`, the chunks of the leaf slots it did not reach into `work` (word
/// n_slaves set to 0 for the scan) (WGSL: `nearest_walk`).
pub fn nearest_walk(c: &Candidates<'_>, work: &mut [u32], best: &mut [u32]) {
    let n = c.params.n_slaves as usize;
    if n > 0 {
        work[n] = 0;
    }
    let n_slots = c.leaves();
    best[..BEST_WORDS * n]
        .par_chunks_mut(BEST_WORDS)
        .zip(&mut work[..n])
        .enumerate()
        .with_min_len(PAR_MIN)
        .for_each(|(t, (b, chunks))| {
            let w = walk(c, t, *chunks);
            let start = if w.next != 0 {
                (w.next - 1).min(n_slots)
            } else {
                n_slots
            };
            let rest = n_slots - start;
            b.copy_from_slice(&[
                w.d2.to_bits(),
                NO_FACET,
                0,
                w.projections + rest,
                w.f,
                start,
                w.d2.to_bits(),
                0,
            ]);
            *chunks = rest.div_ceil(CANDIDATE_CHUNK);
        });
}

/// The winner of a slave's record `b`: the chunks' facet at the best distance, or the walk's
/// when it is at that distance with a lower id (WGSL: `winner`).
pub(super) fn winner(b: &[u32]) -> u32 {
    if b[4] != NO_FACET && b[6] == b[0] && b[4] < b[1] {
        b[4]
    } else {
        b[1]
    }
}

/// One "invocation" per slave, self-contact only: the crowding flag into the record
/// (WGSL: `nearest_crowded`).
pub fn nearest_crowded(c: &Candidates<'_>, best: &mut [u32]) {
    if c.params.flags & FLAG_SELF_CONTACT == 0 {
        return;
    }
    let n = c.params.n_slaves as usize;
    best[..BEST_WORDS * n]
        .par_chunks_mut(BEST_WORDS)
        .enumerate()
        .with_min_len(PAR_MIN)
        .for_each(|(i, b)| {
            let f = winner(b);
            if f != NO_FACET && crowded(c, i, f) {
                b[2] = 1;
            }
        });
}

/// The number of work items, from the scanned `work` (WGSL: `nearest_args`, which writes the
/// indirect dispatch instead).
pub fn nearest_args(params: &SearchParams, work: &[u32]) -> u32 {
    work[params.n_slaves as usize]
}

/// The work items of each slave (`work` scanned: slave i owns items `work[i]..work[i + 1]`), in
/// parallel over the slaves on all cores, each slave's items in order, with its `best` record.
/// The GPU runs every work item as one invocation and combines a slave's through atomics whose
/// result does not depend on their order, so running a slave's items one after another on one
/// thread gives the same bits, whatever the number of threads.
fn per_slave_items(
    c: &Candidates<'_>,
    work: &[u32],
    best: &mut [u32],
    item: impl Fn(usize, u32, &mut [u32]) + Sync,
) {
    let n = c.params.n_slaves as usize;
    best[..BEST_WORDS * n]
        .par_chunks_mut(BEST_WORDS)
        .enumerate()
        .with_min_len(PAR_MIN)
        .for_each(|(i, b)| {
            for t in work[i]..work[i + 1] {
                item(i, t, b);
            }
        });
}

/// One "invocation" per work item: the chunk's nearest facet (WGSL: `nearest_chunks`).
pub fn nearest_chunks(c: &Candidates<'_>, work: &[u32], best: &mut [u32]) {
    per_slave_items(c, work, best, |i, t, b| {
        let (d2, f) = chunk_best(c, work, b, i, t);
        if f == NO_FACET {
            return;
        }
        if work[i + 1] - work[i] == 1 {
            if d2.to_bits() <= b[0] {
                b[0] = d2.to_bits();
                b[1] = f;
            }
        } else {
            b[0] = b[0].min(d2.to_bits());
        }
    });
}

/// One "invocation" per work item of slaves with several chunks: the lowest id at the best
/// distance (WGSL: `nearest_ties`).
pub fn nearest_ties(c: &Candidates<'_>, work: &[u32], best: &mut [u32]) {
    per_slave_items(c, work, best, |i, t, b| {
        if work[i + 1] - work[i] == 1 {
            return;
        }
        let (d2, f) = chunk_best(c, work, b, i, t);
        if f != NO_FACET && d2.to_bits() == b[0] {
            b[1] = b[1].min(f);
        }
    });
}

/// Self-contact: whether the slave at walk position i has a facet within the radius, other than
/// its nearest `best_f` and sharing no node with it, that faces it; a walk cut off by the cap
/// says yes (WGSL: `crowded`).
fn crowded(c: &Candidates<'_>, i: usize, best_f: u32) -> bool {
    let (p, slave) = walk_point(c, i);
    let leaves = c.leaves();
    let r2 = c.params.radius * c.params.radius;
    let q = c.box_point(p);
    let mut k = 1u32;
    for _ in 0..WALK_VISITS {
        if k == 0 {
            return false;
        }
        if c.far(k, q, r2) {
            k = next_node(k);
        } else if k >= leaves {
            let f = c.order[(k - leaves) as usize];
            if f != best_f
                && !c.excluded(slave, f)
                && !share_node(c.facets[f as usize], c.facets[best_f as usize])
            {
                // near and facing the slave (not merely beside it in its own plane)
                let pr = project(c.nodes, p, c.facets[f as usize]);
                let gap = (p - pr.point).dot(pr.normal);
                if pr.dist2 <= r2 && 4.0 * gap * gap > pr.dist2 {
                    return true;
                }
            }
            k = next_node(k);
        } else {
            k *= 2;
        }
    }
    k != 0
}

/// One "invocation" per walk position t: the hit from the winning facet, written to the hit of
/// its slave `walk_order[t]` (WGSL: `nearest_facet`). The invocations write disjoint hits (the
/// walk order is a permutation), through relaxed atomic stores so that they may run on any
/// thread: the bytes do not depend on the threads.
pub fn nearest_facet(c: &Candidates<'_>, status: &mut [u32], hits: &mut [GpuHit], best: &[u32]) {
    let (params, nodes, facets, adjacency) = (c.params, c.nodes, c.facets, c.adjacency);
    let n = params.n_slaves as usize;
    let out = super::Scatter::new(&mut hits[..n]);
    let store = |i: u32, hit: GpuHit| out.write(i as usize, hit);
    let hit_of = |t: usize, i: u32| {
        let (p, slave) = walk_point(c, t);
        let b = &best[BEST_WORDS * t..BEST_WORDS * (t + 1)];
        let candidates = b[3];
        let fallback = u32::from(b[5] < c.leaves());
        let best_f = winner(b);
        if best_f == NO_FACET {
            store(i, GpuHit::miss(slave, candidates));
            return (fallback, 0);
        }
        let fac = facets[best_f as usize];
        let best_pr = project(nodes, p, fac);
        let mut best_node = u32::MAX;
        let mut best_nd2 = 0.0f32;
        for &id in &fac[..facet_node_count(fac)] {
            let d2 = (node(nodes, id) - p).length2();
            if best_node == u32::MAX || d2 < best_nd2 || (d2 == best_nd2 && id < best_node) {
                best_node = id;
                best_nd2 = d2;
            }
        }
        if best_pr.dist2 > params.radius * params.radius {
            // beyond the radius, within the tracking radius: tracked, no facet
            let mut hit = GpuHit::miss(slave, candidates);
            hit.node = best_node;
            store(i, hit);
            return (fallback, u32::from(b[2] != 0));
        }
        let q = best_pr.point;
        let beside = super::common::beside_free_edge(
            nodes,
            facets,
            adjacency,
            best_f,
            fac,
            best_pr.weights,
            p,
            q,
            best_pr.normal,
        );
        let hit = GpuHit {
            facet: best_f,
            node: best_node,
            candidates: candidates | if beside { HIT_BESIDE_FREE_EDGE } else { 0 },
            slave,
            point_gap: [q.x, q.y, q.z, (p - q).dot(best_pr.normal)],
            normal_dist: [
                best_pr.normal.x,
                best_pr.normal.y,
                best_pr.normal.z,
                best_pr.dist2.sqrt(),
            ],
            weights: best_pr.weights,
        };
        store(i, hit);
        (fallback, u32::from(b[2] != 0))
    };
    let counts: (u32, u32) = c.walk_order[..n]
        .par_iter()
        .enumerate()
        .with_min_len(PAR_MIN)
        .fold(
            || (0, 0),
            |acc, (t, &i)| {
                let (f, c) = hit_of(t, i);
                (acc.0 + f, acc.1 + c)
            },
        )
        .map(|acc| {
            out.fence();
            acc
        })
        .reduce(|| (0, 0), |x, y| (x.0 + y.0, x.1 + y.1));
    status[STATUS_FALLBACK] += counts.0;
    status[STATUS_CROWDED] += counts.1;
}
