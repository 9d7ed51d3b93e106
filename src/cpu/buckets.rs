//! CPU mirror of `shaders/buckets.wgsl`: the seed's bucket search — the active facets binned by
//! counting sort into a hashed grid of cells sized to the facets, each slave's cells visited in
//! rings outward and pruned by the best distance so far — writing the same records as the tree
//! walk (`nearest_facet::nearest_walk`), which the chunk, tie and hit passes finish.
//!
//! `bucket_fill` writes each bucket's entries in leaf-slot order here and in the device's order
//! on a GPU; a walk takes a bucket's entries in two rounds that no order decides (the nearest
//! box first, then the others within the best distance after it), so the records are the same
//! bits either way.

use rayon::prelude::*;

use super::common::share_node;
use super::nearest_facet::{
    box_d2_of, project, track_radius2, walk_point, winner, Candidates, CANDIDATE_CHUNK, PRUNE_SLACK,
};
use super::PAR_MIN;
use crate::abi::boxes::{self, BOX_BIAS};
use crate::abi::buckets::{bucket_of, cell_shift, Ring, BIN_SPAN, BUCKET_VISITS};
use crate::abi::search::{SearchParams, BEST_WORDS, FLAG_SELF_CONTACT, NO_FACET};
use crate::geometry::V3;

/// The cells of leaf slot `j`'s packed box (lower, upper per axis), or `None` for an empty one
/// (WGSL: `box_cells`).
fn box_cells(params: &SearchParams, b: [u32; 4], s: u32) -> Option<([u32; 3], [u32; 3])> {
    if boxes::is_empty(b) {
        return None;
    }
    let (lo, hi) = boxes::codes(b);
    let (mut lo, mut hi) = (lo.map(|c| c >> s), hi.map(|c| c >> s));
    if params.dim == 2 {
        lo[2] = (BOX_BIAS as u32) >> s;
        hi[2] = lo[2];
    }
    Some((lo, hi))
}

/// The buckets a box spanning cells `lo..=hi` is binned in: each of its cells' (at most
/// `BIN_SPAN` per axis), or the last bucket alone (WGSL: `binned`, `bin_cell`).
fn bins(params: &SearchParams, lo: [u32; 3], hi: [u32; 3]) -> impl Iterator<Item = u32> {
    let bits = params.bucket_bits;
    let binned = (0..3).all(|a| hi[a] - lo[a] < BIN_SPAN);
    (0..if binned { 8 } else { 1 }).filter_map(move |k| {
        if !binned {
            return Some(1 << bits);
        }
        let d = [k & 1, (k >> 1) & 1, (k >> 2) & 1];
        let c = [lo[0] + d[0], lo[1] + d[1], lo[2] + d[2]];
        (0..3).all(|a| c[a] <= hi[a]).then(|| bucket_of(c, bits))
    })
}

/// The bucket words zeroed (WGSL: `bucket_clear`).
pub fn bucket_clear(params: &SearchParams, grid: &mut [u32]) {
    grid[..=(1usize << params.bucket_bits)].fill(0);
}

/// Each leaf slot's facet counted in the buckets of its cells (WGSL: `bucket_count`).
pub fn bucket_count(params: &SearchParams, boxes: &[[u32; 4]], grid: &mut [u32]) {
    let leaves = 1usize << params.tree_levels;
    let s = cell_shift(params.bucket_cell, params.box_margin);
    for b in &boxes[leaves..2 * leaves] {
        if let Some((lo, hi)) = box_cells(params, *b, s) {
            for k in bins(params, lo, hi) {
                grid[k as usize] += 1;
            }
        }
    }
}

/// Each leaf slot's entries (slot, facet) written where its buckets' words say, each word
/// raised past them (WGSL: `bucket_fill`).
pub fn bucket_fill(params: &SearchParams, order: &[u32], boxes: &[[u32; 4]], grid: &mut [u32]) {
    let leaves = 1usize << params.tree_levels;
    let s = cell_shift(params.bucket_cell, params.box_margin);
    let at = params.bucket_entries as usize;
    for (j, b) in boxes[leaves..2 * leaves].iter().enumerate() {
        if let Some((lo, hi)) = box_cells(params, *b, s) {
            for k in bins(params, lo, hi) {
                let e = grid[k as usize] as usize;
                grid[k as usize] += 1;
                grid[at + 2 * e] = j as u32;
                grid[at + 2 * e + 1] = order[j];
            }
        }
    }
}

/// The entries of bucket `b`: first, end (WGSL: `bucket_range`).
fn bucket_range(grid: &[u32], b: u32) -> (u32, u32) {
    let first = if b > 0 { grid[b as usize - 1] } else { 0 };
    (first, grid[b as usize])
}

/// Where a slave's rings are measured from (WGSL: `Origin`): its box point, its cell clamped
/// into the master's cells, and those cells with their distance² from the box point.
struct Origin {
    q: glam::Vec4,
    cell: [i32; 3],
    s: u32,
    step: f32,
    lo: [i32; 3],
    hi: [i32; 3],
    d2: f32,
}

fn origin(c: &Candidates<'_>, p: V3<f32>) -> Origin {
    let params = c.params;
    let (step, inv) = boxes::box_step(params.box_margin);
    let s = cell_shift(params.bucket_cell, params.box_margin);
    let q = c.box_point(p);
    let mut cell = [q.x, q.y, q.z].map(|x| (boxes::code_lo(x, inv) >> s) as i32);
    let m = params.box_margin;
    let clo: [u32; 3] = std::array::from_fn(|a| boxes::code_lo(params.master_lo[a] - m, inv));
    let chi: [u32; 3] = std::array::from_fn(|a| boxes::code_hi(params.master_hi[a] + m, inv));
    let mut lo = clo.map(|x| (x >> s) as i32);
    let mut hi = chi.map(|x| (x >> s) as i32);
    let bounds = |k: [u32; 3]| {
        glam::Vec4::new(
            boxes::bound(k[0], step),
            boxes::bound(k[1], step),
            boxes::bound(k[2], step),
            0.0,
        )
    };
    let mut e = (bounds(clo) - q).max(q - bounds(chi)).max(glam::Vec4::ZERO);
    if params.dim == 2 {
        let z = ((BOX_BIAS as u32) >> s) as i32;
        (cell[2], lo[2], hi[2]) = (z, z, z);
        e.z = 0.0;
    }
    let e = e * e;
    let cell = std::array::from_fn(|a| cell[a].clamp(lo[a], hi[a]));
    Origin {
        q,
        cell,
        s,
        step,
        lo,
        hi,
        d2: e.x + e.y + e.z,
    }
}

/// Distance² from the origin's box point to cell `c`, or −1 outside the master's cells (WGSL:
/// `cell_d2`).
fn cell_d2(o: &Origin, c: [i32; 3], dim: u32) -> f32 {
    if (0..3).any(|a| c[a] < o.lo[a] || c[a] > o.hi[a]) {
        return -1.0;
    }
    let bound = |x: i32| boxes::bound((x as u32) << o.s, o.step);
    let lo = glam::Vec4::new(bound(c[0]), bound(c[1]), bound(c[2]), 0.0);
    let hi = glam::Vec4::new(bound(c[0] + 1), bound(c[1] + 1), bound(c[2] + 1), 0.0);
    let mut e = (lo - o.q).max(o.q - hi).max(glam::Vec4::ZERO);
    if dim == 2 {
        e.z = 0.0;
    }
    let e = e * e;
    e.x + e.y + e.z
}

/// Whether ring `r` ≥ 1 may hold a master cell within distance² `bound` (WGSL: `ring_near`).
fn ring_near(o: &Origin, r: u32, bound: f32, dim: u32) -> bool {
    let ri = r as i32;
    let mut d = 3.4e38f32;
    let axes = if dim == 2 { 2 } else { 3 };
    for a in 0..axes {
        let c = o.cell[a];
        if c - ri >= o.lo[a] {
            let lo = boxes::bound(((c - ri + 1) as u32) << o.s, o.step);
            d = d.min((o.q[a] - lo).max(0.0));
        }
        if c + ri <= o.hi[a] {
            let hi = boxes::bound(((c + ri) as u32) << o.s, o.step);
            d = d.min((hi - o.q[a]).max(0.0));
        }
    }
    d < 3.4e38 && d * d <= bound * PRUNE_SLACK
}

/// The distance² from the box point to the slab of cells `c` along axis `a` (WGSL: `slab_d2`).
fn slab_d2(o: &Origin, c: i32, a: usize) -> f32 {
    let lo = boxes::bound((c as u32) << o.s, o.step);
    let hi = boxes::bound(((c + 1) as u32) << o.s, o.step);
    let e = (lo - o.q[a]).max(o.q[a] - hi).max(0.0);
    e * e
}

/// What one step of a ring walk does (WGSL: `ring_step`'s 0, 1, 2).
#[derive(PartialEq)]
enum Step {
    /// A layer or row skipped.
    Skipped,
    /// The current cell, to visit.
    Visit,
    /// The rings are done.
    Done,
}

/// One step of a ring walk within distance² `bound`: a layer or row holding no master cell
/// within it skipped, else the current cell handed back (WGSL: `ring_step`).
fn ring_step(o: &Origin, g: &mut Ring, bound: f32, dim: u32) -> Step {
    let c: [i32; 3] = std::array::from_fn(|a| o.cell[a] + g.d[a]);
    let limit = bound * PRUNE_SLACK;
    let outside = |a: usize| c[a] < o.lo[a] || c[a] > o.hi[a];
    let skipped = |new_ring: bool, g: &Ring| {
        if new_ring && !ring_near(o, g.r as u32, bound, dim) {
            Step::Done
        } else {
            Step::Skipped
        }
    };
    if dim != 2 && g.layer_start() && (outside(2) || slab_d2(o, c[2], 2) > limit) {
        let new_ring = g.next_layer(dim);
        return skipped(new_ring, g);
    }
    if g.row_start() {
        let mut far = outside(1);
        let mut yz = slab_d2(o, c[1], 1);
        if dim != 2 {
            far = far || outside(2);
            yz += slab_d2(o, c[2], 2);
        }
        if far || yz > limit {
            let new_ring = g.next_row(dim);
            return skipped(new_ring, g);
        }
    }
    Step::Visit
}

/// What a bucket walk found (WGSL: `BucketWalk`).
struct BucketWalk {
    d2: f32,
    f: u32,
    projections: u32,
    cut: bool,
}

/// Facet `f` projected for the walk `w` of the slave at `p` unless excluded (WGSL:
/// `walk_project`).
fn walk_project(c: &Candidates<'_>, w: &mut BucketWalk, f: u32, p: V3<f32>, slave: u32) {
    if c.excluded(slave, f) {
        return;
    }
    let d2 = project(c.nodes, p, c.facets[f as usize]).dist2;
    w.projections += 1;
    if d2 < w.d2 || (d2 == w.d2 && f < w.f) {
        w.d2 = d2;
        w.f = f;
    }
}

/// The entries of bucket `b` for the walk `w` of the slave at `p`, in two rounds that do not
/// depend on their order: the nearest box first, then the others within the best distance
/// (WGSL: `walk_bucket`).
fn walk_bucket(
    c: &Candidates<'_>,
    grid: &[u32],
    w: &mut BucketWalk,
    b: u32,
    (p, q, slave): (V3<f32>, glam::Vec4, u32),
    visits: &mut u32,
) {
    let (first, end) = bucket_range(grid, b);
    if *visits + 2 * (end - first) > BUCKET_VISITS {
        w.cut = true;
        return;
    }
    *visits += 2 * (end - first);
    let before = w.f;
    let leaves = c.leaves() as usize;
    let at = c.params.bucket_entries as usize;
    let entries = || {
        (first as usize..end as usize).filter_map(|e| {
            let (j, f) = (grid[at + 2 * e] as usize, grid[at + 2 * e + 1]);
            let [lo, hi] = c.corners[leaves + j].map(glam::Vec4::from_array);
            (f != before).then(|| (f, box_d2_of(lo, hi, q)))
        })
    };
    let (mut near, mut near_d2) = (NO_FACET, w.d2 * PRUNE_SLACK);
    for (f, d2) in entries() {
        if d2 < near_d2 || (d2 == near_d2 && f < near) {
            (near, near_d2) = (f, d2);
        }
    }
    if near == NO_FACET {
        return;
    }
    walk_project(c, w, near, p, slave);
    let bound = w.d2 * PRUNE_SLACK;
    for (f, d2) in entries() {
        if f != near && d2 <= bound {
            walk_project(c, w, f, p, slave);
        }
    }
}

/// The nearest facet within the tracking radius of the slave at walk position `t` (WGSL:
/// `bucket_walk_of`).
fn bucket_walk_of(c: &Candidates<'_>, grid: &[u32], t: usize) -> BucketWalk {
    let (p, slave) = walk_point(c, t);
    let o = origin(c, p);
    let dim = c.params.dim;
    let mut w = BucketWalk {
        d2: track_radius2(c.params),
        f: NO_FACET,
        projections: 0,
        cut: false,
    };
    if o.d2 > w.d2 * PRUNE_SLACK {
        return w; // the master is farther than the radius
    }
    let at = (p, o.q, slave);
    let mut visits = 1;
    walk_bucket(c, grid, &mut w, 1 << c.params.bucket_bits, at, &mut visits);
    let mut g = Ring::new();
    let mut more = true;
    while more && visits < BUCKET_VISITS && !w.cut {
        match ring_step(&o, &mut g, w.d2, dim) {
            Step::Done => more = false,
            Step::Skipped => {}
            Step::Visit => {
                let cell: [i32; 3] = std::array::from_fn(|a| o.cell[a] + g.d[a]);
                let d2 = cell_d2(&o, cell, dim);
                if d2 >= 0.0 && d2 <= w.d2 * PRUNE_SLACK {
                    let b = bucket_of(cell.map(|x| x as u32), c.params.bucket_bits);
                    walk_bucket(c, grid, &mut w, b, at, &mut visits);
                }
                if g.next_cell(dim) && !ring_near(&o, g.r as u32, w.d2, dim) {
                    more = false;
                }
            }
        }
        visits += 1;
    }
    if more && visits >= BUCKET_VISITS {
        w.cut = true;
    }
    w
}

/// One "invocation" per walk position t: its bucket walk's best facet into `best`, the chunks
/// of every leaf slot if the cap cut it off into `work` (word n_slaves set to 0 for the scan)
/// (WGSL: `bucket_walk`).
pub fn bucket_walk(c: &Candidates<'_>, grid: &[u32], work: &mut [u32], best: &mut [u32]) {
    let n = c.params.n_slaves as usize;
    if n > 0 {
        work[n] = 0;
    }
    let leaves = c.leaves();
    best[..BEST_WORDS * n]
        .par_chunks_mut(BEST_WORDS)
        .zip(&mut work[..n])
        .enumerate()
        .with_min_len(PAR_MIN)
        .for_each(|(t, (b, chunks))| {
            let w = bucket_walk_of(c, grid, t);
            let start = if w.cut { 0 } else { leaves };
            let rest = leaves - start;
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

/// Whether an entry of bucket `b` is a facet within the radius, other than `best_f` and
/// sharing no node with it, that faces the slave at `p` (WGSL: `crowded_in`).
fn crowded_in(
    c: &Candidates<'_>,
    grid: &[u32],
    b: u32,
    (p, q, slave): (V3<f32>, glam::Vec4, u32),
    best_f: u32,
) -> bool {
    let (first, end) = bucket_range(grid, b);
    let r2 = c.params.radius * c.params.radius;
    let leaves = c.leaves() as usize;
    let at = c.params.bucket_entries as usize;
    for e in first as usize..end as usize {
        let (j, f) = (grid[at + 2 * e] as usize, grid[at + 2 * e + 1]);
        let [lo, hi] = c.corners[leaves + j].map(glam::Vec4::from_array);
        if f == best_f || box_d2_of(lo, hi, q) > r2 * PRUNE_SLACK {
            continue;
        }
        let fac = c.facets[f as usize];
        if c.excluded(slave, f) || share_node(fac, c.facets[best_f as usize]) {
            continue;
        }
        let pr = project(c.nodes, p, fac);
        let gap = (p - pr.point).dot(pr.normal);
        if pr.dist2 <= r2 && 4.0 * gap * gap > pr.dist2 {
            return true;
        }
    }
    false
}

/// Self-contact: whether the slave at walk position `i` has another facet within the radius
/// that faces it; a check cut off by the cap says yes (WGSL: `bucket_crowded_of`).
fn bucket_crowded_of(c: &Candidates<'_>, grid: &[u32], i: usize, best_f: u32) -> bool {
    let (p, slave) = walk_point(c, i);
    let o = origin(c, p);
    let dim = c.params.dim;
    let r2 = c.params.radius * c.params.radius;
    if o.d2 > r2 * PRUNE_SLACK {
        return false;
    }
    let at = (p, o.q, slave);
    let mut visits = 1;
    let (first, end) = bucket_range(grid, 1 << c.params.bucket_bits);
    if visits + (end - first) > BUCKET_VISITS {
        return true;
    }
    visits += end - first;
    if crowded_in(c, grid, 1 << c.params.bucket_bits, at, best_f) {
        return true;
    }
    let mut g = Ring::new();
    while visits < BUCKET_VISITS {
        match ring_step(&o, &mut g, r2, dim) {
            Step::Done => return false,
            Step::Skipped => {}
            Step::Visit => {
                let cell: [i32; 3] = std::array::from_fn(|a| o.cell[a] + g.d[a]);
                let d2 = cell_d2(&o, cell, dim);
                if d2 >= 0.0 && d2 <= r2 * PRUNE_SLACK {
                    let b = bucket_of(cell.map(|x| x as u32), c.params.bucket_bits);
                    let (first, end) = bucket_range(grid, b);
                    if visits + (end - first) > BUCKET_VISITS {
                        return true;
                    }
                    visits += end - first;
                    if crowded_in(c, grid, b, at, best_f) {
                        return true;
                    }
                }
                if g.next_cell(dim) && !ring_near(&o, g.r as u32, r2, dim) {
                    return false;
                }
            }
        }
        visits += 1;
    }
    true
}

/// One "invocation" per slave, self-contact only: the crowding flag into the record (WGSL:
/// `bucket_crowded`).
pub fn bucket_crowded(c: &Candidates<'_>, grid: &[u32], best: &mut [u32]) {
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
            if f != NO_FACET && bucket_crowded_of(c, grid, i, f) {
                b[2] = 1;
            }
        });
}
